"""The joint search space (``algo=closed_loop``): a command and its feedback gains together."""

import json
from dataclasses import replace

import pytest
from cli import run_short_search, run_train, train_config
from search_spaces import assert_wide_samples_are_valid_policies

from jugglerl.dps.spaces.closed_loop import CommandAndGainSpace
from jugglerl.policies.feedback import FIXED_NAMES, FeedbackPolicy, save_feedback_policy
from jugglerl.policies.loading import load_policy
from jugglerl_envs import JuggleEnv


def test_it_starts_at_its_start_policy_and_decodes_back_to_it():
    space = CommandAndGainSpace(train_config("algo=closed_loop"))
    command, gains = space.decode(space.start)
    shipped = load_policy("closed_loop_gains", JuggleEnv())
    assert command == shipped.command and gains == shipped.gains
    assert len(space.start) == len(space.stds) == 10 + 6


def test_samples_keep_the_starts_own_settings(tmp_path):
    shipped = load_policy("closed_loop_gains", JuggleEnv())
    own = replace(shipped.gains, max_offset=0.08, hold_gain=0.01, hold_damping=0.02)
    start = save_feedback_policy(tmp_path / "start.yaml", shipped.command, own, "centred")
    cfg = train_config("algo=closed_loop", f"algo.start={start}")
    space = CommandAndGainSpace(cfg)
    sample = space.project(space.start + space.stds)
    _, gains = space.decode(sample)
    assert gains != own and {n: getattr(gains, n) for n in FIXED_NAMES} == {
        n: getattr(own, n) for n in FIXED_NAMES
    }


def test_its_constraints_hold_over_many_wide_samples():
    space = CommandAndGainSpace(train_config("algo=closed_loop"))
    assert_wide_samples_are_valid_policies(space, JuggleEnv(duration=2.0), FeedbackPolicy)


@pytest.mark.slow
def test_train_closed_loop_writes_a_feedback_policy(tmp_path):
    run_dir = tmp_path / "run"
    result = run_short_search("closed_loop", run_dir, "env.duration=4")
    assert result.returncode == 0, result.stderr
    metrics = json.loads((run_dir / "metrics.json").read_text())
    assert metrics["rollouts"] == 2 and "via_points" in metrics["command"]
    assert "closed_loop (cmaes): best scored" in result.stdout
    best = load_policy(str(run_dir / "best_policy.yaml"), JuggleEnv())
    assert best.command.cycle == metrics["command"]["cycle"]


def test_a_zero_std_under_cmaes_is_one_error_line(tmp_path):
    result = run_train("algo=closed_loop", "algo.std.phase_gain=0", f"hydra.run.dir={tmp_path}")
    assert result.returncode == 1
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith("error: algo.std: CMA-ES needs every std > 0"), result.stderr[-2000:]
