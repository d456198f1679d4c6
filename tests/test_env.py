"""JuggleEnv: API checks, rewards, episode end, errors, speed limit."""

import math

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import jugglerl  # noqa: F401  (registers the id)
from jugglerl_envs import ENV_ID, JuggleEnv
from jugglerl_envs.rewards import REWARDS


def test_gymnasium_check_env_passes():
    env = JuggleEnv()
    check_env(env, skip_render_check=True)
    env.close()


def test_torchrl_check_env_specs_passes():
    from torchrl.envs import GymEnv
    from torchrl.envs.utils import check_env_specs

    env = GymEnv(ENV_ID)
    check_env_specs(env)
    env.close()


def test_registered_id_defaults_equal_the_paper_preset():
    from hydra import compose, initialize

    with initialize(version_base="1.3", config_path="../configs"):
        cfg = compose(config_name="evaluate")
    env = gym.make(ENV_ID).unwrapped
    for key, value in cfg.env.items():
        attr = {"reward": "reward_kind"}.get(key, key)
        actual = env.frame_skip if key == "frame_skip" else getattr(env, attr)
        if isinstance(actual, np.ndarray):
            np.testing.assert_allclose(actual, list(value), err_msg=key)
        else:
            assert actual == value, key


def test_observation_layout(hold):
    env = JuggleEnv()
    obs, _ = env.reset(seed=0)
    assert obs.shape == (18,) and obs.dtype == np.float64
    np.testing.assert_allclose(obs[:3], env.home, atol=1e-9)
    np.testing.assert_allclose(obs[6:9] - obs[12:15], [0, 0, env.drop_height], atol=1e-9)
    for _ in range(10):
        obs, *_ = env.step(hold(env))
    assert obs[11] < 0  # ball falling
    np.testing.assert_allclose(obs[9:12], env.ball_velocity())


def test_reset_noise_offsets_the_ball_reproducibly_by_seed():
    env = JuggleEnv(reset_noise=0.01)
    a, _ = env.reset(seed=3)
    b, _ = env.reset(seed=3)
    c, _ = env.reset(seed=4)
    np.testing.assert_array_equal(a, b)
    offset = (c[6:9] - c[12:15])[:2]
    assert np.all(np.abs(offset) <= 0.01) and np.any(c != a)


def test_distance_reward_is_bounded_and_peaks_with_ball_in_cup(hold):
    env = JuggleEnv(reward="distance")
    env.reset(seed=0)
    rewards = [env.step(hold(env))[1] for _ in range(100)]
    assert 0 < rewards[0] < 0.2  # ball 0.5 m above the cup: 0.05 / 0.5
    assert rewards[-1] == 1.0  # resting in the cup, within 5 cm of the throat
    assert max(rewards) <= 1.0


def test_contacts_reward_counts_ball_arm_contacts(hold):
    env = JuggleEnv(reward="contacts")
    env.reset(seed=0)
    rewards = [env.step(hold(env))[1] for _ in range(100)]
    assert rewards[0] == 0  # in the air
    assert rewards[-1] >= 2  # resting against several plates


def test_throws_reward_pays_one_per_counted_throw():
    from jugglerl.commands import load_command
    from jugglerl.policies.command import CommandPolicy

    env = JuggleEnv(duration=10.0)
    policy = CommandPolicy(load_command("expert"))
    obs, info = env.reset(seed=0)
    total, done = 0.0, False
    while not done:
        obs, reward, terminated, truncated, info = env.step(policy.act(obs, info["time"]))
        assert reward in (0.0, 1.0)
        total += reward
        done = terminated or truncated
    assert total == info["throws"] >= 2


def test_dropping_the_ball_terminates():
    env = JuggleEnv(gravity=-9.81)
    env.reset(seed=0)
    away = env.ctrl_to_action([1.2, -1.5708, 2.15])  # pan the cup out from under the ball
    for _ in range(500):
        _, _, terminated, truncated, info = env.step(away)
        if terminated:
            break
    assert terminated and not truncated
    assert info["ball_height"] < 0.1 and info["physics_error"] == ""


def test_truncation_at_duration(hold):
    env = JuggleEnv(duration=1.0)  # 50 steps of 0.02 s
    env.reset(seed=0)
    ends = [env.step(hold(env))[2:4] for _ in range(50)]
    assert all(not t and not tr for t, tr in ends[:-1])
    assert ends[-1] == (False, True)
    assert math.isclose(env.data.time, 1.0)


def test_bad_physics_terminates_with_error_instead_of_raising(hold):
    env = JuggleEnv()
    env.reset(seed=0)
    env.data.qvel[0] = np.nan
    _, _, terminated, truncated, info = env.step(hold(env))
    assert terminated and not truncated
    assert "mjWARN" in info["physics_error"]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"reward": "style"},
            f"reward='style' is not available; choose one of {', '.join(REWARDS.names())}",
        ),
        ({"gravity": 3.0}, "gravity=3.0 is out of range"),
        ({"frame_skip": 0}, "frame_skip=0 is out of range"),
        ({"timestep": 0.0}, "timestep=0.0 is out of range: expected a number in (0.0, 0.01]"),
        ({"ball_radius": "big"}, "ball_radius='big' is not valid"),
        ({"joint_speed_limit": -1.0}, "joint_speed_limit=-1.0 is out of range"),
        ({"home": (0.0, 1.0)}, "home=(0.0, 1.0) is not valid: expected 3 numbers"),
    ],
)
def test_bad_kwarg_names_the_key_and_the_valid_values(kwargs, message):
    with pytest.raises(
        ValueError,
        match=message.replace("(", r"\(")
        .replace(")", r"\)")
        .replace("[", r"\[")
        .replace("]", r"\]"),
    ):
        JuggleEnv(**kwargs)


def test_joint_speed_limit_caps_the_servo_speed():
    jump = [0.0, -1.5708, 1.0]  # a 1.15 rad elbow setpoint jump

    def peak_speed(limit):
        env = JuggleEnv(joint_speed_limit=limit)
        env.reset(seed=0)
        for _ in range(40):
            _, _, _, _, info = env.step(env.ctrl_to_action(jump))
        return info["peak_joint_speed"][2]

    assert peak_speed(None) > 4.0  # the overdamped servo turns a jump into a fast impulse
    assert peak_speed(1.0) <= 1.0 * 1.05


def test_ball_carried_over_the_threshold_is_not_a_throw():
    # Forearm vertical and cup upright (wrist_1 0, lift + elbow = -π/2) from a low pose; raise the
    # upper arm slowly, keeping the forearm vertical, with the ball resting in the cup.
    env = JuggleEnv(
        home=(0.0, -3.1, 1.5292), wrist_angles=(0.0, 1.5708, 0.0), joint_speed_limit=0.4
    )
    env.reset(seed=0)
    lift = env.ctrl_to_action([0.0, -1.87, 0.2992])
    highest = 0.0
    for _ in range(300):
        _, _, terminated, _, info = env.step(lift)
        assert not terminated
        highest = max(highest, info["ball_height"])
    assert highest > 1.1 and info["in_cup"]
    assert info["throws"] == 0


def test_rgb_rendering_when_an_opengl_backend_exists():
    env = JuggleEnv(render_mode="rgb_array", width=160, height=120)
    env.reset(seed=0)
    try:
        frame = env.render()
    except Exception as error:  # no GL context on this machine
        pytest.skip(f"no OpenGL backend: {error}")
    finally:
        env.close()
    assert frame.shape == (120, 160, 3) and frame.std() > 0


def test_env_imports_without_torch():
    import subprocess
    import sys

    code = "import sys, jugglerl_envs; assert 'torch' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True)
    assert mujoco.__version__


def test_the_rise_reward_pays_the_free_rise_up_to_the_threshold(hold):
    """A ball tossed straight up beside the cup from 0.7 m at 2.5 m/s (apex ≈ 2.26 m at
    g = -2): the rise term sums to its climb up to the 1 m threshold, and nothing after."""
    from jugglerl_envs.rewards.juggle import juggle_reward
    from jugglerl_envs.rewards.rise import RISE_WEIGHT

    env = JuggleEnv(reward="rise")
    env.reset(seed=0)
    env.ball_position()[:] = env.cup_position() + [0.4, 0.0, 0.0]
    env.ball_position()[2] = 0.7
    env.ball_velocity()[:] = [0.0, 0.0, 2.5]
    extra, throws = 0.0, 0
    for _ in range(100):
        _, reward, *_, info = env.step(hold(env))
        thrown = info["throws"] - throws
        throws = info["throws"]
        extra += reward - float(juggle_reward(env.batch, np.array([thrown]))[0])
    assert throws == 1  # the toss crossed the threshold in free flight
    assert extra == pytest.approx(RISE_WEIGHT * (1.0 - 0.7), abs=0.05 * RISE_WEIGHT)
