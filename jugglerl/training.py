"""What ``scripts/train.py`` runs: the trainer of ``algo.trainer``, resumed or new, to the end.

Trainers (``TRAINERS``): ``offpolicy`` (``jugglerl.offpolicy.training.OffPolicyTraining``: DDPG,
TD3, behaviour cloning), ``onpolicy`` (``jugglerl.onpolicy.training.PPOTraining``: PPO) and
``search`` (``jugglerl.dps.training.SearchTraining``: DPS over a search space). All are built as
``Trainer(cfg, run_dir, state)`` (``state``: a checkpoint to resume) and offer ``run(logger,
progress)``, ``position()``, ``summary(metrics)``, ``close()`` and ``recording_id``.
"""

from __future__ import annotations

import importlib
import shutil
import sys
from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

from jugglerl.recording.logger import RerunLogger
from jugglerl.runs.checkpoints import CHECKPOINT, load_checkpoint
from jugglerl.runs.files import BUFFERS, METRICS, PARTIAL, write_atomically
from jugglerl.runs.interrupts import stop_on_interrupt

TRAINERS = {
    "offpolicy": "jugglerl.offpolicy.training:OffPolicyTraining",
    "onpolicy": "jugglerl.onpolicy.training:PPOTraining",
    "search": "jugglerl.dps.training:SearchTraining",
}


def crossed(frames: int, batch: int, every: int) -> bool:
    """True when the last ``batch`` frames passed a multiple of ``every`` (0: never): when a
    trainer evaluates and checkpoints."""
    return every > 0 and frames // every > (frames - batch) // every


def trainer_class(name: str):
    """The trainer class ``algo.trainer`` names (imported on demand: each pulls in its stack)."""
    if name not in TRAINERS:
        raise ValueError(
            f"algo.trainer={name!r} is not available; choose one of {', '.join(TRAINERS)}"
        )
    module, attribute = TRAINERS[name].split(":")
    return getattr(importlib.import_module(module), attribute)


def resume_state(resume: str, cfg: DictConfig, overrides: list[str]) -> tuple:
    """(config, run directory, checkpoint) of ``resume=PATH``: the checkpoint's config with the
    command line's ``overrides`` (other than ``resume`` and Hydra's own) applied on top, before
    its interpolations are resolved (checkpoints older than ``config_unresolved``: after)."""
    try:
        state = load_checkpoint(resume)
    except ValueError as error:
        raise ValueError(f"resume: {error}") from None
    path = Path(resume)
    saved = OmegaConf.create(state.get("config_unresolved", state["config"]))
    keys = [override.split("=", 1)[0].lstrip("+~") for override in overrides]
    if "algo" in keys and cfg.algo.name != saved.algo.name:
        raise ValueError(
            f"resume: {resume} is an algo={saved.algo.name} run and continues as one;"
            f" algo={cfg.algo.name} needs a new run"
        )
    for key in keys:
        if key != "resume" and not key.startswith("hydra"):
            OmegaConf.update(saved, key, OmegaConf.select(cfg, key), force_add=True)
    return saved, path if path.is_dir() else path.parent, state


def check_cluster(cfg: DictConfig, sweeping: bool) -> None:
    """``ValueError`` for a ``cluster=`` that a run would ignore: an off-policy run trains in
    this process, so outside a sweep (whose jobs the cluster runs) only ``local`` applies."""
    if not sweeping and cfg.algo.trainer == "offpolicy" and cfg.cluster.name != "local":
        raise ValueError(
            f"cluster={cfg.cluster.name}: an off-policy run trains in this process; a cluster runs"
            " the searches' roll-outs (algo=dps|feedback|closed_loop|throw_catch) and a sweep's"
            " jobs (-m)"
        )


def prepare_run_folder(run_dir: Path, resuming: bool, overwrite: bool) -> None:
    """Make ``run_dir`` ready for a run: ``ValueError`` if a new run would mix its files with
    another run's there (unless ``overwrite``: then that run's files go); stale partial
    writes go; a resumed run's old ``metrics.json`` goes, as it is unfinished until it ends; a
    new run's folder loses the replay buffers of a run killed before its first checkpoint."""
    found = [name for name in (CHECKPOINT, METRICS) if (run_dir / name).exists()]
    if found and not resuming and not overwrite:
        raise ValueError(
            f"{run_dir} holds another run ({', '.join(found)}): continue it with resume={run_dir},"
            " or start this one in another folder (hydra.run.dir=DIR) or over it (overwrite=true)"
        )
    stale = [run_dir / METRICS, *run_dir.glob(f"*{PARTIAL}")]
    if not resuming:
        stale += [run_dir / CHECKPOINT, *run_dir.glob("*.rrd")]
    for path in stale:
        path.unlink(missing_ok=True)
    if not resuming:
        shutil.rmtree(run_dir / BUFFERS, ignore_errors=True)


def save_hydra_record(run_dir: Path, cfg: DictConfig) -> None:
    """Hydra's record of a new run in ``run_dir/.hydra``: ``config.yaml`` (the run's config),
    ``hydra.yaml`` and ``overrides.yaml``. ``configs/train.yaml`` sets ``hydra.output_subdir:
    null`` so that Hydra does not write them before the run folder is checked: a command refused
    in another run's folder leaves that run's record as it was. Called outside a Hydra app (a
    test calling ``train``), it writes nothing."""
    if not HydraConfig.initialized():
        return
    hydra = HydraConfig.get()
    folder = run_dir / ".hydra"
    folder.mkdir(parents=True, exist_ok=True)
    records = {
        "config.yaml": cfg,
        "hydra.yaml": OmegaConf.create({"hydra": hydra}),
        "overrides.yaml": hydra.overrides.task,
    }
    for name, content in records.items():
        write_atomically(
            folder / name, lambda file, c=content: file.write(OmegaConf.to_yaml(c).encode())
        )


def train(cfg: DictConfig, run_dir: Path, state: dict | None) -> None:
    """Run ``cfg``'s trainer in ``run_dir`` (resumed from ``state``), recording to its ``.rrd``;
    print the result, or on Ctrl-C how to continue. The first Ctrl-C stops the run, the later
    ones are ignored while it saves and closes (``jugglerl.runs.interrupts``)."""
    with stop_on_interrupt():
        try:
            training = trainer_class(cfg.algo.trainer)(cfg, run_dir, state)  # a bad config fails
        except KeyboardInterrupt:
            sys.exit("interrupted while the run was being set up: nothing written")
        _train(training, cfg, run_dir, state)


def _train(training, cfg: DictConfig, run_dir: Path, state: dict | None) -> None:
    """``train`` once its trainer is built: the folder checked and prepared, the run recorded."""
    try:
        prepare_run_folder(run_dir, state is not None, bool(cfg.get("overwrite", False)))
    except ValueError:
        training.close()
        raise
    if state is None:
        save_hydra_record(run_dir, cfg)
    else:
        print(f"resuming {run_dir} at {training.position()}")
    try:
        with RerunLogger.from_config(
            cfg.logger, run_dir, recording_id=training.recording_id
        ) as logger:
            training.recording_id = logger.recording_id
            if state is None:
                logger.log_hparams(cfg)
            metrics = training.run(logger, progress=cfg.progress)
    except KeyboardInterrupt:
        sys.exit(
            f"interrupted at {training.position()}: checkpoint in {run_dir / CHECKPOINT};"
            f" continue with: python scripts/train.py resume={run_dir}"
        )
    finally:
        training.close()
    print(training.summary(metrics))
    files = sorted(p.name for p in run_dir.iterdir() if p.suffix in (".pt", ".yaml", ".json"))
    files.append(logger.path.name)
    if (run_dir / BUFFERS).is_dir():
        size = disk_megabytes(run_dir / BUFFERS)
        files.append(f"{BUFFERS}/ ({size:.0f} MB, which a resume reads)")
    print(f"-> {run_dir}: {', '.join(files)}")


def disk_megabytes(folder: Path) -> float:
    """The disk space the files under ``folder`` take (sparse files count what they hold)."""
    return sum(path.stat().st_blocks * 512 for path in folder.rglob("*") if path.is_file()) / 1e6
