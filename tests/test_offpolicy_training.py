"""Off-policy training: per-actor and per-loss smoke runs that checkpoint and resume; train.py and
evaluate.py on their run directories."""

import json

import pytest
import torch
from cli import interrupt_train, rrd_verifies, run_script, run_train, train_config
from tensordict import TensorDict

from jugglerl.batch.batch_stats import BatchStats
from jugglerl.offpolicy.training import OffPolicyTraining
from jugglerl.recording.logger import RerunLogger
from jugglerl.recording.reading import column
from jugglerl.runs.checkpoints import load_checkpoint

#: A few hundred frames: 2 envs x 64 steps per batch, short episodes and evaluations.
TINY = [
    "algo=ddpg",
    "env.duration=4",
    "state.norm_frames=200",
    "collector.num_envs=2",
    "collector.frames_per_batch=128",
    "collector.total_frames=256",
    "replay_buffer.batch_size=64",
    "optim.updates_per_batch=4",
    "eval.every_frames=128",
    "eval.seeds=2",
    "eval.duration=2",
    "eval.catch_time=1",
    "checkpoint_every_frames=128",
    "progress=false",
]


def train(cfg, run_dir, state=None) -> tuple[dict, OffPolicyTraining]:
    training = OffPolicyTraining(cfg, run_dir, state)
    with RerunLogger.from_config(cfg.logger, run_dir, recording_id=training.recording_id) as log:
        training.recording_id = log.recording_id
        metrics = training.run(log, progress=False)
    training.close()
    return metrics, training


@pytest.mark.parametrize(
    "overrides",
    [
        ["actor=lstm"],
        ["actor=residual"],
        ["algo=td3", "actor=lstm"],
        ["algo=bc", "actor=lstm", "teacher.policy=closed_loop"],
        [
            "algo=ddpg",
            "algo.bc_weight=1",
            "teacher.policy=closed_loop",
        ],
    ],
)
@pytest.mark.slow
def test_a_smoke_run_writes_a_checkpoint_that_resumes(tmp_path, overrides):
    cfg = train_config(*TINY, *overrides)
    metrics, training = train(cfg, tmp_path)
    assert metrics["frames"] == 256 and metrics["updates"] == 8
    assert [e["frames"] for e in metrics["evaluations"]] == [128, 256, 256]  # periodic, final
    final = metrics["final_evaluation"]
    assert final["duration"] == 4 and len(final["episodes"]) == 2
    state = load_checkpoint(tmp_path)
    assert state["counters"]["frames"] == 256 and state["counters"]["updates"] == 8

    cfg.collector.total_frames = 512
    resumed, again = train(cfg, tmp_path, state)
    assert resumed["frames"] == 512 and resumed["updates"] == 16
    assert [h["frames"] for h in resumed["history"]] == [128, 256, 384, 512]
    first = training.actor.state_dict()
    assert any(not torch.equal(first[k], v) for k, v in again.actor.state_dict().items())
    norm = load_checkpoint(tmp_path)["normalisation"]
    torch.testing.assert_close(norm["loc"], state["normalisation"]["loc"])  # kept, not refitted
    times, throws = column(tmp_path / "train.1.rrd", "eval/mean_throws", "Scalars:scalars", "step")
    assert list(times) == [384, 512, 512]


@pytest.mark.slow
def test_a_resumed_checkpoint_restores_networks_optimisers_exploration_and_clocks(
    tmp_path, monkeypatch
):
    saved = []  # the state of every checkpoint the run writes
    save = OffPolicyTraining.save

    def save_and_keep(self):
        save(self)
        saved.append(self.state_dict())

    monkeypatch.setattr(OffPolicyTraining, "save", save_and_keep)
    cfg = train_config(*TINY)
    _, training = train(cfg, tmp_path)
    periodic = saved[0]  # at the first batch, while the run trains
    assert periodic["counters"]["frames"] == 128 and periodic["counters"]["wall_seconds"] > 0
    assert len(periodic["batch_stats"]["recent"]) == 1
    state = load_checkpoint(tmp_path)
    restored = OffPolicyTraining(cfg, tmp_path / "again", state)
    assert list(restored.batch_stats.recent) == list(training.batch_stats.recent)
    assert len(restored.batch_stats.recent) == 2
    for key, value in training.update.loss.state_dict().items():
        torch.testing.assert_close(restored.update.loss.state_dict()[key], value)
    saved_optimiser = training.update.critic_optimiser.state_dict()["state"]
    restored_optimiser = restored.update.critic_optimiser.state_dict()["state"]
    torch.testing.assert_close(restored_optimiser[0]["exp_avg"], saved_optimiser[0]["exp_avg"])
    assert int(restored.noise.frames) == int(training.noise.frames) == 256
    restored.close()


def test_updates_wait_while_the_buffer_holds_no_piece_as_long_as_a_slice(tmp_path, capsys):
    # a resumed run starts without the buffer: an LSTM student that drops the ball early in
    # every env leaves pieces too short for TorchRL's SliceSampler, which would raise
    cfg = train_config(*TINY, "actor=lstm", "replay_buffer.slice_len=32")
    training = OffPolicyTraining(cfg, tmp_path)
    ids = torch.arange(8).repeat_interleave(16).reshape(2, 64)  # pieces of 16 steps
    training.buffer.extend(TensorDict({"collector": {"traj_ids": ids}}, batch_size=[2, 64]))
    assert len(training.buffer) >= cfg.replay_buffer.batch_size
    assert training._learn() == {} and training._learn() == {}
    note = "no episode piece of replay_buffer.slice_len=32 steps collected yet; the updates wait"
    assert capsys.readouterr().err.count(note) == 1
    training.close()


@pytest.mark.slow
def test_the_checkpoint_ships_the_target_actor_unless_told_otherwise(tmp_path):
    for target in (True, False):
        cfg = train_config(*TINY, f"eval.target_actor={target}")
        _, training = train(cfg, tmp_path / str(target))
        loss = training.update.loss
        targets = loss.target_actor_network_params.flatten_keys()
        online = loss.actor_network_params.flatten_keys()
        shipped = load_checkpoint(tmp_path / str(target))["policy"]
        for key, value in shipped.items():
            torch.testing.assert_close(value, (targets if target else online)[key])
            assert not torch.equal(targets[key], online[key])


@pytest.mark.slow
def test_keep_best_ships_the_actor_of_the_best_evaluation(tmp_path):
    cfg = train_config(*TINY, "eval.keep_best=true", "eval.target_actor=false")
    training = OffPolicyTraining(cfg, tmp_path)

    def evaluated(catch_rate, time_up):
        record = {"catch_rate": catch_rate, "mean_throws": 0.0, "mean_time_to_drop": time_up}
        training.evaluations.keep_if_best({**record, "frames": 0}, training.current_actor())
        kept = {k: v.clone() for k, v in training.actor.state_dict().items()}
        with torch.no_grad():  # the training moves on
            for parameter in training.actor.parameters():
                parameter.add_(0.1)
        return kept

    evaluated(0.0, 1.0)
    best = evaluated(1.0, 2.0)
    evaluated(0.0, 30.0)  # up longer but caught less: not kept
    for key, value in training.deployed_actor().state_dict().items():
        torch.testing.assert_close(value, best[key])
    assert training.evaluations.best["score"] == [1.0, 0.0, 2.0]
    tie = evaluated(1.0, 2.0)  # a tie goes to the later actor
    torch.testing.assert_close(training.deployed_actor().state_dict(), tie)
    restored = OffPolicyTraining(cfg, tmp_path / "again", training.state_dict())
    torch.testing.assert_close(restored.deployed_actor().state_dict(), tie)
    training.close()
    restored.close()
    plain = OffPolicyTraining(train_config(*TINY), tmp_path / "plain")
    record = {"catch_rate": 1.0, "mean_throws": 0.0, "mean_time_to_drop": 2.0, "frames": 0}
    plain.evaluations.keep_if_best(record, plain.actor)
    assert plain.evaluations.best is None  # off by default: the last actor ships
    plain.close()


@pytest.mark.slow
def test_train_script_trains_td3_resumes_and_evaluate_runs_its_run_directory(tmp_path):
    first = run_train(*TINY, "algo=td3", "actor=lstm", f"hydra.run.dir={tmp_path}")
    assert first.returncode == 0, first.stderr
    assert (
        "TD3 (lstm actor, gaussian exploration, reward distance) after 256 frames" in first.stdout
    )
    resumed = run_train(f"resume={tmp_path}", "collector.total_frames=384", "progress=false")
    assert resumed.returncode == 0, resumed.stderr
    assert f"resuming {tmp_path} at frame 256" in resumed.stdout
    assert json.loads((tmp_path / "metrics.json").read_text())["frames"] == 384
    for algo in ("dps", "apprentice"):  # another algorithm is a new run
        other = run_train(f"resume={tmp_path}", f"algo={algo}", "progress=false")
        assert other.returncode == 1 and "Traceback" not in other.stderr
        assert other.stderr.strip() == (
            f"error: resume: {tmp_path} is an algo=td3 run and continues as one;"
            f" algo={algo} needs a new run"
        )

    evaluation = run_script(
        "evaluate.py", f"policy={tmp_path}", "duration=3", f"hydra.run.dir={tmp_path / 'eval'}"
    )
    assert evaluation.returncode == 0, evaluation.stderr
    assert "warning" not in evaluation.stderr  # a finished run
    metrics = json.loads((tmp_path / "eval" / "metrics.json").read_text())
    assert 0 < metrics["duration"] <= 3

    record = (tmp_path / ".hydra" / "overrides.yaml").read_text()
    assert "algo=td3" in record
    again = run_train(*TINY, f"hydra.run.dir={tmp_path}")  # a new run over the finished one
    assert again.returncode == 1 and again.stderr.strip() == (
        f"error: {tmp_path} holds another run (checkpoint.pt, metrics.json): continue it with"
        f" resume={tmp_path}, or start this one in another folder (hydra.run.dir=DIR) or over"
        " it (overwrite=true)"
    )
    assert json.loads((tmp_path / "metrics.json").read_text())["frames"] == 384  # untouched
    assert (tmp_path / ".hydra" / "overrides.yaml").read_text() == record


@pytest.mark.slow
def test_ctrl_c_twice_leaves_a_ddpg_checkpoint_and_a_closed_recording(tmp_path):
    """The second press, 20 ms after the first, lands while the run saves: it is ignored."""
    returncode, stderr = interrupt_train(
        tmp_path, *TINY, "collector.total_frames=1000000", "eval.every_frames=0", presses=2
    )
    assert returncode != 0
    assert "interrupted at frame" in stderr and f"resume={tmp_path}" in stderr
    assert "Traceback" not in stderr
    assert load_checkpoint(tmp_path)["counters"]["frames"] >= 128
    assert rrd_verifies(tmp_path / "train.rrd")


@pytest.mark.parametrize(
    "override, message",
    [
        ("actor=gru", "error: actor=gru is not available; choose one of lstm, mlp, residual"),
        ("exploration=epsilon", "error: exploration=epsilon is not available; choose one of"),
        ("reward=height", "error: reward=height is not available; choose one of contacts"),
        ("collector.num_envs=3", "error: collector.frames_per_batch=128 must be a multiple of"),
        ("collector.num_envs=0", "error: collector.num_envs=0 must be >= 1"),
        ("exploration.centre=middle", "error: exploration.centre=middle is not one of timed"),
        ("algo=td3 algo.policy_delay=0", "error: algo.policy_delay=0 must be >= 1"),
        ("algo.loss=sac", "error: algo.loss='sac' is not available; choose one of bc, ddpg, td3"),
        ("actor=lstm replay_buffer.batch_size=50", "error: replay_buffer.batch_size=50 must be a"),
        (
            "actor=lstm replay_buffer.slice_len=128",
            "error: replay_buffer.slice_len=128 must be at most",
        ),
        (
            "actor=lstm replay_buffer.slice_len=32 env.duration=0.5",
            "error: replay_buffer.slice_len=32 must be at most the steps of an episode,"
            " env.duration=0.5 s = 25 steps",
        ),
        ("+eval.perturbed.windy={gust:1}", "error: eval.perturbed.windy: env config:"),
        (
            "optim.lr_actor=-1",
            "error: optim.lr_actor=-1 is out of range: expected a number in (0, inf]",
        ),
        (
            "optim.updates_per_batch=-1",
            "error: optim.updates_per_batch=-1 is out of range: expected an integer in [0,",
        ),
        (
            "state.period=-1",
            "error: state.period=-1 is out of range: expected a number in (0, inf]",
        ),
        ("teacher.policy=nope", "error: teacher.policy=nope: no policy file at"),
        ("state.observe=[ball,elbow]", "error: state.observe=['ball', 'elbow']: one or more"),
        ("env.duration=0", "error: env.duration=0 is out of range"),
        ("env.reset_noise=10", "error: env.reset_noise=10 is out of range"),
        ("+foo=1", "error: +foo=1: nothing reads foo; the config has actor, algo,"),
        (
            "+optim.momentum=0.9",
            "error: +optim.momentum=0.9: nothing reads optim.momentum; optim has lr_actor,",
        ),
        ("cluster=ray", "error: cluster=ray: an off-policy run trains in this process"),
    ],
)
@pytest.mark.slow
def test_a_bad_override_gives_a_clear_message(tmp_path, override, message):
    result = run_train(*TINY, *override.split(), f"hydra.run.dir={tmp_path}")
    assert result.returncode != 0
    assert message in result.stderr, result.stderr
    assert "Traceback" not in result.stderr


def test_the_throw_rate_counts_the_throws_made_within_the_last_batches():
    stats = BatchStats(step_seconds=0.02, window=2)
    throws = torch.tensor([[0, 0, 1, 1], [3, 3, 3, 0]])  # the second env restarts at its last step
    following = torch.tensor([[0, 1, 1, 2], [3, 3, 4, 0]])

    def batch(throws, following):
        rest = {"reward": torch.zeros(2, 4, 1), "done": torch.zeros(2, 4, 1, dtype=torch.bool)}
        return TensorDict({"throws": throws, "next": {"throws": following, **rest}}, [2, 4])

    minutes = 8 * 0.02 / 60
    assert stats(batch(throws, following))["throws_per_minute"] == pytest.approx(3 / minutes)
    none = batch(following, following)  # a batch without a throw halves the rate over two
    assert stats(none)["throws_per_minute"] == pytest.approx(3 / (2 * minutes))
    assert stats(none)["throws_per_minute"] == 0  # the first batch has left the window
