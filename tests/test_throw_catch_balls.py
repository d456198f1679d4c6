"""Throw and catch with several balls at the paper preset: the level catch, the throw timed by the
next ball down, and the shipped ``two_balls_throw`` (kept up by name: tests/test_balls.py)."""

from dataclasses import replace

import numpy as np
import pytest
import yaml

from jugglerl.commands import CommandError
from jugglerl.policies.cup_ik import CupIK
from jugglerl.policies.loading import load_policy
from jugglerl.policies.throw_catch import (
    SEAT_HEIGHT,
    save_throw_catch_policy,
    throw_catch_from_dict,
)
from jugglerl.runs.policy_files import read_policy_file
from jugglerl_envs import JuggleEnv

PAPER_WRIST = (-2.0, 1.5708, 0.0)


def test_a_level_solve_keeps_lift_plus_elbow_and_places_the_throat_horizontally():
    ik = CupIK(PAPER_WRIST)
    rest = np.array([0.0, -1.85, 2.279])
    rng = np.random.default_rng(0)
    for _ in range(10):
        lift = rest[1] + rng.uniform(-0.3, 0.3)
        pose = np.array([rng.uniform(-0.3, 0.3), lift, 0.429 - lift])
        target = ik.throat(pose) + [0.0, 0.0, 0.2]  # a height the level poses do not reach
        solved = ik.solve(target, rest, level=0.429)
        assert solved[1] + solved[2] == pytest.approx(0.429)
        np.testing.assert_allclose(ik.throat(solved)[:2], target[:2], atol=1e-5)
        assert abs(ik.throat(solved)[2] - target[2]) > 0.1
    free = ik.solve(target, rest)  # without level: the height too, and the cup tilts
    np.testing.assert_allclose(ik.throat(free), target, atol=1e-5)


def test_each_throw_starts_as_the_other_ball_comes_down_within_lead():
    env = JuggleEnv(balls=2, duration=20.0)
    policy = load_policy("two_balls_throw", env)
    lead, catch_height = policy.params.lead, policy.params.catch_height
    observation, info = env.reset(seed=0)
    policy.reset()
    leads, done = [], False
    while not done:
        mode = policy.mode
        action = policy.act(observation, info["time"])
        if policy.mode == "throw" and mode != "throw":  # the other ball: time to its catch
            other = observation[env.ball_slice(1 - policy._ball)]
            drop = other[2] - catch_height - SEAT_HEIGHT
            rise, g = other[5], -env.gravity
            leads.append((rise + np.sqrt(rise * rise + 2 * g * drop)) / g)
        observation, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated
    assert len(leads) >= 10 and info["throws"] >= len(leads) - 2
    assert max(leads) <= lead + 1e-9 and min(leads) > 0.0


def test_a_two_ball_file_reads_back_with_its_balls_and_several_ball_fields(tmp_path):
    data, source = read_policy_file("two_balls_throw")
    params = throw_catch_from_dict(data, source)
    assert params.lead and params.level == 0.429 and params.still
    path = save_throw_catch_policy(tmp_path / "mine.yaml", params, "mine", balls=2)
    again = yaml.safe_load(path.read_text())
    assert again["balls"] == 2 and throw_catch_from_dict(again, str(path)) == params
    one = save_throw_catch_policy(tmp_path / "one.yaml", replace(params, lead=None), "one")
    assert {"balls", "lead"}.isdisjoint(yaml.safe_load(one.read_text()))


@pytest.mark.parametrize(
    "change, message",
    [
        ({"lead": 0.0}, "lead must be a positive number"),
        ({"still": -0.1}, "still must be a number of seconds >= 0"),
        ({"level": float("nan")}, "level must be an angle"),
    ],
)
def test_bad_several_ball_fields_are_one_line_errors(change, message):
    data, _ = read_policy_file("two_balls_throw")
    with pytest.raises(CommandError, match=message):
        throw_catch_from_dict({**data, **change}, "bad.yaml")
