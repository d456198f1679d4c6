"""Comparing two policies start by start (jugglerl/reports/paired.py, scripts/compare_starts.py)."""

import json

import pytest
from cli import run_script

from jugglerl.reports.paired import markdown, pair

ENV = {"gravity": -2.0, "action_noise": 0.0}


def benchmark(episodes: dict, seeds: int = 4, duration: float = 120.0) -> dict:
    """A benchmark's JSON: ``episodes`` maps (policy, family, magnitude) to (throws, seconds up)."""
    return {
        "config": {"env": ENV, "seeds": seeds, "duration": duration},
        "episodes": [
            {"policy": p, "family": f, "magnitude": m, "throws": t, "seconds_up": s}
            for (p, f, m), (t, s) in episodes.items()
        ],
    }


FULL = [120.0] * 4
A = benchmark(
    {
        ("a", "nominal", None): ([50, 50, 50, 50], FULL),
        ("a", "action_noise", 0.003): ([48, 10, 49, 47], [120.0, 30.0, 120.0, 120.0]),
    }
)
B = benchmark({("b", "action_noise", 0.003): ([47, 45, 2, 46], [120.0, 120.0, 5.0, 120.0])})


def test_pairs_the_starts_of_the_conditions_both_measured():
    (noisy,) = pair(A, "a", B, "b")
    assert (noisy.family, noisy.magnitude) == ("action_noise", 0.003)
    mean, error = noisy.difference  # differences 1, -35, 47, 1
    assert mean == pytest.approx(3.5)
    assert error == pytest.approx(33.60 / 2, abs=0.01)  # their std (ddof 1) over sqrt(4)
    assert noisy.a_dropped.tolist() == [False, True, False, False]
    row = markdown([noisy], "a", "b").splitlines()[2]
    assert row == "| action_noise 0.003 | 38.5 | 35.0 | +3.5 ± 16.8 | 3 / 1 / 0 | 1 / 1 of 4 |"


def test_refuses_benchmarks_from_other_starts_or_without_the_policy():
    with pytest.raises(ValueError, match="not the same starts"):
        pair(A, "a", {**B, "config": {**B["config"], "seeds": 30}}, "b")
    with pytest.raises(ValueError, match="no episodes of c .it has b"):
        pair(A, "a", B, "c")


def test_the_script_prints_the_table_and_fails_in_one_line(tmp_path):
    (tmp_path / "a.json").write_text(json.dumps(A))
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "robustness.json").write_text(json.dumps(B))
    done = run_script("compare_starts.py", str(tmp_path / "a.json"), "a", str(tmp_path / "b"), "b")
    assert done.returncode == 0, done.stderr
    assert "| action_noise 0.003 | 38.5 | 35.0 | +3.5 ± 16.8 |" in done.stdout
    done = run_script("compare_starts.py", str(tmp_path / "a.json"), "a", str(tmp_path), "b")
    assert done.returncode == 1
    assert done.stderr.strip().startswith("error:") and len(done.stderr.strip().splitlines()) == 1
