"""Robustness benchmark: throws of each policy under growing perturbations of the world.

python scripts/robustness.py                                  # expert and best DPS command
python scripts/robustness.py 'policies=[dps_best,outputs/train/ddpg/<run>]' seeds=20
python scripts/robustness.py seeds=2 duration=10 'select=[kicks]' 'families.kicks.magnitudes=[0.1]'
python scripts/robustness.py cluster=ray cluster.address=HEAD:6379  # the episodes as Ray tasks

Writes to the run directory (``outputs/robustness/<time>``): ``robustness.md`` (the table, and
where the reference open-loop policy breaks), ``robustness.json`` (every episode's throws and
time up), ``robustness.png`` (mean throws against magnitude, one line per policy) and
``robustness.rrd`` (the table, the plot, and each line as scalars on a ``magnitude`` timeline at
``robustness/<family>/<policy>``). Families and magnitudes: ``configs/robustness.yaml``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import hydra
import rerun as rr
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf
from tqdm import tqdm

from jugglerl.cluster import register_sweep_launcher
from jugglerl.config.command_line import check_override_types, exit_on_bad_command_line
from jugglerl.config.envs import make_juggle_env
from jugglerl.policies.loading import load_named_policy
from jugglerl.recording.logger import RerunLogger
from jugglerl.reports import robustness
from jugglerl.runs.files import exits_on_run_file_errors, write_atomically, write_json
from jugglerl_envs.validation import check_number

ROOT = "robustness"


def log_to_rerun(logger: RerunLogger, rows: list[dict], table: str, plot_path: Path) -> None:
    """The table and plot as static entities, and each policy's line as scalars per family."""
    stream = logger.recording
    stream.log(f"{ROOT}/table", rr.TextDocument(table, media_type="text/markdown"), static=True)
    stream.log(f"{ROOT}/plot", rr.EncodedImage(path=plot_path), static=True)
    for (family, policy), throws in robustness.throws_lines(rows).items():
        entity = f"{ROOT}/{family}/{policy.replace('/', '_')}"
        for index, value in enumerate(throws):  # index 0 is the nominal env
            stream.set_time("magnitude", sequence=index)
            stream.log(entity, rr.Scalars(value))
    stream.disable_timeline("magnitude")


@hydra.main(version_base="1.3", config_path="../configs", config_name="robustness")
@exits_on_run_file_errors
def main(cfg: DictConfig) -> None:
    run_dir = Path(HydraConfig.get().runtime.output_dir)
    policies = [str(p) for p in cfg.policies]
    try:
        check_override_types()
        check_number("workers", cfg.workers, 0, 4096, integer=True)  # 0: one per core
        check_number("seeds", cfg.seeds, 1, 100000, integer=True)
        families = robustness.families_from_config(cfg.families, cfg.env, cfg.select)
        with make_juggle_env(cfg.env) as template:  # a policy that cannot load names itself
            for policy in policies:
                load_named_policy("policies", policy, template)
        if cfg.reference not in policies:
            raise ValueError(f"reference={cfg.reference} must be one of policies={policies}")
        episodes = len(policies) * len(robustness.conditions(families)) * cfg.seeds
        bar = tqdm(total=episodes, desc="robustness", unit="episode", disable=not cfg.progress)
        with bar:
            records = robustness.measure(
                policies,
                cfg.env,
                families,
                cfg.seeds,
                cfg.duration,
                cfg.workers,
                on_episode=bar.update,
                cluster=cfg.cluster,
            )
    except ValueError as error:
        sys.exit(f"error: {error}")
    except KeyboardInterrupt:
        sys.exit("interrupted: nothing written (the benchmark writes its results at the end)")

    rows = robustness.summarise(records)
    points = robustness.breaking_points(rows, cfg.reference, cfg.breaking_fraction)
    table = robustness.markdown(rows, families, points)
    run_dir.mkdir(parents=True, exist_ok=True)
    write_atomically(run_dir / "robustness.md", lambda file: file.write(table.encode()))
    results = {
        "config": OmegaConf.to_container(cfg, resolve=True),
        "rows": rows,
        "breaking_points": points,
        "episodes": records,
    }
    write_json(run_dir / "robustness.json", results)
    plot_path = robustness.plot(rows, families, run_dir / "robustness.png")
    with RerunLogger.from_config(cfg.logger, run_dir) as logger:
        logger.log_hparams(cfg)
        log_to_rerun(logger, rows, table, plot_path)
    print(table)
    print(f"-> {run_dir}: robustness.md, robustness.json, robustness.png, {logger.path.name}")


if __name__ == "__main__":
    exit_on_bad_command_line("robustness")
    register_sweep_launcher()
    main()
