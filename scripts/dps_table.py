"""Summarise search runs as a Markdown table: one row per update rule, medians over seeds.

    python scripts/train.py -m algo=dps algo.update=greedy,weighted,elite,ereps seed=0,1,2
    python scripts/dps_table.py outputs/train/dps/multirun/<date_time>

Columns: seeds, best throws (median and per seed), roll-outs to the first θ with >= 39 and >= 60
throws (median over the seeds that got there, and how many did), and the best θ's mean fraction
of its throws kept with start noise (the run's ``noise_check``); ``jugglerl.reports.run_tables``.
"""

from jugglerl.reports.run_tables import search_table, table_main

if __name__ == "__main__":
    table_main(__doc__, search_table, "search")
