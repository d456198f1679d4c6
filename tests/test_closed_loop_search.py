"""The joint search space (``algo=closed_loop``): a command and its feedback gains together."""

import json

import torch
from cli import run_train, train_config

from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.spaces.closed_loop import CommandAndGainSpace
from jugglerl.policies.feedback import FeedbackPolicy
from jugglerl.policies.loading import load_policy
from jugglerl_envs import JuggleEnv


def test_it_starts_at_its_start_policy_and_decodes_back_to_it():
    space = CommandAndGainSpace(train_config("algo=closed_loop"))
    command, gains = space.decode(space.start)
    shipped = load_policy("closed_loop_gains", JuggleEnv())
    assert command == shipped.command and gains == shipped.gains
    assert len(space.start) == len(space.stds) == 10 + 6


def test_its_constraints_hold_over_many_wide_samples():
    space = CommandAndGainSpace(train_config("algo=closed_loop"))
    wide = SearchDistribution.diagonal(space.start, space.stds * 30)
    samples = wide.sample(2000, torch.Generator().manual_seed(0), space)
    assert all(space.violations(theta) == [] for theta in samples)
    assert samples.std(0).min() > 0  # every entry still varies
    env = JuggleEnv(duration=2.0)
    policy = space.policy(samples[0], env)
    assert isinstance(policy, FeedbackPolicy)
    observation, info = env.reset(seed=0)
    policy.reset()
    assert policy.act(observation, info["time"]).shape == (3,)


def test_train_closed_loop_writes_a_feedback_policy(tmp_path):
    run_dir = tmp_path / "run"
    result = run_train(
        "algo=closed_loop",
        "env.duration=4",
        "algo.episodes=1",
        "algo.rollouts=2",
        "algo.workers=1",
        "algo.noise_check.seeds=1",
        "algo.conditions=[{},{action_noise:0.003}]",
        "progress=false",
        "record_best=false",
        f"hydra.run.dir={run_dir}",
    )
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
