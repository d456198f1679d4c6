"""Train a juggling policy; everything lands in the run directory.

python scripts/train.py                                       # LSTM clone of closed_loop_centred
python scripts/train.py actor=lstm                            # the same (the Quickstart's command)
python scripts/train.py actor=mlp                             # the same with an MLP actor
python scripts/train.py algo=ddpg actor=lstm reward=contacts  # DDPG alone, the paper's reward 3
python scripts/train.py algo=td3 actor=lstm                   # TD3 (twin critics, delayed actor)
python scripts/train.py algo=bc teacher.policy=closed_loop    # behaviour cloning of a teacher
python scripts/train.py algo.loss=td3 teacher.policy=closed_loop_tolerant  # TD3 in the RL stage
python scripts/train.py algo=dps                              # eREPS from the expert, 500 roll-outs
python scripts/train.py algo=feedback                         # closed loop: eREPS over its gains
python scripts/train.py algo=throw_catch                      # earth: throw, catch, carry back
python scripts/train.py resume=outputs/train/<algo>/<run>     # continue from its checkpoint
python scripts/train.py algo=dps cluster=ray cluster.address=HEAD:6379  # roll-outs on Ray
python scripts/train.py -m seed=0,1,2 cluster=ray             # a sweep's jobs as Ray tasks
python scripts/evaluate.py policy=outputs/train/<algo>/<run>  # run what it deploys
rerun outputs/train/<algo>/<run>/train.rrd                    # learning curves, episodes
"""

from __future__ import annotations

import sys
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import DictConfig

from jugglerl.cluster import register_sweep_launcher
from jugglerl.config.command_line import check_override_types, exit_on_bad_command_line
from jugglerl.runs.files import RunFileError
from jugglerl.training import check_cluster, resume_state, train


@hydra.main(version_base="1.3", config_path="../configs", config_name="train")
def main(cfg: DictConfig) -> None:
    run_dir = Path(HydraConfig.get().runtime.output_dir)
    try:
        check_override_types()
        check_cluster(cfg, HydraConfig.get().mode == RunMode.MULTIRUN)
        state = None
        if cfg.resume is not None:
            overrides = list(HydraConfig.get().overrides.task)
            cfg, run_dir, state = resume_state(cfg.resume, cfg, overrides)
        train(cfg, run_dir, state)
    except (ValueError, RunFileError) as error:
        sys.exit(f"error: {error}")


if __name__ == "__main__":
    exit_on_bad_command_line("train")
    register_sweep_launcher()
    main()
