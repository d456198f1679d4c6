"""Where parallel work runs (``jugglerl.cluster``): the same results locally and on a real Ray
cluster of two nodes started on this machine, and one clear line for a cluster that is not
there. The Ray tests skip when Ray is not installed (``pip install -e ".[ray]"``)."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from cli import run_script

from jugglerl.cluster import open_cluster
from jugglerl.cluster.ray_tasks import INSTALL_HINT, import_ray

RAY = Path(sys.executable).parent / "ray"
#: the test cluster runs without Ray's token authentication: its nodes and drivers are children
#: of this process on one machine
NO_AUTH = {"RAY_AUTH_MODE": "disabled"}
DPS = [
    "algo=dps",
    "algo.episodes=2",
    "algo.rollouts=4",
    "env.duration=10",
    "seed=3",
    "algo.noise_check.seeds=2",
    "record_best=false",
    "progress=false",
]
FEEDBACK = [
    "algo=feedback",
    "algo.episodes=1",
    "algo.rollouts=2",
    "env.duration=5",
    "seed=1",
    "algo.noise_check.seeds=0",
    "record_best=false",
    "progress=false",
]
ROBUSTNESS = [
    "policies=[expert,closed_loop]",
    "reference=expert",
    "seeds=2",
    "duration=8",
    "select=[kicks]",
    "families.kicks.magnitudes=[0.1]",
    "progress=false",
]


def _halve(items: list) -> list:
    return [item // 2 for item in items]


@pytest.mark.slow
def test_local_cluster_maps_chunks_in_order():
    cluster = open_cluster(None, workers=2)
    try:
        assert list(cluster.map(_halve, list(range(7)))) == [0, 0, 1, 1, 2, 2, 3]
    finally:
        cluster.close()


def test_a_missing_ray_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # what `import ray` meets without Ray
    with pytest.raises(ValueError, match="pip install"):
        import_ray()
    assert "[ray]" in INSTALL_HINT


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _ray_start(*args: str, log: Path) -> subprocess.Popen:
    return subprocess.Popen(
        [
            str(RAY),
            "start",
            "--block",
            "--num-cpus=1",
            "--disable-usage-stats",
            "--object-store-memory=80000000",
            *args,
        ],
        stdout=subprocess.DEVNULL,
        stderr=log.open("w"),
        env={**os.environ, **NO_AUTH},
    )


@pytest.fixture(scope="module")
def ray_cluster(tmp_path_factory):
    """The address of a head and a second node, each a `ray start --block` child of this
    process with one CPU, ended by its own process id (`ray stop` would end every Ray process
    on the machine)."""
    pytest.importorskip("ray", reason="Ray is not installed (pip install -e '.[ray]')")
    logs = tmp_path_factory.mktemp("ray")
    port = _free_port()
    address = f"127.0.0.1:{port}"
    nodes = [
        _ray_start("--head", f"--port={port}", "--include-dashboard=false", log=logs / "head.log")
    ]
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                if time.monotonic() > deadline or nodes[0].poll() is not None:
                    pytest.fail(f"the Ray head did not start: {(logs / 'head.log').read_text()}")
                time.sleep(0.2)
        nodes.append(_ray_start(f"--address={address}", log=logs / "node.log"))
        waiting = (
            "import ray, time\n"
            f"ray.init(address='{address}', logging_level='WARNING')\n"
            "while sum(node['Alive'] for node in ray.nodes()) < 2: time.sleep(0.2)\n"
        )
        subprocess.run(
            [sys.executable, "-c", waiting],
            env={**os.environ, **NO_AUTH},
            check=True,
            timeout=120,
            capture_output=True,
        )
        yield address
    finally:
        for node in reversed(nodes):  # the second node first, while its head can see it go
            node.terminate()
            try:
                node.wait(60)
            except subprocess.TimeoutExpired:
                node.kill()
                node.wait()


def _run(script: str, run_dir: Path, *overrides: str) -> subprocess.CompletedProcess:
    result = run_script(script, *overrides, f"hydra.run.dir={run_dir}", env=NO_AUTH)
    assert result.returncode == 0, result.stderr[-3000:]
    on_ray = any(override.startswith("cluster.address=") for override in overrides)
    assert ("cluster: Ray at" in result.stdout and "2 node(s), 2 CPUs" in result.stdout) == on_ray
    return result


@pytest.mark.slow
def test_dps_on_ray_finds_the_same_command_as_locally(ray_cluster, tmp_path):
    _run("train.py", tmp_path / "local", *DPS)
    _run("train.py", tmp_path / "ray", *DPS, "cluster=ray", f"cluster.address={ray_cluster}")
    local, remote = (
        json.loads((tmp_path / run / "metrics.json").read_text()) for run in ("local", "ray")
    )
    assert remote["history"] == local["history"]
    assert (tmp_path / "ray/best_command.yaml").read_text() == (
        tmp_path / "local/best_command.yaml"
    ).read_text()


@pytest.mark.slow
def test_feedback_search_on_ray_finds_the_same_gains_as_locally(ray_cluster, tmp_path):
    _run("train.py", tmp_path / "local", *FEEDBACK)
    _run(
        "train.py",
        tmp_path / "ray",
        *FEEDBACK,
        "cluster=ray",
        "cluster.chunk=2",
        f"cluster.address={ray_cluster}",
    )
    local, remote = (
        yaml.safe_load((tmp_path / d / "best_policy.yaml").read_text()) for d in ("local", "ray")
    )
    assert remote["feedback"] == local["feedback"]


@pytest.mark.slow
def test_robustness_on_ray_measures_the_same_episodes_as_locally(ray_cluster, tmp_path):
    _run("robustness.py", tmp_path / "local", *ROBUSTNESS)
    _run(
        "robustness.py",
        tmp_path / "ray",
        *ROBUSTNESS,
        "cluster=ray",
        f"cluster.address={ray_cluster}",
    )
    local, remote = (
        json.loads((tmp_path / d / "robustness.json").read_text())["rows"] for d in ("local", "ray")
    )
    assert remote == local
    assert {row["family"] for row in local} == {"nominal", "kicks"}


@pytest.mark.slow
def test_a_sweep_on_ray_runs_each_job_into_its_own_run_directory(ray_cluster, tmp_path):
    result = run_script(
        "train.py",
        "-m",
        *DPS[:-2],
        "algo.noise_check.seeds=0",
        "seed=0,1",
        "cluster=ray",
        f"cluster.address={ray_cluster}",
        f"hydra.sweep.dir={tmp_path}",
        env=NO_AUTH,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    assert "2 node(s), 2 CPUs" in result.stdout
    runs = sorted(path.parent.name for path in tmp_path.glob("*/best_command.yaml"))
    assert [run.split("_")[0] for run in runs] == ["0", "1"]
    assert all((tmp_path / run / "train.rrd").stat().st_size > 0 for run in runs)


@pytest.mark.slow
@pytest.mark.parametrize("script", ["train.py", "robustness.py"])
def test_an_unreachable_cluster_is_one_error_line_naming_its_address(script, tmp_path):
    pytest.importorskip("ray", reason="Ray is not installed (pip install -e '.[ray]')")
    address = f"127.0.0.1:{_free_port()}"  # nothing listens there
    overrides = DPS if script == "train.py" else ROBUSTNESS
    result = run_script(
        script,
        *overrides,
        "cluster=ray",
        f"cluster.address={address}",
        f"hydra.run.dir={tmp_path}",
        timeout=60,
    )
    assert result.returncode == 1
    assert result.stderr.strip().splitlines()[-1].startswith(f"error: cluster.address={address}:")
    assert "Traceback" not in result.stderr
