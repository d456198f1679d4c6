"""Helpers that run the scripts the way a user does, shared by the script tests.

``run_script`` runs ``scripts/<name>`` as ``python scripts/<name> ARGS`` would, in a fresh process
forked from a server that has already imported torch, TorchRL, Hydra and the package: a test
pays a fork (tens of ms) instead of those imports (about 4 s a script). The server has run no
torch op, so its children start with fresh thread pools; each child gets its own ``sys.argv``,
working directory, stdout and stderr files, and exits as the interpreter would (a ``sys.exit``
message on stderr with code 1, an uncaught exception's traceback with code 1). It ends with
``os._exit``, so ``atexit`` handlers do not run: the scripts close their files themselves.
"""

from __future__ import annotations

import multiprocessing
import os
import resource
import runpy
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

from hydra import compose, initialize_config_dir

ROOT = Path(__file__).resolve().parents[1]
#: What every script imports first; preloaded once in the fork server.
PRELOAD = [
    "torch",
    "torchrl",
    "hydra",
    "mujoco",
    "rerun",
    "jugglerl.training",
    "jugglerl.offpolicy.training",
]
_SERVER = multiprocessing.get_context("forkserver")
_SERVER.set_forkserver_preload(PRELOAD)


def train_config(*overrides: str):
    """``configs/train.yaml`` composed with ``overrides``, as Hydra would for train.py."""
    with initialize_config_dir(str(ROOT / "configs"), version_base="1.3"):
        return compose("train", overrides=list(overrides))


def env_preset(name: str, **overrides):
    """The env of preset ``configs/env/<name>.yaml`` with keyword ``overrides``."""
    from jugglerl.config.envs import make_juggle_env

    return make_juggle_env(train_config(f"env={name}").env, **overrides)


def run_train(*overrides: str, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python scripts/train.py *overrides`` to completion."""
    return run_script("train.py", *overrides, timeout=timeout)


def run_short_search(algo: str, run_dir: Path, *overrides: str) -> subprocess.CompletedProcess:
    """``train.py algo=ALGO`` cut to one episode of two closed-loop samples in one worker, under a
    nominal and a noisy condition, with a one-seed noise check and no recording."""
    return run_train(
        f"algo={algo}",
        "algo.episodes=1",
        "algo.rollouts=2",
        "algo.workers=1",
        "algo.noise_check.seeds=1",
        "algo.conditions=[{},{action_noise:0.003}]",
        "progress=false",
        "record_best=false",
        f"hydra.run.dir={run_dir}",
        *overrides,
    )


def run_script(
    name: str,
    *overrides: str,
    timeout: float = 300,
    env: dict[str, str] | None = None,
    file_size_limit: int | None = None,
) -> subprocess.CompletedProcess:
    """``python scripts/<name> *overrides`` to completion, run from the repository root, with
    ``env`` added to its environment; with ``file_size_limit`` no file it writes may grow past
    that many bytes (a write beyond fails as on a full disk)."""
    script = str(ROOT / "scripts" / name)
    with tempfile.TemporaryDirectory() as folder:
        out, err = Path(folder, "stdout"), Path(folder, "stderr")
        arguments = (script, overrides, out, err, env, file_size_limit)
        child = _SERVER.Process(target=_run_as_main, args=arguments)
        child.start()
        child.join(timeout)
        if child.exitcode is None:
            child.kill()
            child.join()
            raise subprocess.TimeoutExpired([name, *overrides], timeout)
        return subprocess.CompletedProcess(
            [name, *overrides], child.exitcode, out.read_text(), err.read_text()
        )


def _run_as_main(
    script: str,
    overrides: tuple[str, ...],
    out: Path,
    err: Path,
    env: dict[str, str] | None,
    file_size_limit: int | None,
) -> None:
    """In the forked child: run ``script`` as ``__main__`` and exit with the interpreter's code."""
    os.chdir(ROOT)
    os.environ.update(env or {})
    for stream, path in ((1, out), (2, err)):
        os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC), stream)
    if file_size_limit is not None:  # Python ignores SIGXFSZ: a write past it raises EFBIG
        resource.setrlimit(resource.RLIMIT_FSIZE, (file_size_limit, file_size_limit))
    sys.argv = [script, *overrides]
    code = 0
    try:
        runpy.run_path(script, run_name="__main__")
    except SystemExit as exit_:
        if isinstance(exit_.code, str):
            print(exit_.code, file=sys.stderr)
            code = 1
        else:
            code = exit_.code or 0
    except BaseException:
        traceback.print_exc()
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def interrupt_train(run_dir: Path, *overrides: str, presses: int = 1) -> tuple[int, str]:
    """Start train.py in ``run_dir``, Ctrl-C it once its first checkpoint exists (``presses``
    times, 20 ms apart, as an impatient user does).

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
    for press in range(presses):
        time.sleep(0.02 * bool(press))
        process.send_signal(signal.SIGINT)
    try:
        _, stderr = process.communicate(timeout=60)
    except subprocess.TimeoutExpired:  # a run that ignored the Ctrl-C must not outlive the test
        process.kill()
        process.communicate()
        raise
    return process.returncode, stderr


def rrd_verifies(path: Path) -> bool:
    """``rerun rrd verify`` accepts the recording (its footer was written)."""
    rerun = Path(sys.executable).parent / "rerun"
    return (
        subprocess.run([str(rerun), "rrd", "verify", str(path)], capture_output=True).returncode
        == 0
    )
