"""How short a hold an open-loop command tolerates: throws as one via-point's hold is cut.

    python scripts/studies/hold_sweep.py [--command dps_best] [--hold 0] \
        [--cuts 0,0.05,0.1,0.15,0.16,0.2] [--lead-in S] [--seeds 10] [--reset-noise 0.01] \
        [--duration 120]

For each cut, via-point ``--hold`` is held that many seconds less and everything after it moves
earlier (``ViaPointCommand.shorten_hold``): the cycle shrinks, the throw and the flight keep their
shape. In ``dps_best`` via-point 0 is the catch pose, so the cut is taken from the time the ball
has to settle in the cup between catch and throw. Each row: the cycle, the throws from the
standard start (and when the ball dropped), and the mean throws over ``--seeds`` starts with the
ball offset up to ``--reset-noise`` metres (kept: as a fraction of the standard start's, when
that kept the ball for the whole episode). ``--lead-in`` replaces the command's lead-in, e.g. to
tell a limit of the cycle itself from one of the start.
Paper preset, open-loop roll-outs in C (``CommandRollouts``).
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace

from jugglerl.commands import load_command
from jugglerl.dps.rollouts import CommandRollouts
from jugglerl_envs import JuggleEnv


def cuts(text: str) -> list[float]:
    try:
        return [float(value) for value in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r}: expected numbers separated by commas"
        ) from None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--command", default="dps_best", help="a shipped name or a command file")
    parser.add_argument("--hold", type=int, default=0, help="index of the via-point to cut")
    parser.add_argument("--cuts", type=cuts, default=[0.0, 0.05, 0.1, 0.15, 0.16, 0.2])
    parser.add_argument("--lead-in", type=float, default=None, help="s; default: the command's")
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--reset-noise", type=float, default=0.01)
    parser.add_argument("--duration", type=float, default=120.0)
    args = parser.parse_args()
    if args.seeds < 1:
        parser.error("--seeds must be at least 1")
    try:
        command = load_command(args.command)
        if args.lead_in is not None:
            command = replace(command, lead_in=args.lead_in)
        variants = [command.shorten_hold(args.hold, cut) for cut in args.cuts]
        standard_env = JuggleEnv(duration=args.duration)
        noisy_env = JuggleEnv(duration=args.duration, reset_noise=args.reset_noise)
    except ValueError as error:  # a CommandError, or an env setting out of range
        sys.exit(f"hold_sweep.py: {error}")

    noisy_seeds = list(range(args.seeds))
    with CommandRollouts(standard_env) as standard, CommandRollouts(noisy_env) as noisy:
        nominal = standard.evaluate(variants, seeds=0)
        starts = noisy.evaluate(
            [variant for variant in variants for _ in noisy_seeds], noisy_seeds * len(variants)
        ).throws.reshape(len(variants), args.seeds)

    print(
        f"{command.name}: via-point {args.hold}'s hold cut; lead-in {command.lead_in:g} s;"
        f" {args.duration:g} s episodes"
    )
    print(f"{'cut s':>6} {'cycle s':>8} {'throws':>6} {'drop s':>7} {'noisy mean':>10} {'kept':>5}")
    for cut, variant, throws, drop, noisy_throws in zip(
        args.cuts, variants, nominal.throws, nominal.time_to_drop, starts, strict=True
    ):
        mean = noisy_throws.mean()
        dropped = not math.isnan(drop)
        kept = "-" if dropped or not throws else f"{mean / throws:.0%}"
        drop_text = f"{drop:.1f}" if dropped else "-"
        print(f"{cut:6.3f} {variant.cycle:8.3f} {throws:6d} {drop_text:>7} {mean:10.1f} {kept:>5}")


if __name__ == "__main__":
    main()
