"""The optional fourth actuator: ``JuggleEnv(wrist_1_actuated=True)``."""

import math

import numpy as np
import pytest

from jugglerl_envs import JuggleEnv
from jugglerl_envs.actions import ctrl_to_action


def test_off_by_default_the_paper_env_keeps_three_actions_and_eighteen_observations():
    env = JuggleEnv()
    observation, info = env.reset(seed=0)
    assert env.wrist_1_actuated is False
    assert env.action_space.shape == (3,) and observation.shape == (18,)
    assert env.observation_space.shape == (18,) and info["peak_joint_speed"].shape == (3,)


@pytest.mark.parametrize("limit", [None, math.pi])
def test_holding_the_fourth_servo_at_its_lock_replays_the_three_actuator_env(limit):
    """The same physics and the same first 18 observations, step for step, plus wrist_1's angle
    and velocity: turning the option on changes nothing until the fourth setpoint moves. (The
    wrist is locked at 0 rad, which action 0 encodes exactly; another lock in float32 is 1e-7
    rad off, and the contacts grow that into centimetres.)"""
    pose = dict(home=(0.0, -2.2, 0.6292), wrist_angles=(0.0, 1.5708, 0.0))  # the cup upright
    three = JuggleEnv(duration=3.0, joint_speed_limit=limit, **pose)
    four = JuggleEnv(duration=3.0, joint_speed_limit=limit, wrist_1_actuated=True, **pose)
    obs3, _ = three.reset(seed=0)
    obs4, _ = four.reset(seed=0)
    done, step = False, 0
    while not done:
        np.testing.assert_array_equal(obs4[:18], obs3)
        assert obs4[18] == pytest.approx(0.0, abs=1e-3)
        elbow = 0.6292 if step < 60 else 0.2  # the ball lands and settles, then a flick
        action = ctrl_to_action(np.array([0.0, -2.2, elbow]))
        obs3, _, terminated, truncated, info3 = three.step(action)
        obs4, _, _, _, info4 = four.step(np.append(action, 0.0))
        done, step = terminated or truncated, step + 1
    assert info3["catches"] == info4["catches"] == 1  # caught at the start, then flung out
    np.testing.assert_array_equal(info4["peak_joint_speed"][:3], info3["peak_joint_speed"])


def test_the_fourth_servo_tilts_the_cup_within_the_speed_limit():
    env = JuggleEnv(wrist_1_actuated=True, joint_speed_limit=math.pi, drop_height=1.5)
    observation, _ = env.reset(seed=0)
    axis = env.data.site_xmat[env._cup_site].reshape(3, 3)[:, 2].copy()
    turned = np.array([*env.home, env.wrist_angles[0] + 0.5])  # 0.5 rad more
    for _ in range(50):
        observation, _, _, _, info = env.step(ctrl_to_action(turned))
    tilted = env.data.site_xmat[env._cup_site].reshape(3, 3)[:, 2]
    assert math.acos(np.clip(axis @ tilted, -1, 1)) == pytest.approx(0.5, abs=0.01)
    assert observation.shape == (20,)
    assert observation[18] == pytest.approx(turned[3], abs=0.01)
    assert info["peak_joint_speed"].shape == (4,)
    assert 1.0 < info["peak_joint_speed"][3] <= math.pi  # it moved, no faster than the limit


def test_an_action_of_the_wrong_length_is_refused():
    env = JuggleEnv(wrist_1_actuated=True)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"this env drives 4 servos \(wrist_1_actuated=True\)"):
        env.step(np.zeros(3))
    with pytest.raises(ValueError, match="wrist_1_actuated='yes' is not valid"):
        JuggleEnv(wrist_1_actuated="yes")


def test_open_loop_roll_outs_refuse_the_fourth_servo():
    from jugglerl.dps.rollouts import CommandRollouts

    with pytest.raises(ValueError, match="open-loop commands drive the three paper actuators"):
        CommandRollouts(JuggleEnv(wrist_1_actuated=True))
