"""Two policies compared start by start: what 30 noisy starts can and cannot tell apart.

Under imprecision an episode mostly either juggles to the end or drops the ball early, so a
mean over starts moves by 6-8 points with one drop. Measured on the same starts (the same env
seeds and conditions of ``scripts/robustness.py``), the throws of two policies pair up; the mean
of the differences and its standard error say whether a gap is larger than the starts' own
spread, and the drops (episodes that ended before the duration) say where it comes from.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class Pair:
    """One condition: ``family`` at ``magnitude`` (``None`` nominal), per start ``a`` and ``b``
    throws and whether each ``a_dropped`` / ``b_dropped`` the ball."""

    family: str
    magnitude: float | None
    a: np.ndarray
    b: np.ndarray
    a_dropped: np.ndarray
    b_dropped: np.ndarray

    @property
    def difference(self) -> tuple[float, float]:
        """Mean of ``a - b`` over the starts, and its standard error (0 with one start)."""
        d = (self.a - self.b).astype(float)
        error = d.std(ddof=1) / np.sqrt(len(d)) if len(d) > 1 else 0.0
        return float(d.mean()), float(error)


def read_benchmark(path: Path) -> dict:
    """A ``robustness.json`` (or the run folder holding one); ``ValueError`` if it is not one."""
    path = Path(path)
    if path.is_dir():
        path = path / "robustness.json"
    try:
        benchmark = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as error:
        raise ValueError(f"{path}: not a robustness benchmark ({error})") from None
    if not {"config", "episodes"} <= benchmark.keys():
        raise ValueError(f"{path}: not a robustness benchmark (no config and episodes)")
    return benchmark


def _starts(benchmark: dict) -> tuple:
    config = benchmark["config"]
    return config["env"], config["seeds"], config["duration"]


def _episodes(benchmark: dict, policy: str, source: str) -> dict:
    found = {
        (record["family"], record["magnitude"]): record
        for record in benchmark["episodes"]
        if record["policy"] == policy
    }
    if not found:
        policies = sorted({record["policy"] for record in benchmark["episodes"]})
        raise ValueError(f"{source} has no episodes of {policy} (it has {', '.join(policies)})")
    return found


def pair(a: dict, policy_a: str, b: dict, policy_b: str) -> list[Pair]:
    """``policy_a``'s episodes in benchmark ``a`` against ``policy_b``'s in ``b``, per condition
    both measured; ``ValueError`` if the two were not run from the same starts."""
    if _starts(a) != _starts(b):
        raise ValueError("the two benchmarks differ in env, seeds or duration: not the same starts")
    duration = a["config"]["duration"]
    ours, theirs = _episodes(a, policy_a, "the first"), _episodes(b, policy_b, "the second")
    pairs = []
    for key in (key for key in ours if key in theirs):
        x, y = ours[key], theirs[key]
        pairs.append(
            Pair(
                family=key[0],
                magnitude=key[1],
                a=np.asarray(x["throws"]),
                b=np.asarray(y["throws"]),
                a_dropped=np.asarray(x["seconds_up"]) < duration,
                b_dropped=np.asarray(y["seconds_up"]) < duration,
            )
        )
    if not pairs:
        raise ValueError("the two benchmarks share no condition")
    return pairs


def markdown(pairs: list[Pair], name_a: str, name_b: str) -> str:
    """The comparison as a Markdown table, one row per condition."""
    lines = [
        f"| condition | {name_a} | {name_b} | difference (± s.e.) | better / worse / equal starts"
        " | drops |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for p in pairs:
        condition = p.family if p.magnitude is None else f"{p.family} {p.magnitude:g}"
        mean, error = p.difference
        d = p.a - p.b
        lines.append(
            f"| {condition} | {p.a.mean():.1f} | {p.b.mean():.1f} | {mean:+.1f} ± {error:.1f}"
            f" | {(d > 0).sum()} / {(d < 0).sum()} / {(d == 0).sum()}"
            f" | {p.a_dropped.sum()} / {p.b_dropped.sum()} of {len(d)} |"
        )
    return "\n".join(lines)
