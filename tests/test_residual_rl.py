"""Residual RL's parts: a correction on a frozen actor, n-step targets, the critic ensemble's
target, the pessimistic actor objective, perturbed training envs, and a run started from a
shipped actor."""

import re

import pytest
import torch
from cli import train_config
from tensordict import TensorDict
from test_losses import transitions
from test_offpolicy_training import TINY

from jugglerl.networks.actors import build_actor
from jugglerl.networks.actors.correction import BASE_ACTION, Correction
from jugglerl.offpolicy.init_actor import load_base_weights
from jugglerl.offpolicy.n_step import n_step_returns
from jugglerl.offpolicy.training import OffPolicyTraining
from jugglerl.policies.actor_file import read_actor_weights
from jugglerl.state.transforms import state_size

CORRECTED = [
    "actor=lstm",
    "++actor.correction.hidden=[16]",
    "++actor.correction.max_correction=0.05",
]


def correction_of(actor) -> Correction:
    return next(m for m in actor.modules() if isinstance(m, Correction))


@pytest.mark.slow
def test_a_corrected_actor_starts_exactly_at_its_base():
    cfg = train_config(*CORRECTED)
    size = state_size(cfg.state)
    torch.manual_seed(0)
    corrected = build_actor(cfg.actor, size, 3)
    base = build_actor(train_config("actor=lstm").actor, size, 3)
    base.load_state_dict(corrected.state_dict(), strict=False)
    states = TensorDict(
        {
            "state": torch.randn(64, size),
            "recurrent_state_h": torch.randn(64, 1, 128),
            "recurrent_state_c": torch.randn(64, 1, 128),
            "is_init": torch.zeros(64, 1, dtype=torch.bool),
        },
        [64],
    )
    ours, theirs = corrected(states.clone()), base(states.clone())
    assert torch.equal(ours["action"], theirs["action"])
    assert torch.equal(ours[BASE_ACTION], theirs["action"])


def test_a_correction_leaves_the_runs_random_stream_and_base_weights_as_without_it():
    """So the cloning stages of a run with a correction repeat those of a run without."""
    draws = []
    for overrides in (CORRECTED, ["actor=lstm"]):
        cfg = train_config(*overrides)
        torch.manual_seed(0)
        actor = build_actor(cfg.actor, state_size(cfg.state), 3)
        draws.append((actor.state_dict(), torch.rand(4)))
    (corrected, after_corrected), (plain, after_plain) = draws
    assert torch.equal(after_corrected, after_plain)
    for key, value in plain.items():
        assert torch.equal(corrected[key], value), key


def test_the_correction_stays_within_its_bound_and_reaches_it():
    cfg = train_config(*CORRECTED)
    actor = build_actor(cfg.actor, state_size(cfg.state), 3)
    body = correction_of(actor).body
    torch.nn.init.normal_(body[-1].weight, std=10.0)
    size = state_size(cfg.state)
    data = actor(
        TensorDict(
            {
                "state": torch.randn(256, size),
                "recurrent_state_h": torch.zeros(256, 1, 128),
                "recurrent_state_c": torch.zeros(256, 1, 128),
                "is_init": torch.ones(256, 1, dtype=torch.bool),
            },
            [256],
        )
    )
    step = (data["action"] - data[BASE_ACTION]).abs()
    inside = data[BASE_ACTION].abs() < 0.9  # away from the [-1, 1] clip
    assert step.max() <= 0.05 + 1e-6 and step[inside].max() > 0.049


@pytest.mark.parametrize(
    "loss", [["algo=ddpg"], ["algo=td3"], ["algo=td3", "algo.pessimism=1.0"]], ids=str
)
@pytest.mark.slow
def test_updates_of_the_correction_never_move_the_base(loss):
    _, actor, update, data = transitions(
        *loss, *CORRECTED, "+optim.trains=correction", "optim.lr_actor=1e-2"
    )
    correction = {id(p) for p in correction_of(actor).parameters()}
    before = {name: p.detach().clone() for name, p in actor.named_parameters()}
    batch = data[:, :16]  # 2 sub-trajectories of 16 steps
    for _ in range(4):
        update(batch)
    moved = {name for name, p in actor.named_parameters() if not torch.equal(p, before[name])}
    owned = {name for name, p in actor.named_parameters() if id(p) in correction}
    assert moved and moved <= owned


@pytest.mark.slow
def test_a_stage_training_the_correction_needs_one():
    with pytest.raises(ValueError, match="trains=correction needs an actor with actor.correction"):
        transitions("actor=lstm", "+optim.trains=correction")


def test_n_step_returns_on_a_hand_made_trajectory():
    steps = 6
    done = torch.zeros(1, steps, 1, dtype=torch.bool)
    done[0, 3] = True  # the episode ends with step 3; a new one starts at step 4
    batch = TensorDict(
        {
            "position": torch.arange(steps).view(1, steps, 1).float(),
            "next": {
                "position": torch.arange(1, steps + 1).view(1, steps, 1).float(),
                "reward": torch.arange(1.0, steps + 1).view(1, steps, 1),
                "done": done,
                "terminated": done.clone(),
            },
        },
        [1, steps],
    )
    out = n_step_returns(batch, 3, 0.5)
    # t=0: 1 + 0.5 * 2 + 0.25 * 3; t=1 meets the end at step 3; t=4 meets the batch's end
    expected = [2.75, 2 + 1.5 + 1, 3 + 2, 4, 5 + 3, 6]
    assert out["next", "reward"].flatten().tolist() == expected
    assert out["steps_to_next_obs"].flatten().tolist() == [3, 3, 2, 1, 2, 1]
    assert out["next", "position"].flatten().tolist() == [3, 4, 4, 4, 6, 6]
    assert out["next", "terminated"].flatten().tolist() == [0, 1, 1, 1, 0, 0]


def test_a_one_step_batch_only_gains_its_step_count():
    batch = TensorDict({"next": {"reward": torch.ones(2, 5, 1)}}, [2, 5])
    out = n_step_returns(batch, 1, 0.9)
    assert out["steps_to_next_obs"].unique().tolist() == [1]
    assert torch.equal(out["next", "reward"], torch.ones(2, 5, 1))


@pytest.mark.parametrize("algo", ["ddpg", "td3"])
@pytest.mark.slow
def test_the_critic_target_is_the_documented_one(algo):
    """DDPG: ``r + γ^m (1 - terminated) Q'(s', μ'(s'))``; TD3 with an ensemble of 3 critics and
    no smoothing noise: the same with the minimum over the 3 target critics."""
    ensemble = ["critic.ensemble=3", "algo.policy_noise=0.0"] if algo == "td3" else []
    _, actor, update, data = transitions(f"algo={algo}", "critic.layer_norm=true", *ensemble)
    batch = n_step_returns(data[:, :16].clone(), 4, 0.9).reshape(-1)
    batch["next", "terminated"][::5] = True
    loss = update.loss
    loss.make_value_estimator(gamma=0.9)
    _, info = loss.value_loss(batch.clone()) if algo == "td3" else loss.loss_value(batch.clone())

    following = batch["next"].clone()
    with loss.target_actor_network_params.to_module(loss.actor_network):
        following = loss.actor_network(following)
    if algo == "ddpg":
        values = _q(loss.value_network, loss.target_value_network_params, following)
    else:
        params = loss.target_qvalue_network_params
        assert params.batch_size[0] == 3
        values = torch.stack([_q(loss.qvalue_network, params[k], following) for k in range(3)])
        values = values.min(0).values
    reward = batch["next", "reward"].squeeze(-1)
    alive = (~batch["next", "terminated"]).squeeze(-1).float()
    discount = 0.9 ** batch["steps_to_next_obs"].squeeze(-1).float()
    torch.testing.assert_close(info["target_value"], reward + discount * alive * values)


@pytest.mark.slow
def test_the_pessimistic_actor_objective_is_the_ensembles_mean_less_its_spread():
    _, actor, update, data = transitions("algo=td3", "critic.ensemble=3", "algo.pessimism=2.0")
    batch = data.reshape(-1)
    objective = update.ensemble_objective(batch)
    loss = update.loss
    acted = actor(batch.select(*actor.in_keys, strict=False).clone())
    params = loss.qvalue_network_params
    values = torch.stack([_q(loss.qvalue_network, params[k], acted) for k in range(3)])
    torch.testing.assert_close(objective, values.mean(0) - 2.0 * values.std(0))
    objective.mean().backward()  # the actor's gradient only: the critics stay as they are
    assert all(p.grad is None for p in params.values(True, True))
    assert all(p.grad is not None for p in loss.actor_network_params.values(True, True))
    with pytest.raises(ValueError, match=re.escape("algo.pessimism=-1.0 must be >= 0 or null")):
        transitions("algo=td3", "algo.pessimism=-1.0")


def _q(network, params, data):
    with params.to_module(network):
        return network(data.clone())["state_action_value"].squeeze(-1)


def test_a_perturbed_stage_splits_its_envs_among_the_conditions(tmp_path):
    conditions = "{noisy: {action_noise: 0.01}, kicked: {kick_rate: 1.0}}"
    perturbed = f"+algo.stages={{rl: {{perturbed: {conditions}}}}}"
    cfg = train_config(*TINY, "collector.num_envs=3", "collector.frames_per_batch=129", perturbed)
    training = OffPolicyTraining(cfg, tmp_path)
    settings = [training.env.base_env.batch.settings.env(i) for i in range(3)]
    noise = [env["action_noise"] for env in settings]
    kicks = [env["kick_rate"] for env in settings]
    assert (noise, kicks) == ([0.0, 0.01, 0.0], [0.0, 0.0, 1.0])
    training.close()


def test_a_run_starts_from_a_shipped_actor(tmp_path):
    tiny = [o for o in TINY if not o.startswith("algo=")]
    tiny += ["actor=lstm", "+experiment=finetune", "replay_buffer.slice_len=16"]
    cfg = train_config(*tiny, "collector.total_frames=128")
    training = OffPolicyTraining(cfg, tmp_path)
    shipped = read_actor_weights("lstm_juggler")
    for key, value in shipped["policy"].items():
        assert torch.equal(training.actor.state_dict()[key], value)
    encoder = training.actor_policy(training.actor).deployed.encoder
    assert torch.equal(encoder.loc, shipped["normalisation"]["loc"])
    training.close()
    other = train_config(*tiny, "state.period=3.0")
    with pytest.raises(ValueError, match="init_actor=lstm_juggler: its state differs in period"):
        OffPolicyTraining(other, tmp_path)


def test_an_actor_without_a_correction_starts_from_one_carrying_a_zero_or_refuses_a_trained_one():
    """``lstm_centred`` was trained with the rl stage's zero correction on top: the default
    actor (none) takes its base weights and leaves the correction out, unless it has trained."""
    cfg = train_config()
    assert "correction" not in cfg.actor
    actor = build_actor(cfg.actor, state_size(cfg.state), 3)
    shipped = read_actor_weights("lstm_centred")["policy"]
    carried = [key for key in shipped if key not in actor.state_dict()]
    assert carried and all(key.startswith("module.2.module.body.") for key in carried)
    load_base_weights(actor, shipped, "lstm_centred")
    for key, value in actor.state_dict().items():
        assert torch.equal(value, shipped[key]), key
    trained = dict(shipped)
    last = max(carried, key=lambda key: int(key.split("body.")[1].split(".")[0]))
    trained[last] = torch.full_like(shipped[last], 1e-3)
    with pytest.raises(ValueError, match="init_actor=x: it carries a trained correction"):
        load_base_weights(actor, trained, "x")
