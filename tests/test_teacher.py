"""A teacher acting in the TorchRL loop: its batched labels are the plain policy's, step by step."""

import numpy as np
import pytest
import torch
from cli import train_config
from tensordict.nn import TensorDictModule, TensorDictSequential
from torchrl.envs.utils import ExplorationType, set_exploration_type

from jugglerl.batch.env_stack import make_env
from jugglerl.config.envs import make_juggle_env
from jugglerl.networks.actors import build_actor
from jugglerl.offpolicy.teacher import TEACHER_ACTION, TeacherModule, teacher_period
from jugglerl.policies.episodes import run_episode
from jugglerl.policies.loading import load_policy
from jugglerl.state.transforms import state_size
from jugglerl_envs import JuggleEnv

#: 2 envs whose 2 s episodes end and restart inside a 250-step roll-out.
SMALL = ["algo=ddpg", "env.duration=2", "state.norm_frames=200", "collector.num_envs=2"]


def replayed_labels(policy, observations, times, starts) -> np.ndarray:
    """What a single plain ``policy`` answers to one env's observation sequence."""
    labels = []
    for observation, time, start in zip(observations, times, starts, strict=True):
        if start:
            policy.reset()
        labels.append(policy.act(observation, float(time)))
    return np.array(labels)


@pytest.mark.slow
def test_the_teacher_labels_what_the_student_visits_as_the_plain_policy_would():
    cfg = train_config(*SMALL)
    torch.manual_seed(0)
    env = make_env(cfg, 2)
    env.set_seed(0)
    teacher = load_policy("closed_loop", JuggleEnv())
    student = build_actor(cfg.actor, state_size(cfg.state), 3)  # untrained: it acts, badly
    policy = TensorDictSequential(TeacherModule(teacher, 2), student)
    with set_exploration_type(ExplorationType.DETERMINISTIC), torch.no_grad():
        data = env.rollout(250, policy, break_when_any_done=False)
    starts = data["is_init"].squeeze(-1)
    assert starts[:, 1:].any()  # episodes restarted inside the roll-out
    assert not torch.allclose(data["action"], data[TEACHER_ACTION])  # the student drove
    for index in range(2):
        expected = replayed_labels(
            load_policy("closed_loop", JuggleEnv()),
            data["observation"][index].numpy(),
            data["time"][index].numpy(),
            starts[index].numpy(),
        )
        np.testing.assert_array_equal(data[TEACHER_ACTION][index].numpy(), expected)


@pytest.mark.slow
def test_a_teacher_driving_the_batch_juggles_as_it_does_alone():
    cfg = train_config(
        "algo=ddpg", "env.duration=10", "state.norm_frames=200", "collector.num_envs=2"
    )
    env = make_env(cfg, 2)
    teacher = TeacherModule(load_policy("closed_loop", JuggleEnv()), 2)
    follow = TensorDictModule(lambda action: action, [TEACHER_ACTION], ["action"])
    with torch.no_grad():
        data = env.rollout(500, TensorDictSequential(teacher, follow))
    plain = JuggleEnv(duration=10)
    observation, info = plain.reset(seed=0)
    alone = load_policy("closed_loop", plain)
    alone.reset()
    for step in range(500):
        action = alone.act(observation, info["time"])
        np.testing.assert_array_equal(data["action"][0, step].numpy(), action)
        observation, *_, info = plain.step(action)
    assert int(data["next", "throws"][0, -1]) == info["throws"] >= 3


class Still:
    """Holds the arm where it starts: never throws."""

    def reset(self) -> None: ...

    def act(self, observation, time):
        return np.zeros(3, dtype=np.float32)


@pytest.mark.slow
def test_a_teachers_period_is_its_command_cycle_or_the_time_between_its_throws():
    paper = JuggleEnv()
    closed_loop = load_policy("closed_loop", paper)
    assert teacher_period(closed_loop, paper) == closed_loop.command.cycle
    earth = make_juggle_env(train_config("env=earth").env, duration=20.0)
    juggler = load_policy("earth_juggler", earth)
    assert not hasattr(juggler, "command")  # no cycle of its own: measured from its throws
    period = teacher_period(juggler, earth)
    throws = run_episode(earth, juggler, seed=0).throws
    assert 20.0 / (throws + 1) < period < 20.0 / (throws - 1)  # throws every `period` s
    with pytest.raises(ValueError, match="the teacher threw 0 times in an episode"):
        teacher_period(Still(), JuggleEnv(duration=4.0))
