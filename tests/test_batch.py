"""``JuggleBatch``: each env of a batch plays bit for bit as a lone ``JuggleEnv``; partial resets,
saved states and the TorchRL env over it."""

import pickle

import numpy as np
import pytest
import torch
from hydra import compose, initialize
from omegaconf import OmegaConf

from jugglerl.batch.torchrl_env import JuggleBatchEnv
from jugglerl.policies.loading import load_policy
from jugglerl_envs import JuggleBatch, JuggleEnv

#: Eight envs under a mix of perturbations, one value per env.
MIXED = {
    "reset_noise": [0.0, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.01],
    "kick_rate": [0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.5],
    "kick_speed": [0.0, 0.0, 0.02, 0.0, 0.0, 0.0, 0.0, 0.02],
    "action_noise": [0.0, 0.0, 0.0, 0.003, 0.003, 0.0, 0.0, 0.003],
    "action_noise_correlation": [0.0, 0.0, 0.0, 0.0, 0.1, 0.0, 0.0, 0.0],
    "ball_noise": [0.0, 0.0, 0.0, 0.0, 0.0, 0.001, 0.0, 0.001],
    "ball_latency": [0, 0, 0, 0, 0, 1, 0, 0],
    "servo_gain": [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.95, 1.0],
}
SEED = 5


def preset(name: str) -> dict:
    with initialize(version_base="1.3", config_path="../configs"):
        cfg = compose(config_name="evaluate", overrides=[f"env={name}"])
    return OmegaConf.to_container(cfg.env, resolve=True)


def play_batch(arguments: dict, policy: str, num_envs: int) -> list[dict]:
    """Each env's first episode in one batch, a copy of ``policy`` acting on each row."""
    batch = JuggleBatch(num_envs, **arguments)
    template = JuggleEnv(**{k: v for k, v in arguments.items() if k not in MIXED})
    policies = [load_policy(policy, template) for _ in range(num_envs)]
    observations, info = batch.reset(seed=SEED)
    episodes = [{"observation": [row], "reward": []} for row in observations]
    running = np.ones(num_envs, dtype=bool)
    while running.any():
        actions = np.stack(
            [p.act(o, t) for p, o, t in zip(policies, observations, info["time"], strict=True)]
        )
        observations, rewards, terminated, truncated, info = batch.step(actions)
        for env in np.flatnonzero(running):
            episode = episodes[env]
            episode["observation"].append(observations[env])
            episode["reward"].append(rewards[env])
            if terminated[env] or truncated[env]:
                episode["end"] = (terminated[env], truncated[env])
                episode["counts"] = (info["throws"][env], info["catches"][env])
                running[env] = False
    return episodes


def play_alone(arguments: dict, policy: str, seed: int) -> dict:
    env = JuggleEnv(**arguments)
    actor = load_policy(policy, env)
    observation, info = env.reset(seed=seed)
    episode = {"observation": [observation], "reward": []}
    done = False
    while not done:
        observation, reward, terminated, truncated, info = env.step(
            actor.act(observation, info["time"])
        )
        episode["observation"].append(observation)
        episode["reward"].append(reward)
        done = terminated or truncated
    episode["end"] = (terminated, truncated)
    episode["counts"] = (info["throws"], info["catches"])
    return episode


@pytest.mark.parametrize(
    ("env", "policy", "extra"),
    [("paper", "closed_loop", {}), ("earth", "earth_juggler", {}), ("paper", "two_balls", {})],
    ids=["paper", "earth", "two_balls"],
)
@pytest.mark.slow
def test_each_env_of_a_mixed_batch_plays_as_the_env_alone_bit_for_bit(env, policy, extra):
    arguments = {**preset(env), "duration": 30.0, "reward": "cradle", **extra}
    if policy == "two_balls":
        arguments["balls"] = 2
    batch = play_batch({**arguments, **MIXED}, policy, num_envs=8)
    ends = set()
    for env_index, played in enumerate(batch):
        alone = play_alone(
            {**arguments, **{k: v[env_index] for k, v in MIXED.items()}}, policy, SEED + env_index
        )
        for key in ("observation", "reward"):
            np.testing.assert_array_equal(played[key], alone[key], err_msg=f"env {env_index} {key}")
        assert played["end"] == alone["end"] and played["counts"] == alone["counts"]
        ends.add(played["end"])
    assert (False, True) in ends  # some env juggled to the time limit


def test_a_partial_reset_restarts_only_the_envs_it_names():
    batch, twin = (JuggleBatch(4, autoreset=False, reset_noise=0.01) for _ in range(2))
    for b in (batch, twin):
        b.reset(seed=0)
    hold = np.zeros((4, 3))
    for _ in range(30):
        batch.step(hold)
        twin.step(hold)
    observations, info = batch.reset(
        seed=[None, 7, None, None], options={"reset_mask": [0, 1, 0, 0]}
    )
    assert info["time"].tolist() == pytest.approx([0.6, 0.0, 0.6, 0.6])
    lone, _ = JuggleEnv(reset_noise=0.01).reset(seed=7)
    np.testing.assert_array_equal(observations[1], lone)
    for _ in range(20):
        after, *_ = batch.step(hold)
        expected, *_ = twin.step(hold)
    np.testing.assert_array_equal(after[[0, 2, 3]], expected[[0, 2, 3]])


def test_an_ended_env_waits_or_restarts_on_the_next_step():
    for autoreset in (False, True):
        batch = JuggleBatch(2, autoreset=autoreset, duration=[0.1, 1.0])
        batch.reset(seed=0)
        hold = np.zeros((2, 3))
        for _ in range(5):
            last, _, _, truncated, info = batch.step(hold)
        assert truncated.tolist() == [True, False] and info["time"][0] == pytest.approx(0.1)
        observations, rewards, terminated, truncated, info = batch.step(hold)
        if autoreset:  # a new episode, as Gymnasium's NEXT_STEP mode has it
            assert info["time"][0] == 0.0 and not truncated[0] and rewards[0] == 0
        else:  # it stays as it ended
            assert info["time"][0] == pytest.approx(0.1) and truncated[0]
            np.testing.assert_array_equal(observations[0], last[0])
        assert info["time"][1] == pytest.approx(0.12)


@pytest.mark.slow
def test_a_saved_batch_continues_bit_for_bit():
    """Saved mid-episode after 777 steps, restored into a new batch: the next 500 steps are the
    same, with kicks, noise, tracked balls and autoresets along the way."""
    arguments = {"duration": 12.0, "reward": "cradle", **MIXED}
    expert = load_policy("expert", JuggleEnv())  # open loop: its action depends on the time alone

    def play(batch, steps, info):
        played = []
        for _ in range(steps):
            actions = np.stack([expert.act(None, t) for t in info["time"]])
            played.append(batch.step(actions))
            info = played[-1][4]
        return played

    batch = JuggleBatch(8, **arguments)
    _, info = batch.reset(seed=1)
    info = play(batch, 777, info)[-1][4]
    saved = pickle.loads(pickle.dumps(batch.state_dict()))
    played = play(batch, 500, info)
    restored = JuggleBatch(8, **arguments)
    restored.load_state_dict(saved)
    replayed = play(restored, 500, info)
    for first, second in zip(played, replayed, strict=True):
        for a, b in zip(first[:4], second[:4], strict=True):
            np.testing.assert_array_equal(a, b)
        for key in first[4]:
            np.testing.assert_array_equal(first[4][key], second[4][key], err_msg=key)
    assert max(step[4]["kicks"].max() for step in played) > 0
    assert any(step[2].any() for step in played) and any(step[3].any() for step in played)


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"num_envs": 0}, "num_envs=0 is out of range"),
        ({"num_envs": 3, "reset_noise": [0.0, 0.01]}, "reset_noise: 2 values for a batch of 3"),
        ({"num_envs": 2, "reset_noise": [0.0, 0.9]}, "reset_noise[1]=0.9 is out of range"),
        ({"num_envs": 2, "balls": [1, 2]}, "balls=[1, 2]: one value for every env of a batch"),
        ({"num_envs": 2, "threads": 0}, "threads=0 is out of range"),
    ],
)
def test_bad_arguments_say_what_is_wrong_in_one_line(arguments, message):
    with pytest.raises(ValueError, match=None) as error:
        JuggleBatch(**arguments)
    assert str(error.value).startswith(message) and "\n" not in str(error.value)


def test_an_action_of_the_wrong_shape_is_refused_in_one_line():
    batch = JuggleBatch(2)
    batch.reset(seed=0)
    with pytest.raises(ValueError) as error:
        batch.step(np.zeros((3, 3)))
    assert str(error.value) == (
        "actions of shape (3, 3): this batch takes (2, 3) (2 envs of 3 servos)"
    )


def test_the_torchrl_env_passes_its_spec_check_and_ends_episodes_apart():
    from torchrl.envs.utils import check_env_specs

    env = JuggleBatchEnv(2, duration=[1.0, 30.0], gravity=-9.81)
    check_env_specs(env)
    env.set_seed(0)
    away = torch.tensor([[0.0, 0.0, 0.0], [0.8, 0.0, 0.0]])  # env 1 pans its cup from the ball
    state = env.reset()
    ends = {}
    for step in range(60):
        state = env.step(state.set("action", away))["next"]
        for env_index in (0, 1):
            if state["done"][env_index] and env_index not in ends:
                ends[env_index] = (
                    step,
                    bool(state["terminated"][env_index]),
                    bool(state["truncated"][env_index]),
                )
    assert ends[0] == (49, False, True)  # the time limit: truncated only
    assert ends[1][1:] == (True, False) and ends[1][0] < 49  # the drop: terminated
    assert state["reward"].shape == (2, 1) and state["time"].dtype == torch.float64
