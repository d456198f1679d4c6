"""The ball clock (``jugglerl.state.ball_clock``): the teacher's phase, made observable."""

from dataclasses import replace

import pytest
import torch
from cli import train_config
from tensordict import TensorDict
from torchrl.envs.utils import check_env_specs

from jugglerl.batch.env_stack import make_env
from jugglerl.networks.actors import build_actor
from jugglerl.policies.loading import load_policy
from jugglerl.state.ball_clock import LOCK, BallClock
from jugglerl.state.timestamp import phase_features
from jugglerl.state.transforms import state_size
from jugglerl_envs import JuggleEnv


def clock_step(clock: BallClock, observation, time, first, memory: dict) -> TensorDict:
    """One step of ``clock`` on a batch of one with its ``memory``, as ``ActorPolicy`` runs it."""
    data = TensorDict(
        {
            "observation": torch.as_tensor(observation).reshape(1, -1),
            "time": torch.tensor([float(time)], dtype=torch.float64),
            "is_init": torch.tensor([[bool(first)]]),
            "state": torch.zeros(1, 0),
            **memory,
        },
        batch_size=[1],
    )
    data = clock(data)
    memory.update({key: data.get(key) for key in clock.carried_keys})
    return data


@pytest.mark.slow
def test_the_clock_is_the_phase_of_a_teacher_that_resets_at_each_lock():
    env = JuggleEnv(duration=20.0)
    teacher = load_policy("closed_loop", env)
    teacher.gains = replace(teacher.gains, phase_gain=1.0)  # the phase reset at each lock
    cycle = teacher.command.cycle
    clock = BallClock(period=cycle)
    observation, info = env.reset(seed=0)
    teacher.reset()
    memory, locks = {}, set()
    for step in range(int(20.0 / env.dt)):
        action = teacher.act(observation, info["time"])
        lock = float(clock_step(clock, observation, info["time"], step == 0, memory)[LOCK][0])
        if lock > 0:  # after the first lock (the dropped ball's fall into the cup)
            locks.add(lock)
            expected = teacher.gains.land_phase + info["time"] - lock
            gap = (teacher.phase - expected + cycle / 2) % cycle - cycle / 2
            assert abs(gap) < 1e-9, (step, teacher.phase, expected)
        observation, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    assert info["throws"] >= 8 and len(locks) >= 8  # thrown, caught and locked again and again


def test_the_clock_starts_at_each_episode_and_interpolates_the_crossing():
    clock = BallClock(period=2.0, height=0.2)
    memory = {}
    # ball 0.3 m above the cup, falling at 1 m/s; at 0.2 s 0.1 m: it passed 0.2 m at 0.1 s
    above, below = torch.zeros(18, dtype=torch.float64), torch.zeros(18, dtype=torch.float64)
    above[8], above[11] = 0.3, -1.0
    below[8], below[11] = 0.1, -1.0
    start = clock_step(clock, above, 0.0, True, memory)
    assert float(start[LOCK][0]) == 0.0
    crossed = clock_step(clock, below, 0.2, False, memory)
    assert float(crossed[LOCK][0]) == pytest.approx(0.2 - 0.1 / 1.0)
    torch.testing.assert_close(
        crossed["state"][0], phase_features(torch.tensor(0.1), 2.0, 1).float()
    )
    assert not bool(crossed["ball_clock_armed"][0])  # the same fall does not lock twice
    clock_step(clock, below, 0.3, False, memory)
    assert float(memory[LOCK][0]) == pytest.approx(0.1)
    restarted = clock_step(clock, above, 0.0, True, memory)  # a new episode: a new clock
    assert float(restarted[LOCK][0]) == 0.0


@pytest.mark.slow
def test_in_the_batched_stack_each_env_keeps_its_own_clock_across_resets():
    cfg = train_config(
        "algo=ddpg",
        "env.duration=3",
        "state.norm_frames=200",
        "collector.num_envs=2",
        "state.ball_clock=true",
        "state.harmonics=2",
    )
    torch.manual_seed(0)
    env = make_env(cfg, 2)
    check_env_specs(env)
    size = state_size(cfg.state)
    assert env.observation_spec["state"].shape[-1] == size == 18 + 5 + 4
    env.set_seed(0)
    data = env.rollout(400, build_actor(cfg.actor, size, 3), break_when_any_done=False)
    assert data["next", "done"].any()  # episodes of 3 s: several resets inside
    clock = BallClock(cfg.state.period, harmonics=2, height=cfg.state.ball_clock_height)
    for index in range(2):
        memory = {}
        for step in range(data.shape[1]):
            row = data[index, step]
            replay = clock_step(clock, row["observation"], row["time"], row["is_init"], memory)
            torch.testing.assert_close(replay["state"][0], row["state"][-4:])
