"""DPSCollector batches; DPS training, checkpoints and resumes; train.py from the command line."""

import json
from pathlib import Path

import pytest
import torch
from cli import interrupt_train, rrd_verifies, run_train, train_config

from jugglerl.commands import load_command
from jugglerl.dps.collector import DPSCollector
from jugglerl.dps.distribution import PAPER_STDS, SearchDistribution
from jugglerl.dps.params import (
    ViaPointConstraints,
    params_to_command,
)
from jugglerl.dps.rollouts import CommandRollouts
from jugglerl.dps.training import SearchTraining
from jugglerl.policies.command import CommandPolicy
from jugglerl.policies.episodes import run_episode
from jugglerl.recording.logger import RerunLogger
from jugglerl.recording.reading import column
from jugglerl.runs.checkpoints import load_checkpoint
from jugglerl_envs import JuggleEnv

SHORT = [
    "algo=dps",
    "env.duration=8",
    "algo.rollouts=4",
    "algo.noise_check.seeds=2",
    "progress=false",
]


class CommandSpace:
    """The least a collector needs of a search space: via-point constraints and commands."""

    def __init__(self, env: JuggleEnv):
        self.constraints = ViaPointConstraints.from_model(env.model, 1.0, 5.0, 0.1)

    def project(self, params):
        return self.constraints.project(params)

    def decode(self, params):
        return params_to_command(params)


def make_collector(seed: int = 0, total: int = 8, common_seeds: bool = False) -> DPSCollector:
    env = JuggleEnv(duration=8.0, reset_noise=0.01)
    return DPSCollector(
        CommandSpace(env),
        CommandRollouts(env, nthread=2),
        SearchDistribution.around(load_command("expert"), PAPER_STDS),
        frames_per_batch=4,
        total_frames=total,
        seed=seed,
        common_seeds=common_seeds,
    )


def test_collector_yields_batches_of_rolled_out_samples():
    collector = make_collector(total=8)
    batches = list(collector)
    collector.shutdown()
    assert [b.batch_size for b in batches] == [torch.Size([4])] * 2
    batch = batches[1]
    assert set(batch.keys(include_nested=True)) >= {
        "params",
        "return",
        "throws",
        "time_to_drop",
        "seed",
        ("collector", "iteration"),
    }
    assert batch["params"].shape == (4, 10) and batch["collector", "iteration"].tolist() == [1] * 4
    assert torch.equal(batch["return"], batch["throws"].double())
    assert collector.frames == 8 and len(collector) == 2
    # the counts belong to the samples: re-evaluating them gives the same throws
    commands = [params_to_command(theta) for theta in batch["params"]]
    with CommandRollouts(JuggleEnv(duration=8.0, reset_noise=0.01), nthread=2) as rollouts:
        results = rollouts.evaluate(commands, batch["seed"].tolist())
    assert results.throws.tolist() == batch["throws"].tolist()
    assert len(set(batch["params"][:, 0].tolist())) == 4  # four different samples


def test_common_seeds_give_every_sample_of_a_batch_the_same_start():
    collector = make_collector(total=-1, common_seeds=True)
    first, second = collector.collect_batch(), collector.collect_batch()
    target = first["params"][0]  # one θ four times: from one start, four equal scores
    collector.update_policy_weights_(SearchDistribution.diagonal(target, torch.zeros(10)))
    same = collector.collect_batch()
    collector.shutdown()
    assert len(set(first["seed"].tolist())) == len(set(second["seed"].tolist())) == 1
    assert first["seed"][0] != second["seed"][0]
    assert len(set(same["throws"].tolist())) == 1
    independent = make_collector(total=4)
    assert len(set(independent.collect_batch()["seed"].tolist())) == 4
    independent.shutdown()


def test_update_policy_weights_sets_the_sampling_distribution():
    collector = make_collector(total=-1)
    target = torch.tensor([2.0, 0.0, -1.5708, 2.15, 1.0, -1.5708, 1.5, 1.5, -1.5708, 2.15])
    narrow = SearchDistribution.diagonal(target, torch.full((10,), 1e-9))
    collector.update_policy_weights_(narrow.to_tensordict())
    batch = collector.collect_batch()
    collector.shutdown()
    assert torch.allclose(batch["params"], target.double().expand(4, 10), atol=1e-7)
    with pytest.raises(TypeError, match="SearchDistribution"):
        collector.update_policy_weights_({"mean": target})


def test_collector_state_restores_the_same_samples():
    first = make_collector(seed=5, total=-1)
    first.collect_batch()
    state = first.state_dict()
    expected = first.collect_batch()
    resumed = make_collector(seed=99, total=-1)
    resumed.load_state_dict(state)
    again = resumed.collect_batch()
    first.shutdown()
    resumed.shutdown()
    assert torch.equal(expected["params"], again["params"])
    assert torch.equal(expected["throws"], again["throws"])


def run_training(cfg, run_dir: Path, state: dict | None = None) -> tuple[dict, SearchTraining]:
    training = SearchTraining(cfg, run_dir, state)
    with RerunLogger.from_config(cfg.logger, run_dir) as logger:
        metrics = training.run(logger, progress=False)
    training.close()
    return metrics, training


@pytest.mark.parametrize("update", ["greedy", "ereps", "cmaes"])
@pytest.mark.slow
def test_a_resumed_run_reproduces_the_uninterrupted_one(tmp_path, update):
    straight, _ = run_training(
        train_config(*SHORT, f"algo.update={update}", "algo.episodes=3", "seed=4"),
        tmp_path / "straight",
    )
    run_training(
        train_config(*SHORT, f"algo.update={update}", "algo.episodes=2", "seed=4"),
        tmp_path / "split",
    )
    state = load_checkpoint(tmp_path / "split")
    assert state["collector"]["iteration"] == 2
    resumed, training = run_training(
        train_config(*SHORT, f"algo.update={update}", "algo.episodes=3", "seed=4"),
        tmp_path / "split",
        state,
    )
    assert resumed["history"] == straight["history"]
    assert resumed["best_command"] == straight["best_command"]
    final = load_checkpoint(tmp_path / "straight")["collector"]["distribution"]
    assert torch.equal(training.collector.distribution.mean, final["mean"])


@pytest.mark.slow
def test_training_keeps_the_best_command_and_logs_its_progress(tmp_path):
    metrics, training = run_training(train_config(*SHORT, "algo.episodes=3"), tmp_path)
    history = metrics["history"]
    assert [r["rollouts"] for r in history] == [4, 8, 12]
    assert metrics["best_throws"] == max(r["max_throws"] for r in history)
    assert [r["best_throws"] for r in history] == sorted(r["best_throws"] for r in history)
    best = load_command(tmp_path / "best_command.yaml")
    assert best == training.space.decode(training.best.params)
    assert best.lead_in == 0.5  # algo.lead_in's default
    # the search rolls out from offset starts (algo.reset_noise's default); the best command
    # replays to its score from its roll-out's start, and the noise check replays the standard one
    assert training.collector.rollouts.env.unwrapped.reset_noise == 0.01
    noisy_env = JuggleEnv(duration=8.0, reset_noise=0.01)
    replay = run_episode(noisy_env, CommandPolicy(best), seed=training.best.seed)
    assert replay.throws == metrics["best_throws"] > 0
    env = JuggleEnv(duration=8.0)
    check = metrics["noise_check"]
    assert check["seeds"] == [0, 1]
    assert check["nominal_throws"] == run_episode(env, CommandPolicy(best), seed=0).throws
    assert check["fraction_of_best"] == pytest.approx(
        sum(check["throws"]) / 2 / max(check["nominal_throws"], 1)
    )
    rrd = tmp_path / "train.rrd"
    steps, values = column(rrd, "dps/best_throws", "Scalars:scalars", "step")
    assert steps.tolist() == [4, 8, 12] and values.ravel().tolist() == [
        r["best_throws"] for r in history
    ]
    best_episode = f"best/{metrics['best_found_at_rollout']:05d}/plots/ball_height"
    times, _ = column(rrd, best_episode, "Scalars:scalars", "sim_time")
    assert times[-1] == pytest.approx(8.0)  # the best episode was recorded whole


@pytest.mark.slow
def test_a_short_search_keeps_its_result(tmp_path):
    """A change to sampling, constraints, roll-outs or the update rule moves these numbers (found
    with torch 2.13.0, mujoco 4.0.1): it then owes the shipped searches' results a rerun. They are
    kept to 1e-7: two hosts with the same packages differ from the ninth digit on (the vector
    code numpy and MuJoCo pick for the CPU), and a change to the search moves them further."""
    overrides = ["algo.episodes=3", "algo.update=ereps", "algo.lead_in=0", "algo.reset_noise=0"]
    metrics, training = run_training(train_config(*SHORT, *overrides, "seed=0"), tmp_path)
    assert [r["best_throws"] for r in metrics["history"]] == [1, 2, 2]
    best = load_command(tmp_path / "best_command.yaml")
    assert best.cycle == pytest.approx(2.9773808244412985, rel=1e-7, abs=0)
    assert [float(x) for point in best.via_points for x in point] == pytest.approx(
        [0.03304070560712154, -1.5634088749435882, 2.1417429577449956]
        + [1.498010759343621, -1.5703249868383242, 1.4983150834791938]
        + [1.9899373968317733, -1.5834465678529286, 2.146806920231029],
        rel=1e-7,
        abs=0,
    )
    mean = training.collector.distribution.mean.tolist()
    assert mean == pytest.approx(
        [2.942609552606715, 0.0262064724345676, -1.5652097432865015, 2.14368142995656]
        + [1.500415004968148, -1.5740438168924789, 1.4975550233701238]
        + [1.9859691038300227, -1.5821140140732484, 2.1484550661261292],
        rel=1e-7,
        abs=0,
    )


@pytest.mark.slow
def test_a_run_deploying_the_mean_writes_it_and_checks_it(tmp_path):
    cfg = train_config(*SHORT, "algo.update=cmaes", "algo.deploy=mean", "algo.episodes=2")
    metrics, training = run_training(cfg, tmp_path)
    mean = training.space.project(training.collector.distribution.mean)
    deployed = load_command(tmp_path / "mean_command.yaml")
    assert deployed == training.space.decode(mean) != training.space.decode(training.best.params)
    assert metrics["deploys"] == load_checkpoint(tmp_path)["deploys"] == "mean_command.yaml"
    assert (tmp_path / "best_command.yaml").is_file()  # the best is kept all the same
    nominal = run_episode(JuggleEnv(duration=8.0), CommandPolicy(deployed), seed=0).throws
    assert metrics["noise_check"]["nominal_throws"] == nominal


@pytest.mark.slow
def test_train_script_runs_and_resumes_from_its_run_directory(tmp_path):
    first = run_train(*SHORT, "algo.episodes=1", f"hydra.run.dir={tmp_path}")
    assert first.returncode == 0, first.stderr
    assert "best" in first.stdout and (tmp_path / "best_command.yaml").is_file()
    resumed = run_train(
        *SHORT, f"resume={tmp_path}", "algo.episodes=2", f"hydra.run.dir={tmp_path}/r"
    )
    assert resumed.returncode == 0, resumed.stderr
    assert f"resuming {tmp_path} at episode 1" in resumed.stdout
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert [record["rollouts"] for record in metrics["history"]] == [4, 8]
    assert (tmp_path / "train.1.rrd").is_file()  # the first recording is kept


@pytest.mark.slow
def test_ctrl_c_leaves_a_checkpoint_that_resumes(tmp_path):
    returncode, stderr = interrupt_train(tmp_path, *SHORT, "algo.episodes=1000")
    assert returncode != 0
    assert "interrupted at episode" in stderr and f"resume={tmp_path}" in stderr
    assert "Traceback" not in stderr
    state = load_checkpoint(tmp_path)
    assert state["collector"]["iteration"] >= 1
    assert rrd_verifies(tmp_path / "train.rrd")


@pytest.mark.parametrize(
    "override, message",
    [
        ("algo.update=adam", "error: algo.update='adam' is not available; choose one of cmaes,"),
        ("algo.update=elite algo.elite=50", "error: algo.elite=50 must be <= algo.rollouts=4"),
        (
            "algo.start=missing.yaml",
            "error: algo.start=missing.yaml: no policy file at missing.yaml; shipped policies:",
        ),
        ("algo.lead_in=-1", "error: algo.lead_in=-1 is out of range"),
        ("algo.space=joint", "error: algo.space='joint' is not available; choose one of"),
        ("algo.reset_noise=0.5", "error: algo.reset_noise=0.5 is out of range"),
        ("algo.deploy=last", "error: algo.deploy='last': use best or mean"),
        ("resume=nowhere", "error: resume: no checkpoint at nowhere"),
    ],
)
def test_bad_config_gives_one_clear_line(tmp_path, override, message):
    result = run_train(*SHORT, *override.split(), f"hydra.run.dir={tmp_path}")
    assert result.returncode != 0
    assert result.stderr.strip().splitlines()[-1].startswith(message), result.stderr
    assert "Traceback" not in result.stderr


def test_a_malformed_start_command_names_the_file_and_the_problem(tmp_path):
    command = tmp_path / "bad.yaml"
    command.write_text("cycle: 2.0\nvia_points: [[1.5, -1.5708, 2.0], [0.5, -1.5708, 1.5]]\n")
    result = run_train(*SHORT, f"algo.start={command}", f"hydra.run.dir={tmp_path}")
    assert result.returncode != 0
    assert result.stderr.strip() == (
        f"error: {command}: via-point times [1.5, 0.5] must increase strictly within [0, cycle=2.0)"
    )
