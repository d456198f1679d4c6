"""A killed off-policy run resumes exactly: the replay buffers reopen from the run folder, the
envs, the teacher and the carried steps continue where the checkpoint left them, and what cannot
be restored is said in a note."""

import pytest
import torch
from cli import train_config
from tensordict import TensorDict

from jugglerl.offpolicy import buffer as module
from jugglerl.offpolicy.buffer import ReplayBuffer
from jugglerl.offpolicy.resume import resume_notes
from jugglerl.offpolicy.stages import stages_from_config
from jugglerl.offpolicy.training import OffPolicyTraining
from jugglerl.recording.logger import RerunLogger
from jugglerl.runs.checkpoints import load_checkpoint
from jugglerl.runs.files import RunFileError
from jugglerl.training import resume_state

#: The apprentice pipeline with its rl stage (a teacher, bc then DAgger then residual RL, an LSTM
#: on slices) in a few seconds: 4 envs of 64 steps a batch, a checkpoint every batch, bc to frame
#: 512, DAgger to 1024.
SHORT_APPRENTICE = (
    "+experiment=apprentice_rl",
    "actor=lstm",
    "collector.num_envs=4",
    "collector.frames_per_batch=256",
    "replay_buffer.batch_size=128",
    "replay_buffer.slice_len=32",
    "algo.stages.bc.until=512",
    "algo.stages.dagger.until=1024",
    "algo.stages.bc.optim.updates_per_batch=4",
    "algo.stages.dagger.optim.updates_per_batch=4",
    "algo.stages.rl.optim.updates_per_batch=4",
    "algo.stop_cloning=null",
    "state.norm_frames=200",
    "env.duration=4",
    "eval.every_frames=512",
    "eval.duration=2",
    "eval.catch_time=1",
    "eval.perturbed_duration=1",
    "checkpoint_every_frames=256",
    "seed=3",
)


class KilledError(Exception):
    """The process dying: nothing after it runs, not even the Ctrl-C checkpoint."""


def run(training: OffPolicyTraining, run_dir) -> dict:
    with RerunLogger.from_config(
        training.cfg.logger, run_dir, recording_id=training.recording_id
    ) as logger:
        training.recording_id = logger.recording_id
        try:
            return training.run(logger, progress=False)
        finally:
            training.close()


def without_wall_times(metrics: dict) -> dict:
    return {key: value for key, value in metrics.items() if key not in ("wall_seconds", "seconds")}


def short_apprentice(total_frames: int):
    """``SHORT_APPRENTICE`` run to ``total_frames`` (past 1024, into the residual rl stage)."""
    budget = f"collector.total_frames={total_frames}"
    return train_config(*SHORT_APPRENTICE, budget, "algo.stages.rl.warmup_frames=256")


@pytest.mark.parametrize(
    "stage, killed_at, total_frames",
    [("bc", 512, 1024), ("dagger", 1024, 1024), ("rl", 1536, 1536)],
)
@pytest.mark.slow
def test_a_run_killed_after_a_checkpoint_resumes_to_the_uninterrupted_run(
    tmp_path, monkeypatch, stage, killed_at, total_frames
):
    straight = run(
        OffPolicyTraining(short_apprentice(total_frames), tmp_path / "a"), tmp_path / "a"
    )

    learn = OffPolicyTraining._learn

    def learn_then_die(self):
        if self.frames == killed_at:  # this batch is in the buffer's files, not in a checkpoint
            raise KilledError
        return learn(self)

    monkeypatch.setattr(OffPolicyTraining, "_learn", learn_then_die)
    killed = tmp_path / "b"
    with pytest.raises(KilledError):
        run(OffPolicyTraining(short_apprentice(total_frames), killed), killed)
    monkeypatch.setattr(OffPolicyTraining, "_learn", learn)

    cfg, _, state = resume_state(str(killed), short_apprentice(total_frames), [])
    assert state["counters"]["frames"] == killed_at - 256
    assert state["stage"] == ["bc", "dagger", "rl"].index(stage)
    resumed = run(OffPolicyTraining(cfg, killed, state), killed)
    assert without_wall_times(resumed) == without_wall_times(straight)


def frames(ids: torch.Tensor) -> TensorDict:
    """A batch ``[envs, steps]`` of trajectory ids and a value that tells frames apart."""
    return TensorDict(
        {"collector": {"traj_ids": ids}, "value": torch.rand(ids.shape)}, batch_size=ids.shape
    )


def test_a_buffer_reopened_from_its_folder_samples_what_it_sampled_before_the_kill(tmp_path):
    buffer = ReplayBuffer(1000, 64, slice_len=16, folder=tmp_path)
    buffer.extend(frames(torch.arange(8).repeat_interleave(32).reshape(4, 64)))
    state = buffer.state_dict()
    torch.manual_seed(0)
    before = buffer.sample()
    buffer.extend(frames(torch.arange(8, 16).repeat_interleave(32).reshape(4, 64)))  # then killed

    reopened = ReplayBuffer(1000, 64, slice_len=16, folder=tmp_path)
    assert reopened.load_state_dict(state)
    assert len(reopened) == 256 and reopened.ready and not reopened.wrapped
    torch.manual_seed(0)
    after = reopened.sample()
    assert torch.equal(after["value"], before["value"])
    assert torch.equal(after["collector", "traj_ids"], before["collector", "traj_ids"])


@pytest.mark.parametrize("slice_len", [None, 16])
def test_a_buffer_sampled_for_some_keys_gives_those_of_the_same_frames(tmp_path, slice_len):
    buffer = ReplayBuffer(1000, 64, slice_len=slice_len, folder=tmp_path)
    batch = frames(torch.arange(8).repeat_interleave(32).reshape(4, 64))
    buffer.extend(batch.set("other", torch.rand(batch.shape)))
    torch.manual_seed(0)
    whole, after_whole = buffer.sample(), torch.rand(3)
    torch.manual_seed(0)
    some, after_some = buffer.sample(keys=["value"]), torch.rand(3)
    assert set(some.keys()) == {"value"} and some.shape == whole.shape
    assert torch.equal(some["value"], whole["value"])
    assert torch.equal(after_some, after_whole)  # the same draws: a run's later ones stay


def test_a_buffer_whose_folder_is_gone_reopens_empty_and_the_resume_says_so(tmp_path):
    buffer = ReplayBuffer(1000, 64, slice_len=16, folder=tmp_path / "kept")
    buffer.extend(frames(torch.arange(8).repeat_interleave(32).reshape(4, 64)))
    state = buffer.state_dict()
    moved = ReplayBuffer(1000, 64, slice_len=16, folder=tmp_path / "elsewhere")
    assert not moved.load_state_dict(state) and len(moved) == 0
    stages = stages_from_config(train_config())
    notes = resume_notes(stages, 256, moved, buffers_restored=False, episodes_restored=True)
    assert len(notes) == 1
    assert notes[0].startswith(
        f"note: resumed without the replay buffer's 256 frames ({tmp_path / 'elsewhere'} does"
        " not hold them)"
    )


def test_a_resume_without_the_buffer_names_the_demonstrations_lost_with_it(tmp_path):
    drawing = "+algo.stages.rl.demo_fraction=0.25"
    stages = stages_from_config(
        train_config("+experiment=apprentice_rl", "+algo.stages.bc.demonstrations=true", drawing)
    )
    gone = ReplayBuffer(600000, 64, folder=tmp_path)

    def note(stages, frames):
        (note,) = resume_notes(stages, frames, gone, buffers_restored=False, episodes_restored=True)
        return note

    after_dagger = note(stages, 368640)  # the RL stage's demonstrations are gone
    assert "the demonstrations of stage bc collected before frame 368640" in after_dagger
    assert "stage rl draws its demo_fraction only from" in after_dagger
    assert "before frame 100000" in note(stages, 100000)  # part of BC's is gone
    assert "buffer's 600000 frames" in note(stages, 700000)  # as many as it holds
    (alone,) = stages_from_config(train_config("algo=td3"))
    assert "demonstrations" not in note([alone], 1024)  # none drawn on


def test_a_full_buffer_and_unsaved_episodes_are_noted_on_resume(tmp_path):
    buffer = ReplayBuffer(128, 64, slice_len=16, folder=tmp_path)
    buffer.extend(frames(torch.arange(8).repeat_interleave(32).reshape(4, 64)))
    assert buffer.wrapped
    stages = stages_from_config(train_config())
    notes = resume_notes(stages, 256, buffer, buffers_restored=True, episodes_restored=False)
    assert notes[0].startswith("note: the replay buffer was full at the checkpoint")
    assert notes[1].startswith("note: the envs start new episodes (collector.env=gym")
    assert resume_notes(stages, 0, buffer, False, False) == []  # a new run


def test_a_buffer_on_a_full_disk_stops_with_a_one_line_error(tmp_path, monkeypatch):
    buffer = ReplayBuffer(1000, 64, slice_len=16, folder=tmp_path)
    usage = module.shutil.disk_usage(tmp_path)
    monkeypatch.setattr(module.shutil, "disk_usage", lambda _: usage._replace(free=1000))
    with pytest.raises(RunFileError, match="could not write the replay buffer"):
        buffer.extend(frames(torch.arange(8).repeat_interleave(32).reshape(4, 64)))
    assert len(buffer) == 0


@pytest.mark.slow
def test_a_gym_collector_resumes_with_new_episodes_and_says_so(tmp_path, capsys):
    cut = ("collector.env=gym", "collector.total_frames=256")  # stops inside the bc stage
    run(OffPolicyTraining(train_config(*SHORT_APPRENTICE, *cut), tmp_path), tmp_path)
    more = "collector.total_frames=512"
    cfg, _, state = resume_state(str(tmp_path), train_config(*SHORT_APPRENTICE, more), [more])
    OffPolicyTraining(cfg, tmp_path, state).close()
    assert "note: the envs start new episodes" in capsys.readouterr().err
    assert load_checkpoint(tmp_path)["collector"] == {}


@pytest.mark.slow
def test_a_resume_with_another_number_of_envs_starts_new_episodes_and_says_so(tmp_path, capsys):
    cut = "collector.total_frames=256"  # stops inside the bc stage
    run(OffPolicyTraining(train_config(*SHORT_APPRENTICE, cut), tmp_path), tmp_path)
    more = ("collector.total_frames=512", "collector.num_envs=2", "collector.frames_per_batch=128")
    cfg, _, state = resume_state(str(tmp_path), train_config(*SHORT_APPRENTICE, *more), list(more))
    training = OffPolicyTraining(cfg, tmp_path, state)
    assert "note: the envs start new episodes" in capsys.readouterr().err
    assert training.collector.carried is None and len(training.buffer) == 256
    training.close()
