"""The env's perturbations do what they say, measured in the simulation."""

import numpy as np
import pytest

from jugglerl.commands import load_command
from jugglerl.dps.rollouts import CommandRollouts
from jugglerl_envs import JuggleEnv
from jugglerl_envs.rewards.cradle import CRADLE_SCALE, CRADLE_WEIGHT, cradle_reward
from jugglerl_envs.rewards.juggle import CENTRING_WEIGHT, juggle_reward


def elbow_after_a_setpoint_jump(servo_gain: float) -> float:
    """Elbow angle 0.1 s after its setpoint jumps 0.5 rad from the home pose."""
    env = JuggleEnv(servo_gain=servo_gain)
    env.reset(seed=0)
    target = env.ctrl_to_action(env.home + np.array([0.0, 0.0, -0.5]))
    for _ in range(5):
        observation, *_ = env.step(target)
    return float(observation[2])


def test_servo_gain_scales_the_arm_servos_kp_and_slows_the_arm():
    weak = JuggleEnv(servo_gain=0.5)
    nominal = JuggleEnv()
    np.testing.assert_allclose(weak.model.actuator_gainprm[:3, 0], [1000.0] * 3)
    np.testing.assert_allclose(weak.model.actuator_biasprm[:3, 1:3], [[-1000.0, -400.0]] * 3)
    wrists = slice(3, None)
    np.testing.assert_array_equal(
        weak.model.actuator_gainprm[wrists], nominal.model.actuator_gainprm[wrists]
    )
    home = nominal.home[2]
    moved_nominal = home - elbow_after_a_setpoint_jump(1.0)
    moved_weak = home - elbow_after_a_setpoint_jump(0.5)
    assert 0.1 < moved_weak < 0.8 * moved_nominal


def test_a_kick_changes_the_balls_horizontal_velocity_by_kick_speed():
    env = JuggleEnv(kick_rate=100.0, kick_speed=0.3)  # a kick in most 20 ms steps of flight
    observation, info = env.reset(seed=1)
    hold = env.ctrl_to_action(env.home)
    while info["kicks"] == 0:
        observation, _, _, _, info = env.step(hold)
    assert info["kicks"] == 1 and not info["in_cup"]  # the ball is still falling onto the cup
    np.testing.assert_allclose(np.linalg.norm(observation[9:11]), 0.3, atol=1e-6)
    assert abs(observation[11]) > 0.01  # gravity alone acts vertically


def test_no_kicks_by_default():
    env = JuggleEnv(duration=10.0)
    observation, info = env.reset(seed=0)
    command = load_command("expert")
    while True:
        observation, _, terminated, truncated, info = env.step(
            env.ctrl_to_action(command.setpoints(info["time"]))
        )
        if terminated or truncated:
            break
    assert info["kicks"] == 0 and not env.kicks_ball


def test_ball_mass_and_radius_reach_the_model():
    env = JuggleEnv(ball_mass=0.15, ball_radius=0.04)
    ball = env.model.body("ball")
    assert ball.mass[0] == pytest.approx(0.15)
    assert env.model.geom("ball").size[0] == pytest.approx(0.04)


@pytest.mark.parametrize(
    "key, value", [("servo_gain", 0.0), ("kick_rate", -1.0), ("kick_speed", "fast")]
)
def test_bad_perturbation_values_are_named(key, value):
    with pytest.raises(ValueError, match=f"{key}="):
        JuggleEnv(**{key: value})


def test_dps_rollouts_refuse_an_env_that_kicks_the_ball():
    with pytest.raises(ValueError, match="cannot kick the ball"):
        CommandRollouts(JuggleEnv(kick_rate=1.0, kick_speed=0.1))


def test_the_juggle_reward_pays_for_a_ball_centred_over_the_cup():
    env = JuggleEnv(reward="juggle", reset_noise=0.05)
    hold = env.ctrl_to_action(env.home)
    for seed in range(3):
        observation, _ = env.reset(seed=seed)
        observation, reward, *_ = env.step(hold)
        offset = np.linalg.norm(observation[6:8] - observation[12:14])
        expected = CENTRING_WEIGHT * max(0.0, 1.0 - offset / 0.1)
        assert reward == pytest.approx(expected, abs=2e-4)  # the cup moved a little in the step
        assert 0 < reward <= CENTRING_WEIGHT


def test_the_cradle_reward_charges_a_held_ball_for_its_distance_from_the_cone_axis():
    env = JuggleEnv(reward="cradle", reset_noise=0.01)
    hold = env.ctrl_to_action(env.home)
    env.reset(seed=1)
    held = 0
    for _ in range(120):  # the ball falls into the cup held at home, rolls in and settles
        env.step(hold)
        radial, _ = env.ball_in_cup_frame()
        cost = CRADLE_WEIGHT * min(1.0, radial / CRADLE_SCALE) if env.ball_in_cup() else 0.0
        none, one = np.zeros(1), np.ones(1)
        assert cradle_reward(env.batch, none) == pytest.approx(
            juggle_reward(env.batch, none) - cost
        )
        held += cost > 0
    assert held > 50
    assert cradle_reward(env.batch, one) == pytest.approx(cradle_reward(env.batch, none) + 1.0)


# --- imprecision ----------------------------------------------------------------------------------
def applied_noise(**kwargs) -> np.ndarray:
    """The noise the env added to a held action, read back from the servo setpoints (rad ->
    normalised), over 500 steps."""
    env = JuggleEnv(**kwargs)
    env.reset(seed=3)
    hold = env.ctrl_to_action(env.home).astype(np.float64)
    applied = []
    for _ in range(500):
        env.step(hold)
        applied.append(env.ctrl_to_action(env.data.ctrl[:3]) - hold)
    return np.array(applied)


def test_action_noise_is_white_or_correlated_with_the_std_asked_for():
    white = applied_noise(action_noise=0.01)
    correlated = applied_noise(action_noise=0.01, action_noise_correlation=0.2)
    for noise in (white, correlated):
        assert noise.std() == pytest.approx(0.01, rel=0.25)
    lag = [np.corrcoef(n[:-1, 1], n[1:, 1])[0, 1] for n in (white, correlated)]
    assert abs(lag[0]) < 0.15 and lag[1] > 0.8  # exp(-0.02 / 0.2) = 0.90
    np.testing.assert_array_equal(applied_noise(), 0)  # off: the action as given


def tracked_ball(steps: int = 60, **kwargs) -> tuple[np.ndarray, np.ndarray]:
    """(observed, true) ball position and velocity, ``[steps + 1, 6]``, while the ball falls."""
    env = JuggleEnv(**kwargs)
    observation, _ = env.reset(seed=0)
    hold = env.ctrl_to_action(env.home)
    seen, true = [observation[6:12]], [env.true_observation()[6:12]]
    for _ in range(steps):
        observation, *_ = env.step(hold)
        seen.append(observation[6:12])
        true.append(env.true_observation()[6:12])
    return np.array(seen), np.array(true)


def test_a_tracked_ball_has_noisy_positions_and_velocities_from_their_differences():
    seen, true = tracked_ball(ball_noise=0.002)
    error = seen[:, :3] - true[:, :3]
    assert error.std() == pytest.approx(0.002, rel=0.3)
    np.testing.assert_allclose(seen[1:, 3:], np.diff(seen[:, :3], axis=0) / 0.02)
    plain_seen, plain_true = tracked_ball()
    np.testing.assert_array_equal(plain_seen, plain_true)  # off: the true state


def test_ball_latency_shows_the_ball_steps_late_and_the_events_read_the_true_one():
    seen, true = tracked_ball(ball_latency=2)
    np.testing.assert_array_equal(seen[2:], true[:-2])
    env = JuggleEnv(ball_latency=2)
    env.reset(seed=0)
    for _ in range(10):
        observation, *_, info = env.step(env.ctrl_to_action(env.home))
    assert info["ball_height"] == env.true_observation()[8] != observation[8]
