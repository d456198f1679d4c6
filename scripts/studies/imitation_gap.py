"""How far a student strays from its teacher on the student's own episode, and where it drops.

    python scripts/studies/imitation_gap.py STUDENT [--teacher closed_loop] [--seed 0] \
        [--duration 120]

STUDENT and ``--teacher`` are ``policy=`` specs (a shipped name, a policy file, a training run).
The student acts; the teacher, stepped on the same observations, labels every step, as in
DAgger. Prints the RMS and 99th-percentile gap per actuator (normalised action units), then
each flight above ``FLIGHT_HEIGHT`` m over the cup: its apex (m, world) and how far from the
cup's axis the ball came back down through that height (m). A juggling cycle the student cannot
hold shows up as growing gaps, wild apexes and a last landing off the cup.
"""

from __future__ import annotations

import argparse

import numpy as np

from jugglerl.policies.loading import load_policy
from jugglerl_envs import JuggleEnv

#: m of the ball above the cup's throat that count as a flight (hops inside the cup stay below)
FLIGHT_HEIGHT = 0.2


def measure(student_spec: str, teacher_spec: str, seed: int, duration: float) -> dict:
    """The gaps (``[step, actuator]``), the flights' apexes and landing offsets, the episode."""
    env = JuggleEnv(duration=duration)
    student, teacher = load_policy(student_spec, env), load_policy(teacher_spec, env)
    observation, info = env.reset(seed=seed)
    student.reset()
    teacher.reset()
    gaps, apexes, landings = [], [], []
    apex = None  # the highest ball of the running flight
    done = False
    while not done:
        action = student.act(observation, info["time"])
        gaps.append(action - teacher.act(observation, info["time"]))
        ball, cup = observation[6:9], observation[12:15]
        if ball[2] - cup[2] > FLIGHT_HEIGHT:
            apex = max(apex or ball[2], ball[2])
        elif apex is not None:
            apexes.append(float(apex))
            landings.append(float(np.linalg.norm(ball[:2] - cup[:2])))
            apex = None
        observation, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated
    env.close()
    return {
        "gaps": np.array(gaps),
        "apexes": apexes,
        "landings": landings,
        "throws": int(info["throws"]),
        "seconds": float(info["time"]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("student")
    parser.add_argument("--teacher", default="closed_loop")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--duration", type=float, default=120.0)
    args = parser.parse_args()
    try:
        result = measure(args.student, args.teacher, args.seed, args.duration)
    except ValueError as error:
        raise SystemExit(f"error: {error}") from None
    gaps = result["gaps"]
    print(f"{args.student}: {result['throws']} throws, ball up {result['seconds']:.1f} s")
    print(
        f"gap to {args.teacher} (pan, lift, elbow): RMS",
        np.array2string(np.sqrt((gaps**2).mean(0)), precision=4),
        "p99",
        np.array2string(np.percentile(np.abs(gaps), 99, axis=0), precision=4),
    )
    print("flight apexes (m):", " ".join(f"{a:.3f}" for a in result["apexes"]))
    print("landing offsets (m):", " ".join(f"{d:.3f}" for d in result["landings"]))


if __name__ == "__main__":
    main()
