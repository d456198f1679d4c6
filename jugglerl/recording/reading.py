"""Read JuggleRL recordings back with rerun's own reader (no viewer needed).

Used by the tests to check what was logged, and by ``scripts/plot_recording.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
from rerun.chunk import RrdReader


def entities(path: Path) -> set[str]:
    """Entity paths in the recording, without the leading slash."""
    return {chunk.entity_path.lstrip("/") for chunk in RrdReader(path).stream()}


def timelines(path: Path) -> set[str]:
    return {name for chunk in RrdReader(path).stream() for name in chunk.timeline_names}


def column(path: Path, entity: str, component: str, timeline: str | None = None):
    """Values of ``component`` (e.g. ``"Scalars:scalars"``) logged at ``entity``.

    Returns ``(times, values)`` sorted by time on ``timeline`` (``None`` for static data: times
    is then empty). Values are stacked into an array of one row per logged row. Time columns in
    seconds for durations, integers for sequences.
    """
    times, values = [], []
    for chunk in RrdReader(path).stream():
        if chunk.entity_path.lstrip("/") != entity:
            continue
        batch = chunk.to_record_batch()
        if component not in batch.schema.names:
            continue
        if timeline is not None:
            if timeline not in batch.schema.names:
                continue
            times.append(_time_values(batch.column(timeline)))
        values.extend(_row_values(batch.column(component)))
    if timeline is None:
        return np.array([]), np.array(values)
    times = np.concatenate(times) if times else np.array([])
    order = np.argsort(times, kind="stable")
    return times[order], np.array(values)[order]


def _time_values(array: pa.Array) -> np.ndarray:
    if pa.types.is_duration(array.type):
        return array.cast(pa.int64()).to_numpy() / 1e9
    return array.to_numpy()


def _row_values(array: pa.Array) -> list:
    """One value per row: the single element of each row's list (a scalar or a vector)."""
    rows = []
    for row in array.to_pylist():
        rows.append(row[0] if isinstance(row, list) and len(row) == 1 else row)
    return rows
