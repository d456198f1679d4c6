"""The Gymnasium sanity check (``jugglerl.gym_check``): its env follows the juggling env's
conventions (actions in [-1, 1], a fall terminated, the time limit truncated), its evaluation
counts each episode to its end, its learners are the trainers' own, and its script trains,
reports and refuses bad input in one line."""

import json

import pytest
import torch
from cli import ROOT, run_script
from hydra import compose, initialize_config_dir
from tensordict import TensorDict

from jugglerl.gym_check.offpolicy import OffPolicyCheck
from jugglerl.gym_check.ppo import PPOCheck
from jugglerl.gym_check.task_env import first_episode_returns, make_task_env
from jugglerl.offpolicy.losses.td3 import TD3
from jugglerl.onpolicy.update import PPOUpdate


def check_config(*overrides: str):
    with initialize_config_dir(str(ROOT / "configs"), version_base="1.3"):
        return compose("gym_check", overrides=list(overrides))


def test_actions_in_minus_one_to_one_reach_the_tasks_bounds_and_are_clipped_there():
    env = make_task_env("InvertedPendulum-v5", 3)  # the cart's force is in [-3, 3]
    env.set_seed(0)
    state = env.reset()
    state["action"] = torch.tensor([[1.0], [-0.5], [7.0]])
    env.step(state)
    forces = [vector.unwrapped.data.ctrl[0] for vector in env.base_env._env.envs]
    assert forces == pytest.approx([3.0, -1.5, 3.0])
    assert env.action_spec.space.low.tolist() == [[-1.0]] * 3
    env.close()


def test_a_fall_is_terminated_and_the_time_limit_truncated():
    env = make_task_env("InvertedPendulum-v5", 1)
    env.set_seed(0)
    rollout = env.rollout(200, break_when_any_done=True)  # random pushes topple the pole
    last = rollout[0, -1]["next"]
    assert last["terminated"].item() and not last["truncated"].item()
    env.close()
    long_enough = make_task_env("Pusher-v5", 1)  # no fall: only the 100-step limit ends it
    long_enough.set_seed(0)
    rollout = long_enough.rollout(150, break_when_any_done=True)
    assert rollout.shape[-1] == 100
    assert rollout[0, -1]["next", "truncated"].item()
    assert not rollout[0, -1]["next", "terminated"].item()
    long_enough.close()


def test_the_state_is_the_observation_standardised():
    loc, scale = torch.arange(4.0), torch.full((4,), 2.0)
    env = make_task_env("InvertedPendulum-v5", 2, loc, scale)
    env.set_seed(1)
    state = env.reset()
    expected = (state["observation"].float() - loc) / scale
    assert torch.allclose(state["state"], expected)
    env.close()


def test_an_episodes_return_stops_at_its_first_end():
    rewards = torch.tensor([[1.0, 2.0, 3.0, 4.0], [1.0, 1.0, 1.0, 1.0]])
    done = torch.tensor([[False, True, False, True], [False, False, False, False]])
    assert first_episode_returns(rewards, done).tolist() == [3.0, 4.0]


def test_the_untrained_policy_samples_around_its_actor_with_the_set_sigma():
    cfg = check_config(
        "task.id=InvertedPendulum-v5",
        "collector.num_envs=2",
        "norm_frames=64",
        "algo.sigma_init=0.5",
    )
    check = PPOCheck(cfg)
    assert isinstance(check.update, PPOUpdate)
    states = TensorDict({"state": torch.randn(4096, 4)}, batch_size=[4096])
    acted = check.agent.policy(states)
    assert torch.allclose(acted["scale"], torch.full((4096, 1), 0.5))
    spread = float((acted["action"] - acted["loc"]).std())
    assert spread == pytest.approx(0.5, rel=0.05)
    check.close()


@pytest.mark.slow
def test_the_script_trains_and_reports_each_seed(tmp_path):
    out = tmp_path / "records.json"
    done = run_script(
        "benchmarks/gym_check.py",
        "task.id=InvertedPendulum-v5",
        "seeds=[0,1]",
        "collector.num_envs=4",
        "collector.frames_per_batch=256",
        "collector.total_frames=1024",
        "algo.epochs=2",
        "norm_frames=64",
        "eval_episodes=2",
        "progress=false",
        f"out={out}",
    )
    assert done.returncode == 0, done.stderr
    lines = [line for line in done.stdout.splitlines() if line.startswith("InvertedPendulum")]
    assert [line.split(":")[0] for line in lines] == [
        "InvertedPendulum-v5 ppo seed 0",
        "InvertedPendulum-v5 ppo seed 1",
    ]
    records = json.loads(out.read_text())
    assert [r["frames"] for r in records] == [1024, 1024]
    assert all(r["eval_return"] > 0 and r["curve"] for r in records)
    assert records[0]["curve"] != records[1]["curve"]


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("task.id=NoSuchTask-v0", "task.id=NoSuchTask-v0"),
        ("task.id=CartPole-v1", "continuous (Box) action spaces"),
        ("collector.frames_per_batch=100", "must be a multiple of collector.num_envs=8"),
    ],
)
@pytest.mark.slow
def test_bad_settings_fail_in_one_line(override, message):
    done = run_script("benchmarks/gym_check.py", override, "progress=false")
    assert done.returncode == 1
    error = done.stderr.strip()
    assert error.startswith("error: ") and "\n" not in error
    assert message in error


@pytest.mark.slow
def test_the_offpolicy_check_updates_with_the_trainers_loss_after_its_random_frames():
    cfg = check_config(
        "learner=td3",
        "task.id=InvertedPendulum-v5",
        "collector.num_envs=2",
        "collector.frames_per_batch=32",
        "collector.init_random_frames=64",
        "optim.updates_per_batch=2",
        "norm_frames=64",
    )
    check = OffPolicyCheck(cfg)
    assert isinstance(check.update, TD3)
    check.collector.restart(0)
    steps = []
    for _ in range(3):
        batch = check.collect(16)
        check.frames += batch.numel()
        check.learn(batch)
        steps.append(check.update.updates)
    assert steps == [0, 2, 4]  # none until 64 random frames are in the buffer, then two a batch
    assert len(check.buffer) == 96
    check.close()
