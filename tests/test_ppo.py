"""PPO (``algo=ppo``): the untrained residual plays its command, GAE bootstraps through the time
limit but not through a drop, and a short run trains, resumes exactly and ships a policy."""

import json

import pytest
import torch
from cli import run_script, run_train, train_config
from tensordict import TensorDict
from torchrl.objectives.value import GAE

from jugglerl.commands import load_command
from jugglerl.networks.reference import CommandReference
from jugglerl.onpolicy.agent import make_agent
from jugglerl.onpolicy.training import PPOTraining
from jugglerl.state.transforms import state_size

#: A PPO run of a few seconds: 16 envs, batches of 16 steps, short evaluations.
SMOKE = (
    "algo=ppo",
    "collector.num_envs=16",
    "collector.frames_per_batch=256",
    "collector.total_frames=1024",
    "algo.minibatch_size=128",
    "algo.epochs=2",
    "eval.every_frames=512",
    "eval.duration=10",
    "eval.perturbed_seeds=1",
    "eval.perturbed_duration=2",
    "state.norm_frames=256",
    "checkpoint_every_frames=512",
    "progress=false",
)


def test_the_untrained_policy_acts_as_its_command_on_any_states():
    cfg = train_config("algo=ppo")
    agent = make_agent(cfg, state_size(cfg.state))
    states = torch.randn(64, state_size(cfg.state)) * 3
    times = torch.rand(64, dtype=torch.float64) * 30
    acted = agent.policy(TensorDict({"state": states, "time": times}, batch_size=[64]))
    reference = CommandReference(load_command("expert"))(times)
    assert torch.equal(acted["loc"], reference)
    assert torch.allclose(acted["scale"], torch.full((64, 3), cfg.algo.sigma_init))
    assert not torch.equal(acted["action"], reference)  # sampled around it


def test_gae_bootstraps_through_the_time_limit_and_not_through_a_drop():
    """One env, four steps, V = 1 everywhere, reward 1 per step: step 1 is truncated (the next
    value counts), step 3 terminated (it does not). With γ = 0.5 and λ = 1, the advantage at
    step t is the discounted rewards to the end of its episode plus γ^k V at a truncation,
    minus V(t)."""

    class Ones(torch.nn.Module):
        def forward(self, state):
            return torch.ones(*state.shape[:-1], 1)

    from torchrl.modules import ValueOperator

    gae = GAE(gamma=0.5, lmbda=1.0, value_network=ValueOperator(Ones(), in_keys=["state"]))
    ends = {"terminated": [0, 0, 0, 1], "truncated": [0, 1, 0, 0]}
    flags = {k: torch.tensor(v, dtype=torch.bool).reshape(1, 4, 1) for k, v in ends.items()}
    flags["done"] = flags["terminated"] | flags["truncated"]
    data = TensorDict(
        {
            "state": torch.zeros(1, 4, 2),
            "next": {"state": torch.zeros(1, 4, 2), "reward": torch.ones(1, 4, 1), **flags},
        },
        batch_size=[1, 4],
    )
    gae(data)
    # episode 1: steps 0, 1, truncated after step 1 (bootstrap V = 1)
    #   A0 = 1 + 0.5 * 1 + 0.25 * 1 - 1 = 0.75; A1 = 1 + 0.5 * 1 - 1 = 0.5
    # episode 2: steps 2, 3, terminated after step 3 (no bootstrap)
    #   A2 = 1 + 0.5 * 1 - 1 = 0.5; A3 = 1 - 1 = 0
    expected = torch.tensor([0.75, 0.5, 0.5, 0.0]).reshape(1, 4, 1)
    assert torch.allclose(data["advantage"], expected)


@pytest.mark.slow
def test_a_resumed_run_repeats_the_uninterrupted_one(tmp_path):
    cfg = train_config(*SMOKE[:-1])
    straight = PPOTraining(cfg, tmp_path / "straight")
    for _ in range(4):
        straight._collect_and_learn()
    resumed = PPOTraining(cfg, tmp_path / "resumed")
    for _ in range(2):
        resumed._collect_and_learn()
    state = resumed.state_dict()
    resumed.close()
    again = PPOTraining(cfg, tmp_path / "resumed", state=state)
    for _ in range(2):
        again._collect_and_learn()
    wall = ("frames_per_second", "update_seconds")
    assert [{k: v for k, v in r.items() if k not in wall} for r in again.history] == [
        {k: v for k, v in r.items() if k not in wall} for r in straight.history
    ]
    for name, weights in straight.agent.policy.state_dict().items():
        assert torch.equal(weights, again.agent.policy.state_dict()[name]), name
    assert straight.history[-1]["frames"] == 1024 and straight.updates == 4 * 2 * 2


@pytest.mark.slow
def test_a_smoke_run_trains_resumes_and_ships_a_policy_that_evaluate_runs(tmp_path):
    run = tmp_path / "run"
    first = run_train(*SMOKE, "collector.total_frames=512", f"hydra.run.dir={run}")
    assert first.returncode == 0, first.stderr[-3000:]
    assert "PPO (residual actor, reward juggle) after 512 frames" in first.stdout
    resumed = run_train(f"resume={run}", "collector.total_frames=1024", "progress=false")
    assert resumed.returncode == 0, resumed.stderr[-3000:]
    metrics = json.loads((run / "metrics.json").read_text())
    assert metrics["frames"] == 1024 and metrics["algo"] == "ppo"
    assert {"kl_approx", "clip_fraction", "sigma", "loss_critic"} <= set(metrics["history"][-1])
    ship = run_script("ship_actor.py", str(run), "ppo_smoke", "--folder", str(tmp_path))
    assert ship.returncode == 0, ship.stderr[-3000:]
    shipped = tmp_path / "ppo_smoke.yaml"
    assert ship.stdout.strip() == str(shipped)
    evaluation = run_script(
        "evaluate.py", f"policy={shipped}", "duration=3", f"hydra.run.dir={tmp_path / 'eval'}"
    )
    assert evaluation.returncode == 0, evaluation.stderr[-3000:]
    assert json.loads((tmp_path / "eval" / "metrics.json").read_text())["duration"] > 0


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("algo.gamma=1.5", "error: algo.gamma=1.5 must be in (0, 1]"),
        ("algo.minibatch_size=0", "error: algo.epochs=2 must be >= 1 and algo.minibatch_size=0"),
        ("algo.sigma_init=0", "error: algo.sigma_init=0 must be in (0, 1]"),
        ("actor=lstm", "error: actor=lstm: algo=ppo trains feed-forward actors"),
        ("algo.servo_gain=[1.1,0.9]", "error: algo.servo_gain=[1.1, 0.9]: a range of positive"),
        ("collector.env=gym", "error: collector.env=gym: algo=ppo collects from a batch"),
    ],
)
@pytest.mark.slow
def test_bad_settings_fail_in_one_line(override, message, tmp_path):
    result = run_train(*SMOKE, override, f"hydra.run.dir={tmp_path}")
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert result.stderr.strip().startswith(message), result.stderr
