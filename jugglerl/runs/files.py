"""Writing a run's files so that a failed write loses nothing and says so in one line.

``write_atomically(path, write)`` has ``write`` fill ``PATH.partial``, flushes it to the disk and
only then renames it over ``path``: a crash or a full disk mid-write leaves the previous file
intact and no partial one behind. A failure raises ``RunFileError`` naming the file and the
cause, which the scripts print as one ``error: …`` line.
"""

from __future__ import annotations

import functools
import json
import os
import shutil
import sys
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO

#: Below this many free bytes a failed write is put down to a full disk.
FULL_DISK_BYTES = 1 << 20
#: A run's results, written when it finishes: a run folder without it holds an unfinished run.
METRICS = "metrics.json"
PARTIAL = ".partial"
#: The folder of an off-policy run's replay buffers (memory-mapped frames; a resume reopens them).
BUFFERS = "buffers"


class RunFileError(RuntimeError):
    """A run's file could not be written; the message names it and the cause."""


def failure(path: Path, action: str, cause: object) -> RunFileError:
    """The ``RunFileError`` of ``action`` (``"write it"``) on ``path`` failing with ``cause``;
    a nearly full disk is named as the cause whatever the writer reported."""
    try:
        full = shutil.disk_usage(path.parent).free < FULL_DISK_BYTES
    except OSError:
        full = False
    reason = "no space left on device" if full else str(cause)
    return RunFileError(f"{path}: could not {action} ({reason})")


def write_atomically(path: Path, write: Callable[[BinaryIO], None]) -> None:
    """``write(file)`` into ``PATH.partial``, fsynced, then renamed over ``path``."""
    partial = path.with_name(path.name + PARTIAL)
    try:
        with open(partial, "wb") as file:
            write(file)
            file.flush()
            os.fsync(file.fileno())
        os.replace(partial, path)
    except (OSError, RuntimeError) as error:  # torch's zip writer raises RuntimeError
        reported = failure(path, "write it", error)  # while the partial file still fills the disk
        partial.unlink(missing_ok=True)
        raise reported from None


def write_json(path: Path, data: object) -> None:
    """``data`` as indented JSON, atomically."""
    text = json.dumps(data, indent=2) + "\n"
    write_atomically(path, lambda file: file.write(text.encode()))


def exits_on_run_file_errors(main: Callable) -> Callable:
    """``main`` (a script's Hydra entry point) ending with one ``error: …`` line and exit code 1
    when a run file cannot be written, wherever that happens, instead of a traceback."""

    @functools.wraps(main)
    def guarded(*args, **kwargs):
        try:
            return main(*args, **kwargs)
        except RunFileError as error:
            sys.exit(f"error: {error}")

    return guarded
