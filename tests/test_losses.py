"""The loss plug-ins (ddpg, td3, bc) on fixed batches, and the registry's message."""

import math

import pytest
import torch
from cli import train_config
from tensordict import TensorDict
from torchrl.envs.utils import ExplorationType, set_exploration_type
from torchrl.modules import set_recurrent_mode

from jugglerl.batch.env_stack import make_env
from jugglerl.networks.actors import build_actor
from jugglerl.networks.plain import PlainActor, starts_inside
from jugglerl.offpolicy.buffer import ReplayBuffer
from jugglerl.offpolicy.losses import LOSSES
from jugglerl.offpolicy.losses.bc import TEACHER_ACTION, behaviour_cloning_loss
from jugglerl.state.transforms import state_size

SMALL = ["algo=ddpg", "env.duration=6", "state.norm_frames=200", "collector.num_envs=2"]


def transitions(*overrides: str):
    """A config, an actor, its loss plug-in and 2 x 64 random transitions with teacher labels."""
    cfg = train_config(*SMALL, *overrides)
    torch.manual_seed(0)
    env = make_env(cfg, cfg.collector.num_envs)
    env.set_seed(0)
    actor = build_actor(cfg.actor, state_size(cfg.state), 3)
    with set_exploration_type(ExplorationType.RANDOM):
        data = env.rollout(64, lambda td: env.rand_action(td), break_when_any_done=False)
    data[TEACHER_ACTION] = torch.tanh(data["state"][..., :3])  # any fixed map of the state
    recurrent = cfg.actor.name == "lstm"
    update = LOSSES.get(cfg.algo.loss)(
        actor, state_size(cfg.state), env.action_spec, cfg, recurrent
    )
    return cfg, actor, update, data


def critic_loss(update, batch) -> float:
    losses = update.loss.value_loss(batch) if hasattr(update.loss, "value_loss") else None
    if losses is None:
        losses = update.loss.loss_value(batch)
    return float(losses[0].detach())


@pytest.mark.parametrize("algo", ["ddpg", "td3"])
@pytest.mark.slow
def test_an_update_lowers_the_critic_loss_on_a_fixed_batch(algo):
    cfg, _, update, data = transitions(f"algo={algo}", "optim.lr_critic=1e-4")
    batch = data.reshape(-1)
    torch.manual_seed(1)  # TD3's target smoothing noise: the same draw before and after
    before = critic_loss(update, batch)
    update(batch)
    torch.manual_seed(1)
    assert critic_loss(update, batch) < before


@pytest.mark.slow
def test_ddpg_targets_move_by_tau():
    cfg, _, update, data = transitions()
    loss = update.loss
    update(data.reshape(-1))  # targets start as copies; move the online weights once first
    online_actor = loss.actor_network_params.clone()
    online_critic = loss.value_network_params.clone()
    targets_before = (
        loss.target_actor_network_params.clone(),
        loss.target_value_network_params.clone(),
    )
    update.targets.step()
    tau = cfg.algo.tau
    for online, before, after in (
        (online_actor, targets_before[0], loss.target_actor_network_params),
        (online_critic, targets_before[1], loss.target_value_network_params),
    ):
        expected = before.apply(lambda b, o: (1 - tau) * b + tau * o, online)
        moved = 0
        for key, value in expected.items(True, True):
            torch.testing.assert_close(after[key], value)
            moved += not torch.equal(before[key], online[key])
        assert moved >= 4  # weights and biases of every layer (constant buffers stay)


@pytest.mark.slow
def test_td3_moves_the_actor_and_its_target_only_every_policy_delay_updates():
    cfg, actor, update, data = transitions("algo=td3", "algo.policy_delay=3")
    batch = data.reshape(-1)
    loss = update.loss
    moved = []
    for _ in range(6):
        actor_before = loss.actor_network_params.clone()
        target_before = loss.target_actor_network_params.clone()
        critic_before = loss.qvalue_network_params.clone()
        losses = update(batch)
        actor_moved = any(
            not torch.equal(actor_before[k], v)
            for k, v in loss.actor_network_params.items(True, True)
        )
        target_moved = any(
            not torch.equal(target_before[k], v)
            for k, v in loss.target_actor_network_params.items(True, True)
        )
        assert actor_moved == target_moved == ("loss_actor" in losses)
        assert any(
            not torch.equal(critic_before[k], v)
            for k, v in loss.qvalue_network_params.items(True, True)
        )  # the critics move every update
        moved.append(actor_moved)
    assert moved == [True, False, False, True, False, False]


@pytest.mark.slow
def test_td3_state_resumes_its_delay_count():
    _, _, update, data = transitions("algo=td3")
    update(data.reshape(-1))
    _, _, again, _ = transitions("algo=td3")
    again.load_state_dict(update.state_dict())
    assert again.updates == 1 and "loss_actor" not in again(data.reshape(-1))


@pytest.mark.slow
def test_behaviour_cloning_brings_the_actor_to_the_teachers_actions():
    cfg, actor, update, data = transitions("algo=bc", "optim.lr_actor=1e-3")
    batch = data.reshape(-1)
    first = update(batch)["loss_bc"]
    for _ in range(200):
        last = update(batch)["loss_bc"]
    assert last < 0.2 * first
    with torch.no_grad():
        error = actor(batch.clone())["action"] - batch[TEACHER_ACTION]
    assert float(error.pow(2).mean()) == pytest.approx(last, rel=0.5)


@pytest.mark.slow
def test_behaviour_cloning_with_bc_tau_deploys_the_moving_average_and_resumes_it():
    cfg, actor, update, data = transitions("algo=bc", "algo.bc_tau=0.25")
    batch = data.reshape(-1)
    expected = None
    for _ in range(4):
        update(batch)
        weights = {k: v.detach().clone() for k, v in actor.state_dict().items()}
        expected = (
            weights
            if expected is None
            else {k: expected[k] + 0.25 * (weights[k] - expected[k]) for k in weights}
        )
    deployed = update.target_actor().state_dict()
    for key, value in expected.items():
        torch.testing.assert_close(deployed[key], value)
    assert any(not torch.equal(deployed[k], v) for k, v in actor.state_dict().items())
    _, _, again, _ = transitions("algo=bc", "algo.bc_tau=0.25")
    again.load_state_dict(update.state_dict())
    for key, value in again.target_actor().state_dict().items():
        torch.testing.assert_close(value, deployed[key])


@pytest.mark.slow
def test_a_bc_tau_outside_zero_one_says_so():
    with pytest.raises(ValueError, match=r"algo.bc_tau=1.5 must be in \(0, 1\]"):
        transitions("algo=bc", "algo.bc_tau=1.5")


@pytest.mark.parametrize("algo", ["ddpg", "td3"])
@pytest.mark.slow
def test_a_bc_weight_adds_the_cloning_term_to_the_rl_loss(algo):
    _, _, update, data = transitions(f"algo={algo}", "algo.bc_weight=2.5")
    losses = update(data.reshape(-1))
    assert losses["loss_bc"] > 0 and math.isfinite(losses["loss_actor"])


@pytest.mark.slow
def test_behaviour_cloning_without_a_teacher_says_so():
    _, _, update, data = transitions("algo=bc")
    with pytest.raises(ValueError, match="needs a teacher in the loop"):
        update(data.reshape(-1).exclude(TEACHER_ACTION))


@pytest.mark.parametrize("algo", ["ddpg", "td3", "bc"])
@pytest.mark.slow
def test_an_lstm_update_runs_on_sub_trajectories(algo):
    cfg, _, update, data = transitions("actor=lstm", f"algo={algo}")
    buffer = ReplayBuffer(1000, 64, slice_len=16)
    data["collector", "traj_ids"] = (
        torch.cumsum(data["is_init"].squeeze(-1).long(), 1) + 10 * torch.arange(2)[:, None]
    )
    buffer.extend(data)
    batch = buffer.sample()
    assert batch.shape == (4, 16)
    ids, steps = batch["collector", "traj_ids"], batch["step_count"].squeeze(-1)
    assert torch.all(ids == ids[:, :1]) and torch.all(steps.diff(dim=1) == 1)  # consecutive
    losses = update(batch)
    assert all(math.isfinite(value) for value in losses.values())


def test_an_unknown_loss_names_the_valid_ones():
    with pytest.raises(ValueError, match="algo.loss='sac' is not available; choose one of bc,"):
        LOSSES.get("sac")


def cloning_batch(pieces: int = 8, steps: int = 16) -> TensorDict:
    """Sub-trajectories of the default LSTM actor's inputs and a teacher's actions."""
    size = state_size(train_config().state)
    return TensorDict(
        {
            "state": torch.randn(pieces, steps, size),
            "recurrent_state_h": torch.randn(pieces, steps, 1, 128),
            "recurrent_state_c": torch.randn(pieces, steps, 1, 128),
            "is_init": torch.zeros(pieces, steps, 1, dtype=torch.bool),
            TEACHER_ACTION: torch.rand(pieces, steps, 3) * 2 - 1,
        },
        [pieces, steps],
    )


def test_cloning_on_plain_tensors_gives_the_actors_loss_and_gradients_bit_for_bit():
    cfg = train_config()
    torch.manual_seed(0)
    actor = build_actor(cfg.actor, state_size(cfg.state), 3)
    plain = PlainActor(actor, sequences=True)
    batch = cloning_batch()
    batch["is_init"][:, 0] = torch.rand(8, 1) < 0.5  # episodes may start at a piece's first step

    def loss_and_gradients(plain_actor):
        actor.zero_grad()
        with set_recurrent_mode(True):
            loss = behaviour_cloning_loss(actor, batch, plain_actor)
        loss.backward()
        return loss.detach(), [p.grad.clone() for p in actor.parameters()]

    (loss, gradients), (plain_loss, plain_gradients) = map(loss_and_gradients, (None, plain))
    assert torch.equal(plain_loss, loss)
    assert all(map(torch.equal, plain_gradients, gradients))
    assert not starts_inside(batch["is_init"])
    batch["is_init"][3, 7] = True  # an episode starting inside a piece: TorchRL splits it
    assert starts_inside(batch["is_init"])
    split, plain_split = map(loss_and_gradients, (None, plain))
    assert torch.equal(plain_split[0], split[0]) and not torch.equal(split[0], loss)
