"""``RerunLogger``: a TorchRL logger that writes one rerun recording per run."""

from __future__ import annotations

import threading
import time
import uuid
import warnings
import weakref
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
import yaml
from omegaconf import DictConfig, OmegaConf
from rerun.chunk import RrdReader
from torchrl.record.loggers import Logger

from jugglerl.recording.names import HPARAMS, STEP
from jugglerl.runs.files import RunFileError, failure

APP_ID = "jugglerl"
#: The longest a flush waits for the recording's file writer, in seconds.
FLUSH_TIMEOUT = 30.0
#: The longest the close of a failed recording may take, in seconds.
CLOSE_TIMEOUT = 5.0


class RerunLogger(Logger):
    """Logs to ``<log_dir>/<exp_name>.rrd`` (headless), optionally streaming to a live viewer too.

    Scalars land on the ``step`` timeline, at the entity path given by their name
    (``train/return``, ``eval/throws``). They are buffered and sent in columns, one chunk per name,
    at most every ``flush_every`` seconds: a rerun log call costs ~25 µs, a buffered value ~1 µs.

    The file is complete (footer written) only after ``shutdown()``. Use the logger as a context
    manager so that an exception or Ctrl-C still closes it; a finaliser closes it at interpreter
    exit as a last resort. An existing file is never overwritten: the next free name
    ``<exp_name>.1.rrd``, ``.2``... is used (a resumed run keeps its ``recording_id``, so the
    viewer merges the files of one run when they are opened together).

    Args:
        exp_name: file stem of the recording.
        log_dir: folder of the recording (created if missing).
        live_url: also stream to a running viewer at this gRPC url
            (``rerun+http://127.0.0.1:9876/proxy`` is the viewer's default); ``None``: file only.
        recording_id: rerun recording id; a fresh one when ``None``. To continue a run's
            recording after a resume, pass the id saved in ``state_dict()["local"]``.
        flush_every: seconds between automatic sends of buffered scalars.
    """

    def __init__(
        self,
        exp_name: str,
        log_dir: str | Path,
        *,
        live_url: str | None = None,
        recording_id: str | None = None,
        flush_every: float = 2.0,
    ):
        self.live_url = live_url
        self.recording_id = recording_id or uuid.uuid4().hex
        self.flush_every = flush_every
        self.path = _free_path(Path(log_dir), exp_name)
        self._pending: dict[str, tuple[list[int], list[float]]] = {}
        self._last_send = time.monotonic()
        self._last_step = 0
        super().__init__(exp_name=exp_name, log_dir=str(log_dir))
        self._close_at_exit = weakref.finalize(self, self.experiment.disconnect)

    @classmethod
    def from_config(cls, cfg: DictConfig, log_dir: str | Path, **kwargs) -> RerunLogger:
        """A logger from the ``configs/logger/rerun.yaml`` group (``name``, ``live_url``, ...)."""
        return cls(cfg.name, log_dir, live_url=cfg.live_url, flush_every=cfg.flush_every, **kwargs)

    def _create_experiment(self) -> rr.RecordingStream:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        stream = rr.RecordingStream(APP_ID, recording_id=self.recording_id)
        sinks = [rr.FileSink(str(self.path))]
        if self.live_url:
            sinks.append(rr.GrpcSink(self.live_url))
        try:
            stream.set_sinks(*sinks)
        except RuntimeError as error:  # the file sink's first write failed (a full disk)
            raise failure(self.path, "write the recording", error) from None
        return stream

    @property
    def recording(self) -> rr.RecordingStream:
        """The rerun stream, for recorders that log into the same file (e.g. episodes)."""
        return self.experiment

    # --- scalars --------------------------------------------------------------------------
    def log_scalar(self, name: str, value: float, step: int | None = None) -> None:
        """Buffer ``value`` at ``step`` (the last step used when ``None``) for entity ``name``."""
        step = self._last_step if step is None else int(step)
        self._last_step = step
        steps, values = self._pending.setdefault(name, ([], []))
        steps.append(step)
        values.append(float(value))
        if time.monotonic() - self._last_send >= self.flush_every:
            self._send_scalars()

    def _send_scalars(self) -> None:
        # numpy arrays: rerun converts Python lists element by element, ~15x slower
        for name, (steps, values) in self._pending.items():
            self.experiment.send_columns(
                name,
                indexes=[rr.TimeColumn(STEP, sequence=np.asarray(steps))],
                columns=rr.Scalars.columns(scalars=np.asarray(values)),
            )
        self._pending.clear()
        self._last_send = time.monotonic()

    # --- other records --------------------------------------------------------------------
    def log_hparams(self, cfg: DictConfig | Mapping[str, Any]) -> None:
        """The run's configuration, as a YAML text document at entity ``hparams`` (static)."""
        if isinstance(cfg, DictConfig):
            text = OmegaConf.to_yaml(cfg, resolve=True)
        else:
            text = yaml.safe_dump(dict(cfg), sort_keys=False)
        document = f"```yaml\n{text}```\n"
        self.experiment.log(
            HPARAMS, rr.TextDocument(document, media_type="text/markdown"), static=True
        )

    def log_table(self, name: str, values: Mapping[str, float]) -> None:
        """``values`` as a two-column markdown table at entity ``name`` (static): a result that
        is logged once reads better as text than as a single point in a plot."""
        rows = "".join(f"| {key} | {value:g} |\n" for key, value in values.items())
        document = f"| metric | value |\n| --- | --- |\n{rows}"
        self.experiment.log(
            name, rr.TextDocument(document, media_type="text/markdown"), static=True
        )

    def log_histogram(
        self, name: str, data: Sequence, step: int | None = None, bins: int = 30, **kwargs
    ) -> None:
        """A histogram of ``data`` as a bar chart at entity ``name`` on the ``step`` timeline."""
        counts, edges = np.histogram(np.asarray(data, dtype=np.float64).ravel(), bins=bins)
        centres = (edges[:-1] + edges[1:]) / 2
        self._log_at_step(name, step, rr.BarChart(counts, abscissa=centres, widths=np.diff(edges)))

    def log_video(self, name: str, video, step: int | None = None, **kwargs) -> None:
        """Frames of a ``[T, C, H, W]`` (or ``[T, H, W, C]``) uint8 video as images at ``name``.

        The frames sit on a ``video_frame`` timeline, all at the same ``step``.
        """
        frames = np.asarray(video)
        if frames.ndim != 4:
            raise ValueError(f"video must be [T, C, H, W] or [T, H, W, C], got {frames.shape}")
        if frames.shape[1] in (1, 3, 4) and frames.shape[-1] not in (1, 3, 4):
            frames = frames.transpose(0, 2, 3, 1)
        for index, frame in enumerate(frames):
            self.experiment.set_time("video_frame", sequence=index)
            self._log_at_step(name, step, rr.Image(frame))
        self.experiment.disable_timeline("video_frame")

    def send_blueprint(self, blueprint: rrb.Blueprint) -> None:
        """Make ``blueprint`` the recording's default layout."""
        self.experiment.send_blueprint(blueprint, make_active=True, make_default=True)

    def _log_at_step(self, name: str, step: int | None, archetype) -> None:
        step = self._last_step if step is None else int(step)
        self.experiment.set_time(STEP, sequence=step)
        self.experiment.log(name, archetype)
        self.experiment.disable_timeline(STEP)

    # --- life cycle -----------------------------------------------------------------------
    def flush(self, timeout: float | None = None) -> None:
        """Send buffered scalars and push everything to the sinks, waiting at most ``timeout``
        seconds (``FLUSH_TIMEOUT`` if ``None``). A file that cannot be written (a full disk)
        closes the recording and raises ``RunFileError`` naming it: rerun's writer stops at
        the first failed write, and an unbounded flush then waited forever."""
        if self._service_shutdown:
            return
        self._send_scalars()
        try:
            self.experiment.flush(timeout_sec=FLUSH_TIMEOUT if timeout is None else timeout)
        except RuntimeError as error:  # "File-writer thread shut down prematurely"
            self._abandon()
            raise failure(self.path, "write the recording", error) from None

    def _abandon(self) -> None:
        """Give up a recording whose writer died: rerun's ``disconnect`` then sometimes waits
        forever, so it runs in a daemon thread given ``CLOSE_TIMEOUT`` seconds; if it is still
        waiting, so would rerun's own close at interpreter exit, which is then skipped."""
        self._service_shutdown = True
        closing = threading.Thread(target=self._close_at_exit, daemon=True)
        closing.start()
        closing.join(CLOSE_TIMEOUT)
        if closing.is_alive():
            rr.unregister_shutdown()

    def shutdown(self, timeout: float | None = None) -> None:
        """Flush, then close the file (writes its footer). Safe to call more than once. A file
        left without its footer (rerun's writer reports no failure of that last write: a disk
        that filled up at the end) raises ``RunFileError`` naming it."""
        if self._service_shutdown:
            return
        self.flush(timeout)
        self._close_at_exit()
        self._service_shutdown = True
        if not has_footer(self.path):
            raise failure(self.path, "write the recording", "its footer is missing")

    def __enter__(self) -> RerunLogger:
        return self

    def __exit__(self, exc_type, *exc_info) -> None:
        try:
            self.shutdown()
        except RunFileError:
            if exc_type is None:  # else the error already raised is the one to report
                raise

    def _checkpoint_state(self) -> dict[str, Any]:
        return {"recording_id": self.recording_id, "last_step": self._last_step}

    def _load_checkpoint_state(self, state_dict: Mapping[str, Any]) -> None:
        self._last_step = int(state_dict.get("last_step", self._last_step))

    def __repr__(self) -> str:
        return f"RerunLogger(path={str(self.path)!r}, recording_id={self.recording_id!r})"


def has_footer(path: Path) -> bool:
    """Whether the ``.rrd`` file at ``path`` ends with its footer (rerun's reader warns when it
    does not, and then scans the whole file)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        RrdReader(str(path))
    return not any("no footer" in str(warning.message) for warning in caught)


def _free_path(folder: Path, stem: str) -> Path:
    """``folder/stem.rrd``, or ``folder/stem.K.rrd`` with the first K that does not exist yet."""
    path = folder / f"{stem}.rrd"
    index = 0
    while path.exists():
        index += 1
        path = folder / f"{stem}.{index}.rrd"
    return path
