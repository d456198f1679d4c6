"""A run's files under write failures: the previous checkpoint survives, no partial file stays,
the recording's flush is bounded, and every failure is one line naming the file."""

import subprocess
import sys
import textwrap
import uuid
from pathlib import Path

import pytest
import torch

import jugglerl.runs.checkpoints as checkpoints
from jugglerl.recording.logger import FLUSH_TIMEOUT, RerunLogger
from jugglerl.runs.checkpoints import load_checkpoint, save_checkpoint
from jugglerl.runs.files import RunFileError, write_json


def test_a_checkpoint_write_that_fails_midway_leaves_the_previous_one_and_no_partial(
    tmp_path, monkeypatch
):
    path = tmp_path / "checkpoint.pt"
    save_checkpoint({"config": {}, "deploys": "actor", "frames": 1}, path)

    def fails_midway(state, file):
        file.write(b"PK\x03\x04 half a checkpoint")
        raise RuntimeError("PytorchStreamWriter failed writing file data/0: file write failed")

    monkeypatch.setattr(checkpoints.torch, "save", fails_midway)
    with pytest.raises(RunFileError) as raised:
        save_checkpoint({"config": {}, "deploys": "actor", "frames": 2}, path)
    assert str(raised.value) == (
        f"{path}: could not write it"
        " (PytorchStreamWriter failed writing file data/0: file write failed)"
    )
    monkeypatch.undo()
    assert load_checkpoint(path)["frames"] == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["checkpoint.pt"]


def test_json_is_written_whole(tmp_path):
    write_json(tmp_path / "metrics.json", {"throws": [52, 53]})
    assert (tmp_path / "metrics.json").read_text() == '{\n  "throws": [\n    52,\n    53\n  ]\n}\n'


def writer_gone(timeout_sec: float) -> None:
    """rerun's flush once its file writer stopped at a failed write."""
    raise RuntimeError("File-writer thread shut down prematurely")


def test_a_recording_whose_writer_died_closes_and_names_its_file(tmp_path, monkeypatch):
    logger = RerunLogger("train", tmp_path)
    waits = []

    def flush(timeout_sec):
        waits.append(timeout_sec)
        writer_gone(timeout_sec)

    monkeypatch.setattr(logger.experiment, "flush", flush)
    logger.log_metrics({"train/return": 1.0}, 1)
    with pytest.raises(RunFileError) as raised:
        logger.shutdown()
    assert waits == [FLUSH_TIMEOUT]
    message = str(raised.value)
    assert message.startswith(f"{logger.path}: could not write the recording (")
    assert "\n" not in message
    logger.shutdown()  # closed: a second close is a no-op


def test_an_error_inside_the_recording_is_not_masked_by_its_close(tmp_path, monkeypatch):
    with pytest.raises(ValueError, match="first failure"), RerunLogger("train", tmp_path) as log:
        monkeypatch.setattr(log.experiment, "flush", writer_gone)
        raise ValueError("the first failure")


FILL = """
import faulthandler
faulthandler.dump_traceback_later(50, exit=True)
import sys
import torch
from pathlib import Path
from jugglerl.runs.checkpoints import save_checkpoint
from jugglerl.recording import logger as logger_module
from jugglerl.recording.logger import RerunLogger
from jugglerl.runs.files import RunFileError

logger_module.FLUSH_TIMEOUT = 3.0  # the bound under test, shorter than a run's 30 s
folder = Path(sys.argv[1])
path = folder / "checkpoint.pt"
save_checkpoint({"config": {}, "deploys": "actor", "weights": torch.zeros(1000)}, path)
try:
    with RerunLogger("train", folder) as logger:
        for step in range(200_000):
            logger.log_metrics({"train/return": float(step), "train/throws": 1.0}, step)
except RunFileError as error:
    print(error)
try:
    save_checkpoint({"config": {}, "deploys": "actor", "weights": torch.ones(1_000_000)}, path)
except RunFileError as error:
    print(error)
"""


@pytest.fixture
def full_disk(tmp_path):
    """A 1 MiB tmpfs (root, where mounts are allowed), unmounted afterwards."""
    folder = tmp_path / f"tiny-{uuid.uuid4().hex[:6]}"
    folder.mkdir()
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=1M", "tmpfs", str(folder)], capture_output=True
    )
    if mounted.returncode != 0:
        pytest.skip("cannot mount a small tmpfs here (needs root and mount rights)")
    yield folder
    subprocess.run(["umount", "-l", str(folder)], check=False)


@pytest.mark.slow
def test_a_full_disk_ends_the_recording_and_the_checkpoint_with_one_line_each(full_disk):
    """Before the bounded flush, rerun's writer died at the first ENOSPC and the close waited
    forever; the subprocess's time limit turns such a hang into a failure."""
    result = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(FILL), str(full_disk)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == [
        f"{full_disk / 'train.rrd'}: could not write the recording (no space left on device)",
        f"{full_disk / 'checkpoint.pt'}: could not write it (no space left on device)",
    ]
    assert torch.equal(load_checkpoint(full_disk)["weights"], torch.zeros(1000))
    assert not list(Path(full_disk).glob("*.partial"))
