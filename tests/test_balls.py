"""``JuggleEnv(balls=N)``: one ball plays back as before; with two, either ball's throw counts
once, a dropped ball ends the episode, and the observation is laid out as the env documents."""

import numpy as np
import pytest
from closed_loop_episode import RECORDED, play

import jugglerl  # noqa: F401  (registers the id)
from jugglerl.evaluation import run_episode
from jugglerl.policies.loading import load_policy
from jugglerl_envs import JuggleEnv


def test_one_ball_plays_back_the_episode_recorded_before_the_env_took_balls():
    recorded = np.load(RECORDED)
    played, info = play(balls=1)
    for key, values in played.items():
        np.testing.assert_array_equal(values, recorded[key], err_msg=key)
    assert info["throws_per_ball"] == (info["throws"],) == (14,)


def hold_arm(env: JuggleEnv) -> np.ndarray:
    """The action that keeps the arm at its start pose."""
    return env.ctrl_to_action(env.data.ctrl[: len(env.actuated_joints)])


def test_the_observation_holds_each_further_ball_after_the_first():
    env = JuggleEnv(balls=3, wrist_1_actuated=True)
    observation, info = env.reset(seed=1)
    assert env.observation_space.shape == observation.shape == (18 + 2 + 6 * 2,)
    observation, *_ = env.step(hold_arm(env))
    for ball, start in ((0, 6), (1, 20), (2, 26)):
        np.testing.assert_array_equal(observation[start : start + 3], env.ball_position(ball))
        np.testing.assert_array_equal(observation[start + 3 : start + 6], env.ball_velocity(ball))
    heights = [env.ball_position(ball)[2] for ball in range(3)]
    assert info["ball_heights"][1] - info["ball_heights"][0] == pytest.approx(env.ball_spacing)
    assert heights[2] > heights[1] > heights[0]  # still falling in their order
    env.close()


def test_a_throw_of_either_ball_counts_once_for_that_ball():
    env = JuggleEnv(balls=2)
    env.reset(seed=0)
    cup = env.cup_position().copy()
    position, velocity = env.ball_position(1), env.ball_velocity(1)
    position[:] = cup + [0.3, 0.0, env.threshold - 0.05 - cup[2]]  # beside the cup, rising
    velocity[:] = [0.0, 0.0, 1.0]
    counts = []
    for _ in range(50):
        _, reward, terminated, _, info = env.step(hold_arm(env))
        counts.append(info["throws_per_ball"])
    crossing = counts.index((0, 1))  # counted at its crossing, once, up and back down
    assert crossing > 0 and counts == [(0, 0)] * crossing + [(0, 1)] * (len(counts) - crossing)
    assert info["throws"] == 1
    env.close()


def test_either_ball_dropped_ends_the_episode():
    env = JuggleEnv(balls=2)
    env.reset(seed=0)
    env.ball_position(1)[:] = env.cup_position() + [0.5, 0.0, 0.0]  # beside the cup: it falls
    terminated = False
    for _ in range(100):
        _, _, terminated, truncated, info = env.step(hold_arm(env))
        if terminated:
            break
    assert terminated and not truncated and not info["physics_error"]
    assert info["ball_heights"][1] < 0.1 < info["ball_heights"][0]
    env.close()


def test_an_episode_of_two_balls_reports_throws_per_ball():
    env = JuggleEnv(balls=2, duration=6.0)
    metrics = run_episode(env, load_policy("closed_loop", env), seed=0)
    assert sum(metrics.throws_per_ball) == metrics.throws
    assert len(metrics.throws_per_ball) == 2
    env.close()
