"""scripts/evaluate.py end to end, as a user runs it."""

import json
import subprocess

import yaml
from cli import run_script

from jugglerl.recording.reading import column
from jugglerl_envs.rewards import REWARDS


def run_evaluate(*overrides: str) -> subprocess.CompletedProcess:
    return run_script("evaluate.py", *overrides)


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


def test_bad_policy_or_env_value_gives_one_clear_line(tmp_path):
    rewards = ", ".join(REWARDS.names())
    for override, message in [
        ("policy=missing_command", "error: no policy file at"),
        ("duration=0", "error: duration=0 is out of range"),  # evaluate.py's own key
        (
            "env.reward=style",
            f"error: env.reward='style' is not available; choose one of {rewards}",
        ),
    ]:
        result = run_evaluate(override, f"hydra.run.dir={tmp_path}")
        assert result.returncode != 0
        assert result.stderr.strip().startswith(message), result.stderr
        assert "Traceback" not in result.stderr
