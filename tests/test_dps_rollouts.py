"""Batched open-loop roll-outs agree with the env, step for step and throw for throw."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from jugglerl.commands import ViaPointCommand, load_command
from jugglerl.dps.distribution import sample_commands
from jugglerl.dps.params import ViaPointConstraints
from jugglerl.dps.rollouts import CommandRollouts
from jugglerl.policies.command import CommandPolicy
from jugglerl.policies.episodes import run_episode
from jugglerl_envs import JuggleEnv


def perturbed_experts(env: JuggleEnv, count: int) -> list[ViaPointCommand]:
    """Samples around the expert from DPS's search distribution (the paper's stds)."""
    constraints = ViaPointConstraints.from_model(env.model, 1.0, 5.0, 0.1)
    return sample_commands(load_command("expert"), count, constraints, seed=1)


@pytest.mark.slow
def test_batched_throws_and_drops_equal_the_envs():
    env = JuggleEnv(duration=20.0, reset_noise=0.01)
    commands = [load_command("expert"), *perturbed_experts(env, 9)]
    seeds = list(range(len(commands)))
    with CommandRollouts(env, nthread=2) as rollouts:
        results = rollouts.evaluate(commands, seeds)
    reference = [
        run_episode(env, CommandPolicy(command), seed=seed)
        for command, seed in zip(commands, seeds, strict=True)
    ]
    assert results.throws.tolist() == [m.throws for m in reference]
    drops = [np.nan if m.time_to_drop is None else m.time_to_drop for m in reference]
    assert np.allclose(results.time_to_drop, drops, equal_nan=True)
    assert len(set(results.throws.tolist())) >= 3  # the commands differ: the check discriminates
    assert np.isnan(results.time_to_drop).sum() not in (0, len(commands))


def test_rate_limited_controls_are_the_setpoints_the_env_applies():
    env = JuggleEnv(gravity=-9.81, joint_speed_limit=3.14159, duration=4.0)
    command = load_command("expert")
    policy = CommandPolicy(command)
    observation, info = env.reset(seed=0)
    applied = []
    for _ in range(200):
        observation, *_, info = env.step(policy.act(observation, info["time"]))
        applied.append(env.data.ctrl.copy())
    with CommandRollouts(env, nthread=1) as rollouts:
        controls = rollouts.controls([command])[0]
    at_env_steps = controls[env.frame_skip - 1 :: env.frame_skip]
    assert np.array_equal(at_env_steps, np.array(applied))
    assert np.abs(np.diff(controls[:, :3], axis=0)).max() <= 3.14159 * 0.002 + 1e-12


def test_one_seed_per_command():
    env = JuggleEnv(duration=1.0)
    commands = perturbed_experts(env, 3)
    rollouts = CommandRollouts(env, nthread=1)
    with rollouts, pytest.raises(ValueError, match="2 seeds for 3 commands"):
        rollouts.evaluate(commands, seeds=[0, 1])


@pytest.mark.slow
def test_bench_dps_prints_the_ratio_last():
    script = Path(__file__).resolve().parents[1] / "scripts" / "benchmarks" / "bench_dps.py"
    result = subprocess.run(
        [sys.executable, str(script), "--commands", "2", "--duration", "1", "--repeats", "1"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    last = result.stdout.strip().splitlines()[-1]
    assert last.startswith("ratio ours / bare") and float(last.split()[-1]) > 0


@pytest.mark.slow
def test_hold_sweep_prints_a_row_per_cut():
    script = Path(__file__).resolve().parents[1] / "scripts" / "studies" / "hold_sweep.py"
    arguments = ["--duration", "6", "--seeds", "2", "--cuts", "0,0.3", "--lead-in", "0.5"]
    result = subprocess.run(
        [sys.executable, str(script), *arguments], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert "lead-in 0.5 s" in result.stdout
    rows = [line.split() for line in result.stdout.strip().splitlines()[2:]]
    assert [row[:2] for row in rows] == [["0.000", "2.177"], ["0.300", "1.877"]]
    assert int(rows[0][2]) >= 2  # dps_best throws from the standard start within 6 s
    refused = subprocess.run(
        [sys.executable, str(script), "--cuts", "2"], capture_output=True, text=True, timeout=120
    )
    assert refused.returncode == 1
    assert "cannot cut 2.0 s from via-point 0" in refused.stderr
