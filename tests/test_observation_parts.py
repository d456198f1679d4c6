"""The observation's parts in the networks' state (``state.observe``)."""

import pytest
import torch
from cli import train_config
from tensordict import TensorDict
from torchrl.envs.utils import check_env_specs

from jugglerl.batch.env_stack import make_env, normalisation
from jugglerl.networks.actors import build_actor
from jugglerl.policies.actor import ActorPolicy
from jugglerl.state.observation_parts import ObservationParts, observed_parts
from jugglerl.state.transforms import state_size

RELATIVE = "state.observe=[ball_from_cup,ball_velocity,cup_velocity]"


def test_the_parts_are_the_observations_values_in_the_order_named():
    observation = torch.arange(18.0).reshape(1, 18) ** 2  # ball 36, 49, 64; cup 144, 169, 196
    data = TensorDict({"state": observation}, batch_size=[1])
    state = ObservationParts(["ball_from_cup", "joints", "cup_velocity"])(data)["state"][0]
    expected = [36 - 144, 49 - 169, 64 - 196, 0, 1, 4, 225, 256, 289]
    assert state.tolist() == expected


@pytest.mark.slow
def test_the_stack_and_a_deployed_actor_see_the_same_relative_state():
    cfg = train_config("algo=ddpg", "env.duration=2", "state.norm_frames=200", RELATIVE)
    torch.manual_seed(0)
    env = make_env(cfg, 2)
    check_env_specs(env)
    size = state_size(cfg.state)
    assert env.observation_spec["state"].shape[-1] == size == 9 + 3  # the parts, the time
    actor = build_actor(cfg.actor, size, 3)
    env.set_seed(0)
    data = env.rollout(30, actor, break_when_any_done=False)
    norm = normalisation(env)
    policy = ActorPolicy.from_config(
        cfg, actor.state_dict(), {"loc": norm.loc, "scale": norm.scale}
    )
    policy.reset()
    for step in range(30):  # the deployed policy replays env 0's actions from its observations
        row = data[0, step]
        action = policy.act(row["observation"].numpy(), float(row["time"]))
        torch.testing.assert_close(torch.as_tensor(action), row["action"])


@pytest.mark.parametrize("parts", [["ball", "elbow"], ["ball", "ball"], []])
def test_a_bad_list_of_parts_is_refused_by_name(parts):
    with pytest.raises(
        ValueError, match=r"state.observe=.*: one or more of joints, .* at most once"
    ):
        observed_parts({"observe": parts})
