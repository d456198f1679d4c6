"""What ``scripts/dps_table.py`` and ``scripts/ddpg_table.py`` share: finding the runs' metrics
below a folder, rendering a Markdown table, and the command line around both."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path


def run_metrics(folder: Path, file_name: str) -> Iterator[dict]:
    """The parsed ``file_name`` of every run below ``folder``, in path order."""
    for path in sorted(folder.rglob(file_name)):
        yield json.loads(path.read_text())


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    lines += ["| " + " | ".join(cells) + " |" for cells in rows]
    return "\n".join(lines)


def table_main(
    doc: str, load_runs: Callable[[Path], Mapping], table: Callable[[Mapping], str], what: str
) -> None:
    """Parse ``folder`` from the command line and print ``table(load_runs(folder))``; no runs
    end with one ``error:`` line naming ``what``."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("folder", type=Path, help="a multirun folder (or any folder of runs)")
    args = parser.parse_args()
    runs = load_runs(args.folder)
    if not runs:
        sys.exit(f"error: no {what} below {args.folder}")
    print(table(runs))
