"""A run file that cannot be written (a full disk) ends each tool with one ``error:`` line naming
the file, exit code 1, and no list of files written. The scripts run with a cap on the size of
any file they write (``RLIMIT_FSIZE``): a write past it fails as it would on a full disk."""

from __future__ import annotations

import re

import pytest
from cli import run_script
from test_offpolicy_training import TINY

#: ``error: PATH: could not write it|the recording|the video (cause)``
FAILED_WRITE = re.compile(
    r"^error: \S+: could not write (it|the recording|the video|the replay buffer) \(.+\)$"
)


@pytest.mark.parametrize(
    "script, overrides, limit, written",
    [
        ("evaluate.py", ["policy=closed_loop", "duration=20"], 40_000, "episode.rrd"),
        (
            "evaluate.py",
            ["policy=closed_loop", "duration=4", "video=true", "logger.scene_fps=1"],
            30_000,
            "episode.mp4",
        ),
        (
            "robustness.py",
            [
                "policies=[expert]",
                "reference=expert",
                "seeds=1",
                "duration=20",
                "select=[kicks]",
                "families.kicks.magnitudes=[0.01]",
                "workers=1",
                "progress=false",
            ],
            20_000,
            "robustness.rrd",
        ),
        (
            "train.py",  # the replay buffer's memory-mapped files, made at the first batch
            [*TINY, "actor=lstm", "replay_buffer.slice_len=16"],
            20_000_000,
            "buffers/replay",
        ),
    ],
)
@pytest.mark.slow
def test_a_file_that_cannot_be_written_is_one_line_and_a_failure(
    tmp_path, script, overrides, limit, written
):
    result = run_script(
        script, *overrides, f"hydra.run.dir={tmp_path}", file_size_limit=limit, timeout=600
    )
    assert result.returncode == 1, result.stderr
    last = result.stderr.strip().splitlines()[-1]
    assert FAILED_WRITE.match(last), result.stderr
    assert f"{tmp_path / written}: could not write" in last
    assert "Traceback" not in result.stderr
    assert "->" not in result.stdout  # the closing line that lists the files written
