"""scripts/evaluate.py end to end, as a user runs it."""

import json
import subprocess

import pytest
import yaml
from cli import run_script

from jugglerl.recording.reading import column
from jugglerl_envs.rewards import REWARDS


def run_evaluate(*overrides: str) -> subprocess.CompletedProcess:
    return run_script("evaluate.py", *overrides)


@pytest.mark.slow
def test_evaluate_writes_metrics_json_in_the_run_dir(tmp_path):
    result = run_evaluate("policy=expert", "duration=10", "seed=2", f"hydra.run.dir={tmp_path}")
    assert result.returncode == 0, result.stderr
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert set(metrics) >= {
        "throws",
        "catches",
        "max_consecutive_catches",
        "time_to_drop",
        "duration",
        "seed",
    }
    assert metrics["duration"] == 10.0 and metrics["seed"] == 2 and metrics["time_to_drop"] is None
    assert metrics["throws"] >= 2
    assert f"{metrics['throws']} throws" in result.stdout
    document = column(tmp_path / "episode.rrd", "hparams", "TextDocument:text")[1][0]
    config = yaml.safe_load(document.strip().removeprefix("```yaml").removesuffix("```"))
    assert config["env"]["duration"] == 10.0  # the recording's config says what was run


def test_evaluate_replays_a_command_file(tmp_path):
    command = tmp_path / "hold.yaml"
    command.write_text("cycle: 1.0\nvia_points: [[0.0, -1.5708, 2.15]]\n")
    result = run_evaluate(f"policy={command}", "duration=4", f"hydra.run.dir={tmp_path}")
    assert result.returncode == 0, result.stderr
    assert (
        json.loads((tmp_path / "metrics.json").read_text())["throws"] == 0
    )  # holding never throws


@pytest.mark.slow
def test_bad_policy_or_env_value_gives_one_clear_line(tmp_path):
    rewards = ", ".join(REWARDS.names())
    for override, message in [
        ("policy=missing_command", "error: policy=missing_command: no policy file at"),
        ("policy=", "error: policy is empty: give a shipped policy (closed_loop,"),
        ("video=true render.fps=0", "error: render.fps=0 must be in (0, 50] (the env's steps)"),
        ("video=true render.camera=top", "error: render.camera=top is not in the scene; cameras:"),
        ("duration=0", "error: duration=0 is out of range"),  # evaluate.py's own key
        (
            "env.reward=style",
            f"error: env.reward='style' is not available; choose one of {rewards}",
        ),
    ]:
        result = run_evaluate(*override.split(), f"hydra.run.dir={tmp_path}")
        assert result.returncode != 0
        assert result.stderr.strip().startswith(message), result.stderr
        assert "Traceback" not in result.stderr


@pytest.mark.slow
def test_several_seeds_add_the_other_starts_run_as_one_batch(tmp_path):
    result = run_evaluate(
        "policy=closed_loop",
        "seeds=3",
        "seed=4",
        "duration=6",
        "env.reset_noise=0.01",
        f"hydra.run.dir={tmp_path}",
    )
    assert result.returncode == 0, result.stderr
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    starts = metrics["starts"]
    assert starts["seeds"] == [4, 5, 6] and starts["throws"][0] == metrics["throws"]
    alone = run_evaluate(
        "policy=closed_loop",
        "seed=6",
        "duration=6",
        "env.reset_noise=0.01",
        f"hydra.run.dir={tmp_path / 'alone'}",
    )
    assert alone.returncode == 0, alone.stderr
    lone = json.loads((tmp_path / "alone" / "metrics.json").read_text())
    assert lone["throws"] == starts["throws"][2]  # the batch's third start, run alone
    assert "on average over 3 starts" in result.stdout
    refused = run_evaluate("seeds=0", f"hydra.run.dir={tmp_path / 'refused'}")
    assert refused.returncode == 1
    assert refused.stderr.strip().startswith("error: seeds=0 is out of range")
