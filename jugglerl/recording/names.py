"""Entity paths and timelines of a JuggleRL recording, in one place so loggers and layouts agree."""

from __future__ import annotations

WORLD = "world"  # the 3D scene; the ball at world/ball
PLOTS = "plots"  # per-episode time series: plots/ball_height, plots/threshold, plots/throws
TRAIN = "train"  # training metrics
EVAL = "eval"  # evaluation metrics
DPS = "dps"  # direct policy search: throws per episode, current via-points
HPARAMS = "hparams"  # the run's resolved config, a markdown text document
SUMMARY = "summary"  # an evaluated episode's metrics, a markdown table

STEP = "step"  # training progress: env frames (DDPG) or roll-outs (DPS)
SIM_TIME = "sim_time"  # seconds of simulated time since an episode's reset


def join(*parts: str) -> str:
    """Entity path from parts, skipping empty ones: ``join("", "world") == "world"``."""
    return "/".join(part.strip("/") for part in parts if part and part.strip("/"))
