"""How high can the arm throw at real gravity within the UR5e's speed limit? A CMA-ES search.

Nothing juggles at ``env=earth`` (g = -9.81 m/s², setpoints rate-limited to π rad/s): the
expert's elbow flick would need about twice the limit. This script searches one throw from
rest: a start pose (shoulder lift, elbow; wrist_1 set so the cup is upright there, plus a tilt),
then three setpoint knots (duration, lift, elbow) that the env's rate limit turns into ramps. The
score is the ball's apex after it leaves the cup, less 10 per metre the cup's throat rises above
``--max-cup`` (0.76 m: a counted throw rises at least 0.24 m above the cup) and, with
``--landing-weight W``, W per metre the ball comes down from the start cup. It prints the best
throw, its apex, the cup's highest point, the peak joint speeds and how far from the start the
ball comes down (where a catch would have to be).

    python scripts/studies/earth_throw.py [--restarts 12] [--generations 60] [--seed 1] \
        [--landing-weight 0]
"""

from __future__ import annotations

import argparse

import numpy as np

from jugglerl.studies.earth_throw import decode, search


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--restarts", type=int, default=12)
    parser.add_argument("--generations", type=int, default=60)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--max-cup", type=float, default=0.76, help="m, the cup's highest allowed")
    parser.add_argument(
        "--landing-weight",
        type=float,
        default=0.0,
        help="score lost per metre the ball lands from the start cup",
    )
    args = parser.parse_args()
    if args.restarts < 1 or args.generations < 1:
        parser.error("--restarts and --generations must be >= 1")
    if args.landing_weight < 0:
        parser.error("--landing-weight must be >= 0")
    x, throw = search(args.restarts, args.generations, args.seed, args.max_cup, args.landing_weight)
    start, tilt, knots = decode(x)
    print(f"start pose (lift, elbow) {np.round(start, 3).tolist()} rad, cup tilt {tilt:+.3f} rad")
    for duration, lift, elbow in knots:
        print(f"  then for {duration:.3f} s towards lift {lift:.3f}, elbow {elbow:.3f} rad")
    speeds = ", ".join(f"{v:.2f}" for v in throw.peak_speed)
    print(
        f"apex {throw.apex:.3f} m ({throw.throws} counted), cup at most {throw.max_cup:.3f} m,"
        f" peak joint speeds {speeds} rad/s, lands {throw.landing_offset:.3f} m from the start"
    )


if __name__ == "__main__":
    main()
