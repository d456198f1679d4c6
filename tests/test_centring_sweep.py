"""``scripts/studies/centring_sweep.py``: a grid of a feedback policy's centring gains."""

import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "studies" / "centring_sweep.py"


def sweep(*arguments: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(SCRIPT), *arguments], capture_output=True, text=True, timeout=300
    )


@pytest.mark.slow
def test_it_prints_a_row_per_pair_of_gains():
    result = sweep("--gains", "0:0,0.02:0.015", "--seeds", "1", "--duration", "6", "--workers", "1")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.strip().splitlines()
    assert lines[0] == "two_balls_searched, 2 ball(s), 6 s; mean throws over env seeds 1000-1000"
    rows = [line.split() for line in lines[2:]]
    assert [row[:2] for row in rows] == [["0.000", "0.000"], ["0.020", "0.015"]]
    assert all(int(row[2]) >= 3 and len(row) == 7 for row in rows)  # a throw every 1.43 s


def test_a_policy_that_is_not_a_feedback_policy_is_one_line():
    result = sweep("--policy", "expert", "--balls", "1")
    assert result.returncode == 1
    assert result.stderr.strip() == (
        "centring_sweep.py: expert is not a feedback policy (kind: feedback)"
    )
