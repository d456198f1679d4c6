"""The throw-and-catch search (``algo=throw_catch``), the flight fit and the roll-outs' limits."""

import json
from dataclasses import replace

import numpy as np
import pytest
from cli import env_preset, run_script, run_short_search, run_train, train_config
from search_spaces import assert_wide_samples_are_valid_policies

from jugglerl.dps.closed_loop_rollouts import ClosedLoopRollouts, within_limits
from jugglerl.dps.spaces.throw_catch import ThrowCatchSpace
from jugglerl.policies.episodes import EpisodeMetrics
from jugglerl.policies.flight_fit import FlightFit
from jugglerl.policies.loading import load_policy
from jugglerl.policies.throw_catch import ThrowCatchPolicy


def test_it_starts_at_earth_expert_and_decodes_back_to_it():
    space = ThrowCatchSpace(train_config("algo=throw_catch", "algo.workers=1"))
    shipped = load_policy("earth_expert", env_preset("earth"))
    assert space.decode(space.start) == shipped.params
    assert len(space.start) == len(space.stds) == 2 + 3 * 3 + 3


def test_a_two_ball_start_adds_its_lead_and_still_to_theta_and_its_balls_to_the_file(tmp_path):
    space = ThrowCatchSpace(train_config("+experiment=two_balls_throw", "algo.workers=1"))
    start = space.decode(space.start)
    env = env_preset("paper", balls=2)
    assert start == load_policy("two_balls_throw_start", env).params
    assert space._names()[-2:] == ["lead", "still"] and len(space.start) == 2 + 3 * 3 + 5
    moved = space.decode(space.start + 0.01)
    assert moved.lead == pytest.approx(start.lead + 0.01) and moved.level == start.level
    written = tmp_path / space.save(space.start, tmp_path, "mine")
    assert load_policy(str(written), env).params == start  # it states balls: 2, as the env has


@pytest.mark.slow
def test_its_constraints_hold_over_many_wide_samples():
    space = ThrowCatchSpace(train_config("algo=throw_catch", "algo.workers=1"))
    env = env_preset("earth", duration=1.0)
    samples = assert_wide_samples_are_valid_policies(space, env, ThrowCatchPolicy)
    for theta in samples[:50]:  # what the bounds promise
        params = space.decode(theta)
        assert min(knot[0] for knot in params.knots) >= 0.02 and params.settle >= 0.05
        assert 0.3 <= params.catch_height <= 0.76


def test_a_start_made_for_another_wrist_lock_is_one_error_line(tmp_path):
    result = run_train("algo=throw_catch", "env=paper", f"hydra.run.dir={tmp_path}")
    assert result.returncode == 1
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith("error: policy earth_expert throws with wrist_angles")


@pytest.mark.slow
def test_train_throw_catch_writes_a_policy_that_evaluate_replays(tmp_path):
    run_dir = tmp_path / "run"
    result = run_short_search("throw_catch", run_dir, "env.duration=6")
    assert result.returncode == 0, result.stderr
    metrics = json.loads((run_dir / "metrics.json").read_text())
    assert metrics["rollouts"] == 2 and len(metrics["throw_catch"]["knots"]) == 3
    assert "throw_catch (cmaes): best scored" in result.stdout
    evaluated = run_script(
        "evaluate.py",
        f"policy={run_dir}",
        "env=earth",
        "duration=6",
        f"hydra.run.dir={tmp_path / 'eval'}",
    )
    assert evaluated.returncode == 0, evaluated.stderr
    assert "throws in 6 s" in evaluated.stdout


@pytest.mark.slow
def test_episodes_beyond_the_limits_score_no_throws():
    metrics = EpisodeMetrics(
        throws=10,
        catches=10,
        max_consecutive_catches=10,
        time_to_drop=None,
        duration=10.0,
        seed=0,
        max_cup_height=0.7,
        peak_joint_speed=(0.1, 3.0, 2.0),
    )
    assert within_limits(metrics, {})
    assert within_limits(metrics, {"max_cup_height": 0.76, "max_joint_speed": 3.14})
    assert not within_limits(metrics, {"max_cup_height": 0.65})
    assert not within_limits(metrics, {"max_joint_speed": 2.5})
    assert within_limits(metrics, {"max_balls_in_cup": 1})
    shared = replace(metrics, max_balls_in_cup=2)  # two balls in the cup at once
    assert within_limits(shared, {"max_balls_in_cup": None})
    assert not within_limits(shared, {"max_balls_in_cup": 1})
    space = ThrowCatchSpace(train_config("algo=throw_catch", "env.duration=6"))
    start = space.decode(space.start)  # its cup rises to 0.66 m
    env_cfg = train_config("env=earth", "env.duration=6").env
    build = space.build
    with ClosedLoopRollouts(env_cfg, [{}], 1, build, limits={"max_cup_height": 0.76}) as free:
        assert free.evaluate([start], [0]).throws[0] > 0
    with ClosedLoopRollouts(env_cfg, [{}], 1, build, limits={"max_cup_height": 0.6}) as low:
        assert low.evaluate([start], [0]).throws[0] == 0
    with pytest.raises(ValueError, match="limits: unknown \\['max_height'\\]"):
        ClosedLoopRollouts(env_cfg, [{}], 1, build, limits={"max_height": 1.0})


def test_the_flight_fit_averages_tracking_noise_and_follows_a_kick():
    rng = np.random.default_rng(0)
    times = np.arange(40) * 0.02
    line = np.array([0.1, -0.2]) + np.outer(times, [0.5, 0.1])  # m, at 0.5 and 0.1 m/s
    noisy = line + rng.normal(0.0, 0.001, size=line.shape)  # 1 mm of tracking noise
    fit = FlightFit()
    for t, p in zip(times, noisy, strict=True):
        fit.add(t, p)
    position, velocity = fit.state(times[-1], noisy[-1], None)
    differenced = (noisy[-1] - noisy[-2]) / 0.02  # what the tracker reports
    assert np.abs(velocity - [0.5, 0.1]).max() < 0.01 < np.abs(differenced - [0.5, 0.1]).max()
    assert np.abs(position - line[-1]).max() < 0.001
    single = FlightFit()
    single.add(0.0, noisy[0])  # one sample spans no time: the sample itself
    assert single.state(0.0, noisy[0], np.array([0.5, 0.1]))[1].tolist() == [0.5, 0.1]
    forgetting = FlightFit(forget=0.8)
    for t in times:  # kicked at 0.4 s: from 0.5 to 0.8 m/s along x
        forgetting.add(t, np.array([0.5 * t + 0.3 * max(t - 0.4, 0.0), 0.0]))
    assert forgetting.state(times[-1], None, None)[1][0] == pytest.approx(0.8, abs=0.02)
