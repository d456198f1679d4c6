"""``JuggleEnv(balls=N)``: one ball plays back as before; with two, either ball's throw counts
once, a dropped ball ends the episode, and the observation is laid out as the env documents."""

import numpy as np
import pytest
from closed_loop_episode import RECORDED, play

import jugglerl  # noqa: F401  (registers the id)
from jugglerl.commands import load_command
from jugglerl.policies.episodes import run_episode
from jugglerl.policies.feedback import LOCK_HEIGHT, FeedbackGains, FeedbackPolicy
from jugglerl.policies.loading import load_policy
from jugglerl.policies.throw_catch import ThrowCatchPolicy
from jugglerl.runs.policy_files import PolicyFileError
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


def test_balls_sharing_the_cup_are_reported():
    """Balls pass through each other, so two can sit in the cup at once; ``max_balls_in_cup``
    says so (the searches refuse such episodes, ``algo.limits.max_balls_in_cup``)."""
    for spacing, most in ((0.2, 2), (2.0, 1)):  # the second lands on the first; or after it
        env = JuggleEnv(balls=2, ball_spacing=spacing, duration=1.4)
        env.reset(seed=0)
        done = False
        while not done:
            _, _, terminated, truncated, info = env.step(hold_arm(env))
            done = terminated or truncated
        assert info["max_balls_in_cup"] == most and not terminated
        env.close()


def test_an_episode_of_two_balls_reports_throws_per_ball():
    env = JuggleEnv(balls=2, duration=6.0)
    metrics = run_episode(env, load_policy("closed_loop", env), seed=0)
    assert sum(metrics.throws_per_ball) == metrics.throws
    assert len(metrics.throws_per_ball) == 2
    env.close()


def two_balls_seen(first: float, second: float, second_x: float = 0.0) -> np.ndarray:
    """An observation of a two-ball env: the cup at rest at (0, 0, 0.8), the first ball ``first``
    above it and the second ``second`` above it (``second_x`` along x), both falling at 1 m/s."""
    observation = np.zeros(24)
    observation[12:15] = (0.0, 0.0, 0.8)
    for start, x, height in ((6, 0.0, first), (18, second_x, second)):
        observation[start : start + 3] = (x, 0.0, 0.8 + height)
        observation[start + 5] = -1.0
    return observation


def test_with_two_balls_each_one_locks_the_phase_as_it_comes_down():
    env = JuggleEnv(balls=2)
    policy = FeedbackPolicy(load_command("dps_best"), FeedbackGains(0.6, 1, 0, 1, 0, 0), env)
    policy.reset()
    policy.act(two_balls_seen(0.5, 1.5), 1.0)
    policy.act(two_balls_seen(LOCK_HEIGHT, 1.5), 1.02)  # the first ball locks
    assert policy.phase == pytest.approx(0.6)
    policy.act(two_balls_seen(0.0, 0.5), 2.0)
    policy.act(two_balls_seen(0.0, LOCK_HEIGHT), 2.02)  # then the second; the first, held, not
    assert policy.phase == pytest.approx(0.6)
    policy.act(two_balls_seen(0.0, LOCK_HEIGHT - 0.02), 2.04)  # each locks once per fall
    assert policy.phase == pytest.approx(0.6 + env.dt)


def test_with_two_balls_the_cup_tracks_the_next_landing_only_while_it_holds_none():
    env = JuggleEnv(balls=2)
    gains = FeedbackGains(0.6, 0.0, 0.5, 0.5, 0.0, 0.0)
    policy = FeedbackPolicy(load_command("dps_best"), gains, env)
    policy.reset()
    policy.act(two_balls_seen(0.05, 0.6, second_x=0.04), 0.0)  # one held: no tracking
    np.testing.assert_array_equal(policy.offset, [0.0, 0.0])
    policy.act(two_balls_seen(1.0, 0.6, second_x=0.04), 0.02)  # thrown: track the other
    assert policy.offset[0] > 0.01 and policy.offset[1] == 0.0


@pytest.mark.parametrize(
    "name, kind", [("two_balls", FeedbackPolicy), ("two_balls_throw", ThrowCatchPolicy)]
)
@pytest.mark.slow
def test_a_shipped_two_ball_juggler_keeps_both_balls_up_one_at_a_time(name, kind):
    env = JuggleEnv(balls=2, duration=30.0)
    policy = load_policy(name, env)
    assert isinstance(policy, kind)
    metrics = run_episode(env, policy, seed=0)
    assert metrics.time_to_drop is None and min(metrics.throws_per_ball) >= 8
    assert metrics.max_cup_height <= 0.76 and metrics.max_balls_in_cup == 1
    env.close()
    with pytest.raises(
        PolicyFileError, match="juggles balls=2 but the env has 1: run it with env.balls=2"
    ):
        load_policy(name, JuggleEnv())
