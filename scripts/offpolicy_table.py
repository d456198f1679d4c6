"""Summarise off-policy runs as a Markdown table: one row per algorithm, reward and actor.

    python scripts/train.py -m algo=ddpg,td3 seed=0,1,2 hydra.sweep.dir=outputs/compare
    python scripts/offpolicy_table.py outputs/compare

Reports each run's final evaluation (``eval.seeds`` deterministic episodes of ``env.duration``
from the standard start): catch rate (the ball caught and kept up for ``eval.catch_time``), mean
throws, mean time the ball stayed up, and the run's frames and wall time; runs of the same
algorithm, reward and actor (seeds) are averaged. See ``jugglerl.reports.run_tables``.
"""

from jugglerl.reports.run_tables import offpolicy_table, table_main

if __name__ == "__main__":
    table_main(__doc__, offpolicy_table, "off-policy")
