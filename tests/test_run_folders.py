"""Run folders: a new run never mixes its files with another run's, a resumed run is unfinished
until it ends, and a policy taken from an unfinished run says so."""

import pytest
import torch

from jugglerl.policies.loading import load_policy
from jugglerl.runs.policy_files import policy_file
from jugglerl.training import prepare_run_folder
from jugglerl_envs import JuggleEnv

RUN_FILES = ("checkpoint.pt", "metrics.json", "train.rrd", "metrics.json.partial")


def a_run_folder(path):
    path.mkdir()
    for name in RUN_FILES:
        (path / name).write_text("x")
    return path


def test_a_new_run_refuses_another_runs_folder_and_leaves_it_alone(tmp_path):
    run = a_run_folder(tmp_path / "run")
    with pytest.raises(ValueError, match=r"holds another run \(checkpoint.pt, metrics.json\)"):
        prepare_run_folder(run, resuming=False, overwrite=False)
    assert all((run / name).exists() for name in RUN_FILES)
    prepare_run_folder(tmp_path / "fresh", resuming=False, overwrite=False)  # nothing there


def test_overwrite_clears_the_other_runs_files(tmp_path):
    run = a_run_folder(tmp_path / "run")
    (run / "best_policy.yaml").write_text("x")
    prepare_run_folder(run, resuming=False, overwrite=True)
    assert sorted(path.name for path in run.iterdir()) == ["best_policy.yaml"]  # rewritten later


def test_a_resumed_run_keeps_its_checkpoint_and_recording_but_is_unfinished(tmp_path):
    run = a_run_folder(tmp_path / "run")
    prepare_run_folder(run, resuming=True, overwrite=False)
    assert sorted(path.name for path in run.iterdir()) == ["checkpoint.pt", "train.rrd"]


def test_a_policy_from_an_unfinished_run_says_so(tmp_path, capsys):
    env = JuggleEnv()
    run = tmp_path / "run"
    run.mkdir()
    torch.save({"config": {}, "deploys": "best_policy.yaml"}, run / "checkpoint.pt")
    (run / "best_policy.yaml").write_text(policy_file("expert").read_text())
    load_policy(str(run), env)
    assert capsys.readouterr().err.startswith(f"warning: {run} holds an unfinished run")
    (run / "metrics.json").write_text("{}")
    load_policy(str(run), env)
    assert capsys.readouterr().err == ""
