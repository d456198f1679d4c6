"""The off-policy stack's modules: timestamp transform, env stack, exploration, actors, buffer."""

from dataclasses import replace

import numpy as np
import pytest
import torch
from cli import train_config
from tensordict import TensorDict
from tensordict.nn import TensorDictSequential
from torchrl.data import Bounded
from torchrl.envs.utils import ExplorationType, check_env_specs, set_exploration_type
from torchrl.modules import set_recurrent_mode

from jugglerl.batch.env_stack import make_env, normalisation
from jugglerl.commands import load_command
from jugglerl.networks.actors import build_actor
from jugglerl.networks.reference import CommandReference
from jugglerl.offpolicy.buffer import ReplayBuffer
from jugglerl.offpolicy.exploration import make_exploration
from jugglerl.offpolicy.exploration.gaussian import CentredGaussianNoise, CommandCentre
from jugglerl.offpolicy.teacher import TEACHER_ACTION
from jugglerl.offpolicy.who_acts import WhoActs
from jugglerl.policies.actor import ActorPolicy
from jugglerl.state.timestamp import TimestampFeatures, time_features
from jugglerl.state.transforms import state_size
from jugglerl_envs import JuggleEnv

SMALL = ["algo=ddpg", "env.duration=6", "state.norm_frames=200", "collector.num_envs=2"]


def stack(*overrides: str):
    """A small env stack (2 envs) with the actor of ``overrides``, its recurrent state primed."""
    cfg = train_config(*SMALL, *overrides)
    torch.manual_seed(0)
    env = make_env(cfg, cfg.collector.num_envs)
    actor = build_actor(cfg.actor, state_size(cfg.state), 3)
    env.set_seed(0)
    return cfg, env, actor


# --- timestamp ----------------------------------------------------------------------------------
def test_time_features_are_elapsed_fraction_and_cycle_phase():
    times = torch.tensor([0.0, 0.75, 1.5, 3.0, 60.0])
    features = time_features(times, duration=120.0, period=3.0)
    expected = [
        [0.0, 0.0, 1.0],
        [0.75 / 120, 1.0, 0.0],
        [1.5 / 120, 0.0, -1.0],
        [3.0 / 120, 0.0, 1.0],
        [0.5, 0.0, 1.0],
    ]
    torch.testing.assert_close(features, torch.tensor(expected), atol=1e-5, rtol=0)


@pytest.mark.slow
def test_timestamp_transform_appends_the_env_time_features():
    cfg, env, actor = stack()
    check_env_specs(env)
    assert env.observation_spec["state"].shape[-1] == 18 + 3
    data = env.rollout(400, actor, break_when_any_done=False)  # 8 s: resets inside
    assert data["next", "done"].any()
    time = data["next", "time"]
    assert time.dtype == torch.float64  # the env's own clock, as a teacher reads it
    torch.testing.assert_close(
        time, data["next", "step_count"].squeeze(-1) * 0.02, check_dtype=False
    )
    expected = time_features(time.float(), cfg.env.duration, cfg.state.period)
    torch.testing.assert_close(data["next", "state"][..., 18:], expected)


def test_the_stack_keeps_the_physical_observation_beside_the_state():
    _, env, _ = stack()
    data = env.rollout(20)
    raw = data["next", "observation"]
    assert raw.dtype == torch.float64 and raw.shape[-1] == 18
    norm = normalisation(env)
    torch.testing.assert_close(
        data["next", "state"][..., :18], (raw.float() - norm.loc) / norm.scale
    )


def test_timestamp_transform_rejects_a_zero_period():
    with pytest.raises(ValueError, match="period=0"):
        TimestampFeatures(duration=120.0, period=0.0)


def test_the_stack_without_timestamp_keeps_18_observations():
    _, env, _ = stack("state.timestamp=false")
    check_env_specs(env)
    assert env.observation_spec["state"].shape[-1] == 18


@pytest.mark.slow
def test_normalisation_standardises_the_fitting_steps():
    _, env, _ = stack()
    norm = normalisation(env)
    assert norm.loc.shape == norm.scale.shape == (18,)
    data = env.rollout(100)  # random actions, like the fit
    standardised = data["next", "state"][..., :18].reshape(-1, 18)
    assert standardised.mean(0).abs().max() < 1.5  # roughly centred on fresh random steps
    assert torch.all(standardised.std(0) < 5)


# --- exploration --------------------------------------------------------------------------------
def expert_noise(env: JuggleEnv, **kwargs) -> CentredGaussianNoise:
    settings = dict(
        sigma_init=0.05,
        sigma_end=0.01,
        expert_weight_init=1.0,
        expert_weight_end=0.0,
        annealing_frames=1000,
    )
    settings.update(kwargs)
    average = settings.pop("centre", "timed") == "average"
    return CentredGaussianNoise(CommandCentre(load_command("expert"), average), **settings)


def noisy_actions(noise, action: torch.Tensor, time: float, samples: int = 20000) -> torch.Tensor:
    data = TensorDict(
        {"action": action.expand(samples, 3).clone(), "time": torch.full((samples,), time)},
        batch_size=[samples],
    )
    with set_exploration_type(ExplorationType.RANDOM):
        return noise(data)["action"]


@pytest.mark.parametrize("time", [0.5, 1.7, 2.5, 4.6])
def test_expert_gaussian_is_centred_on_the_expert_setpoint_of_the_time(time):
    env = JuggleEnv()
    noise = expert_noise(env)
    torch.manual_seed(0)
    actions = noisy_actions(noise, torch.zeros(3), time)
    expert = torch.as_tensor(env.ctrl_to_action(load_command("expert").setpoints(time)))
    torch.testing.assert_close(actions.mean(0), expert, atol=3e-3, rtol=0)
    torch.testing.assert_close(actions.std(0), torch.full((3,), 0.05), atol=2e-3, rtol=0)


def test_expert_gaussian_average_centre_ignores_the_time():
    env = JuggleEnv()
    noise = expert_noise(env, centre="average")
    torch.manual_seed(0)
    early, late = (noisy_actions(noise, torch.zeros(3), t).mean(0) for t in (0.2, 1.7))
    times = np.linspace(0, 3.0, 3000, endpoint=False)
    average = env.ctrl_to_action(load_command("expert").setpoints(times)).mean(0)
    for mean in (early, late):
        torch.testing.assert_close(mean, torch.as_tensor(average), atol=3e-3, rtol=0)


def test_expert_gaussian_anneals_towards_the_actor():
    env = JuggleEnv()
    noise = expert_noise(env)
    actor_action = torch.tensor([0.1, -0.2, 0.3])
    expert = torch.as_tensor(env.ctrl_to_action(load_command("expert").setpoints(0.5)))
    noise.step(500)  # half way: weight 0.5, sigma 0.03
    assert noise.expert_weight == pytest.approx(0.5) and noise.sigma == pytest.approx(0.03)
    torch.manual_seed(1)
    actions = noisy_actions(noise, actor_action, 0.5)
    torch.testing.assert_close(actions.mean(0), (actor_action + expert) / 2, atol=2e-3, rtol=0)
    torch.testing.assert_close(actions.std(0), torch.full((3,), 0.03), atol=1.5e-3, rtol=0)
    noise.step(10_000)  # past the end: the actor's action with the final sigma
    actions = noisy_actions(noise, actor_action, 0.5)
    torch.testing.assert_close(actions.mean(0), actor_action, atol=1e-3, rtol=0)
    torch.testing.assert_close(actions.std(0), torch.full((3,), 0.01), atol=1e-3, rtol=0)


@pytest.mark.parametrize("acts", ["teacher", "student"])
def test_who_acts_moves_the_envs_with_its_action_and_white_noise(acts):
    student, teacher = torch.tensor([0.1, -0.2, 0.3]), torch.tensor([0.4, 0.5, -0.6])
    data = TensorDict(
        {"action": student.expand(20000, 3).clone(), TEACHER_ACTION: teacher.expand(20000, 3)},
        batch_size=[20000],
    )
    who = WhoActs(acts, noise=0.01)
    torch.manual_seed(0)
    with set_exploration_type(ExplorationType.RANDOM):
        actions = who(data.clone())["action"]
    acting = teacher if acts == "teacher" else student
    torch.testing.assert_close(actions.mean(0), acting, atol=3e-4, rtol=0)
    torch.testing.assert_close(actions.std(0), torch.full((3,), 0.01), atol=3e-4, rtol=0)
    still = WhoActs(acts, noise=0.0)
    with set_exploration_type(ExplorationType.RANDOM):
        assert torch.equal(still(data.clone())["action"][0], acting)  # exactly, without noise
    with set_exploration_type(ExplorationType.DETERMINISTIC):  # evaluation: the actor acts
        assert torch.equal(who(data.clone())["action"], data["action"])
    with pytest.raises(ValueError, match="acts=both must be one of teacher, student"):
        WhoActs("both", 0.0)


@pytest.mark.slow
def test_exploration_modules_pass_the_action_through_when_deterministic():
    cfg, env, actor = stack()
    for name in ("gaussian", "ou"):
        exploration_cfg = train_config(f"exploration={name}").exploration
        policy = TensorDictSequential(actor, make_exploration(exploration_cfg, env.action_spec))
        data = env.reset()
        with set_exploration_type(ExplorationType.DETERMINISTIC):
            explored = policy(data.clone())["action"]
            plain = actor(data.clone())["action"]
        torch.testing.assert_close(explored, plain, rtol=0, atol=0)
        with set_exploration_type(ExplorationType.RANDOM):
            assert not torch.equal(policy(data.clone())["action"], plain)


@pytest.mark.slow
def test_ou_noise_is_correlated_in_time_and_its_scale_anneals():
    cfg, env, actor = stack("exploration=ou", "exploration.annealing_frames=100")
    noise = make_exploration(cfg.exploration, env.action_spec)
    policy = TensorDictSequential(actor, noise)
    with set_exploration_type(ExplorationType.RANDOM), torch.no_grad():
        data = env.rollout(200, policy, break_when_any_done=False)
        clean = actor(data.clone())["action"]
    offsets = (data["action"] - clean)[0, :, 1].numpy()  # lift joint, first env
    lag_one = np.corrcoef(offsets[:-1], offsets[1:])[0, 1]
    assert lag_one > 0.8  # an Ornstein-Uhlenbeck process, not white noise
    assert float(noise.eps) == pytest.approx(1.0)
    noise.step(100)
    assert float(noise.eps) == pytest.approx(cfg.exploration.eps_end)


def test_unknown_exploration_centre_is_named():
    cfg = train_config("algo=ddpg", "exploration.centre=middle")
    with pytest.raises(ValueError, match="centre=middle is not one of timed, average$"):
        make_exploration(cfg.exploration, Bounded(-1.0, 1.0, shape=(3,)))


def test_unknown_exploration_names_the_valid_ones():
    cfg = train_config("algo=ddpg")
    cfg.exploration.name = "pink"
    with pytest.raises(ValueError, match="exploration='pink' is not available; choose one of"):
        make_exploration(cfg.exploration, Bounded(-1.0, 1.0, shape=(3,)))


# --- actors -------------------------------------------------------------------------------------
@pytest.mark.slow
def test_lstm_actor_gives_the_same_actions_step_by_step_and_in_recurrent_mode():
    _, env, actor = stack("actor=lstm", "env.duration=1")  # truncated every 50 steps
    with set_exploration_type(ExplorationType.DETERMINISTIC):
        data = env.rollout(120, actor, break_when_any_done=False)  # step by step
        replay = data.clone().exclude("action", "memory", "param")
        replay = replay.exclude(("next", "recurrent_state_h"), ("next", "recurrent_state_c"))
        with set_recurrent_mode(True):
            actor(replay)
    assert data["is_init"][:, 1:].any()  # an episode ended and restarted inside the sequence
    torch.testing.assert_close(replay["action"], data["action"], atol=1e-5, rtol=0)


@pytest.mark.parametrize(
    "actor_name, state",
    [("mlp", []), ("lstm", []), ("residual", []), ("lstm", ["state.ball_clock=true"])],
)
@pytest.mark.slow
def test_actor_policy_acts_as_the_actor_does_in_the_env_stack(actor_name, state):
    cfg, env, actor = stack(f"actor={actor_name}", "collector.num_envs=1", *state)
    with set_exploration_type(ExplorationType.DETERMINISTIC), torch.no_grad():
        data = env.rollout(100, actor)
    norm = normalisation(env)
    policy = ActorPolicy.of_actor(
        actor, cfg.state, cfg.actor, cfg.env.duration, norm.loc, norm.scale
    )
    plain = JuggleEnv(duration=cfg.env.duration, reward=cfg.env.reward)
    observation, info = plain.reset(seed=0)
    policy.reset()
    for step in range(len(data[0])):
        action = policy.act(observation, info["time"])
        np.testing.assert_array_equal(action, data["action"][0, step].numpy())
        observation, _, terminated, truncated, info = plain.step(action)
        if terminated or truncated:
            break


@pytest.mark.parametrize("actor_name", ["mlp", "lstm"])
@pytest.mark.slow
def test_actor_policy_acts_on_a_batch_as_the_env_stack_does(actor_name):
    cfg, env, actor = stack(
        f"actor={actor_name}", "collector.num_envs=4", "state.ball_clock=true", "env.duration=2"
    )
    with set_exploration_type(ExplorationType.DETERMINISTIC), torch.no_grad():
        data = env.rollout(80, actor)  # stops when an env is done: no env resets on the way
    assert data.shape[1] > 10
    norm = normalisation(env)
    policy = ActorPolicy.of_actor(
        actor, cfg.state, cfg.actor, cfg.env.duration, norm.loc, norm.scale
    )
    for step in range(data.shape[1]):  # four envs in one call, from what the stack observed
        row = data[:, step]
        actions = policy.act(row["observation"].numpy(), row["time"].numpy())
        np.testing.assert_array_equal(actions, row["action"].numpy())


def test_unknown_actor_is_named():
    cfg = train_config()
    cfg.actor.name = "gru"
    with pytest.raises(ValueError, match="actor='gru' is not available; choose one of lstm, mlp"):
        build_actor(cfg.actor, 21, 3)


# --- residual actor -----------------------------------------------------------------------------
@pytest.mark.parametrize("lead_in", [0.0, 0.5])
def test_command_reference_is_the_commands_action_at_each_time(lead_in):
    env, command = JuggleEnv(), replace(load_command("dps_best"), lead_in=lead_in)
    reference = CommandReference(command)
    times = torch.linspace(0.0, 3 * command.cycle, 1001, dtype=torch.float64)
    expected = env.ctrl_to_action(command.setpoints(times.numpy()))
    np.testing.assert_allclose(reference(times).numpy(), expected, atol=1e-6)
    assert reference(times.reshape(7, 143)).shape == (7, 143, 3)


def residual_actor(**settings):
    overrides = (f"actor.{k}={v}" for k, v in settings.items())
    cfg = train_config("actor=residual", *overrides)
    actor = build_actor(cfg.actor, 18, 3)
    reference = CommandReference(load_command(cfg.actor.command))
    torch.manual_seed(0)
    data = TensorDict(
        {"state": 3 * torch.randn(500, 18), "time": 10 * torch.rand(500)}, batch_size=[500]
    )
    return actor, reference(data["time"]), data


def test_an_untrained_residual_actor_plays_its_command():
    actor, reference, data = residual_actor()
    torch.testing.assert_close(actor(data)["action"], reference)


def test_the_residual_correction_is_bounded_by_max_correction():
    actor, reference, data = residual_actor(max_correction=0.2)
    with torch.no_grad():
        for parameter in actor.parameters():
            parameter.normal_(0.0, 1.0)
    correction = (actor(data)["action"] - reference).abs()
    inside = (reference.abs() < 0.75).all(-1)  # away from the [-1, 1] clip
    assert correction.max() <= 0.2 + 1e-6
    assert correction[inside].max() > 0.19  # the bound is reached, not just respected


def test_a_bad_max_correction_is_named():
    with pytest.raises(ValueError, match="actor.max_correction=0 must be in"):
        residual_actor(max_correction=0)


# --- buffer -------------------------------------------------------------------------------------
def test_replay_buffer_rejects_a_batch_that_is_not_whole_slices():
    with pytest.raises(
        ValueError, match="batch_size=100 must be a multiple of replay_buffer.slice_len=16"
    ):
        ReplayBuffer(1000, 100, slice_len=16)


def trajectory_batch(ids: list[list[int]]) -> TensorDict:
    """A collector batch ``[envs, time]`` whose steps carry the trajectory ids ``ids``."""
    traj = torch.tensor(ids)
    return TensorDict(
        {"observation": traj.float().unsqueeze(-1), "collector": {"traj_ids": traj}},
        batch_size=traj.shape,
    )


def test_a_slice_buffer_waits_for_a_piece_as_long_as_a_slice():
    buffer = ReplayBuffer(100, 8, slice_len=4)
    buffer.extend(trajectory_batch([[0, 0, 0], [1, 1, 1]]))
    buffer.extend(trajectory_batch([[0, 0, 0], [1, 1, 1]]))  # env 0's piece follows env 1's
    assert len(buffer) >= 8 and not buffer.ready and not buffer.sliceable
    buffer.extend(trajectory_batch([[2, 2, 3], [4, 4, 4]]))
    assert not buffer.ready
    buffer.extend(trajectory_batch([[5, 5, 5], [6, 6, 6]]))  # 4, 4, 5, 5, 5: a piece of 3
    assert not buffer.ready
    buffer.extend(trajectory_batch([[7, 8, 8], [8, 8, 8]]))  # 8 runs on for 5 steps
    assert buffer.ready
    sample = buffer.sample()
    assert sample.shape == (2, 4)
    assert (sample["collector", "traj_ids"] == 8).all()


def test_a_slice_buffer_of_one_env_joins_its_consecutive_batches():
    buffer = ReplayBuffer(100, 4, slice_len=4)
    buffer.extend(trajectory_batch([[5, 5, 5]]))
    assert not buffer.ready
    buffer.extend(trajectory_batch([[5, 5, 6]]))
    assert buffer.ready
    assert (buffer.sample()["observation"] == 5).all()


def test_the_residual_experiment_composes_its_groups():
    cfg = train_config("+experiment=residual")
    assert (cfg.actor.name, cfg.env.reward, cfg.state.timestamp) == ("residual", "juggle", False)
    assert cfg.env.kick_rate > 0 and cfg.env.reset_noise > 0
