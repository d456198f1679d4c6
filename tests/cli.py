"""Helpers that run the training script the way a user does, shared by the training tests."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

from hydra import compose, initialize_config_dir

ROOT = Path(__file__).resolve().parents[1]


def train_config(*overrides: str):
    """``configs/train.yaml`` composed with ``overrides``, as Hydra would for train.py."""
    with initialize_config_dir(str(ROOT / "configs"), version_base="1.3"):
        return compose("train", overrides=list(overrides))


def run_train(*overrides: str, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python scripts/train.py *overrides`` to completion."""
    return run_script("train.py", *overrides, timeout=timeout)


def run_script(name: str, *overrides: str, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python scripts/<name> *overrides`` to completion."""
    return subprocess.run(
        [sys.executable, str(ROOT / "scripts" / name), *overrides],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=timeout,
    )


def interrupt_train(run_dir: Path, *overrides: str) -> tuple[int, str]:
    """Start train.py in ``run_dir``, Ctrl-C it once its first checkpoint exists.

    Returns the exit code and stderr.
    """
    process = subprocess.Popen(
        [
            sys.executable,
            str(ROOT / "scripts" / "train.py"),
            *overrides,
            f"hydra.run.dir={run_dir}",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )
    deadline = time.monotonic() + 120
    while not (run_dir / "checkpoint.pt").exists() and time.monotonic() < deadline:
        time.sleep(0.2)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    return process.returncode, stderr


def rrd_verifies(path: Path) -> bool:
    """``rerun rrd verify`` accepts the recording (its footer was written)."""
    rerun = Path(sys.executable).parent / "rerun"
    return (
        subprocess.run([str(rerun), "rrd", "verify", str(path)], capture_output=True).returncode
        == 0
    )
