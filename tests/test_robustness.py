"""The robustness benchmark: families from config, summaries, and the script end to end."""

import json

import pytest
from cli import ROOT, rrd_verifies, run_script
from omegaconf import OmegaConf

from jugglerl.recording.reading import column
from jugglerl.reports import robustness

ENV = OmegaConf.load(ROOT / "configs" / "env" / "paper.yaml")
FAMILIES = OmegaConf.create(
    {
        "kicks": {"key": "kick_speed", "magnitudes": [0.1, 0.2], "fixed": {"kick_rate": 1.0}},
        "mass": {"key": "ball_mass", "magnitudes": [0.2], "unit": "kg"},
    }
)


def test_families_come_from_config_with_their_nominal_values():
    kicks, mass = robustness.families_from_config(FAMILIES, ENV)
    assert kicks.overrides(0.2) == {"kick_rate": 1.0, "kick_speed": 0.2}
    assert (kicks.nominal, mass.nominal, mass.unit) == (0.0, 0.1, "kg")
    assert [c.family for c in robustness.conditions([kicks, mass])] == [
        "nominal",
        "kicks",
        "kicks",
        "mass",
    ]
    (only,) = robustness.families_from_config(FAMILIES, ENV, select=["mass"])
    assert only.name == "mass"


@pytest.mark.parametrize(
    "families, select, message",
    [
        ({"wind": {"key": "wind", "magnitudes": [1]}}, [], "wind is not an env argument"),
        ({"mass": {"key": "ball_mass"}}, [], "needs key and a non-empty magnitudes"),
        (FAMILIES, ["heat"], r"select=\['heat'\]: no such families; valid: kicks, mass"),
        (
            {"kicks": {"key": "kick_speed", "magnitudes": ["abc"]}},
            [],
            r"families.kicks.magnitudes=\['abc'\] must be numbers",
        ),
    ],
)
def test_bad_families_are_named(families, select, message):
    with pytest.raises(ValueError, match=message):
        robustness.families_from_config(OmegaConf.create(families), ENV, select)


def record(policy, family, magnitude, throws, seconds_up):
    return {
        "policy": policy,
        "family": family,
        "magnitude": magnitude,
        "throws": throws,
        "seconds_up": seconds_up,
    }


RECORDS = [
    record("open", "nominal", None, [40, 40], [120, 120]),
    record("closed", "nominal", None, [30, 30], [120, 120]),
    record("open", "kicks", 0.1, [20, 10], [60, 30]),
    record("closed", "kicks", 0.1, [30, 27], [120, 110]),
    record("open", "kicks", 0.2, [4, 4], [10, 12]),
    record("closed", "kicks", 0.2, [24, 24], [100, 100]),
    record("open", "mass", 0.2, [40, 36], [120, 120]),
    record("closed", "mass", 0.2, [0, 0], [2, 2]),
]


def test_rows_give_fractions_of_each_policys_own_nominal_throws():
    rows = robustness.summarise(RECORDS)
    kicks = {(r["policy"], r["magnitude"]): r for r in rows if r["family"] == "kicks"}
    assert kicks["open", 0.1]["mean_throws"] == 15
    assert kicks["open", 0.1]["fraction_of_nominal"] == 15 / 40
    assert kicks["closed", 0.2]["fraction_of_nominal"] == pytest.approx(0.8)
    assert kicks["closed", 0.1]["mean_seconds_up"] == 115


def test_breaking_points_are_where_the_reference_first_falls_below_the_fraction():
    rows = robustness.summarise(RECORDS)
    (kicks,) = robustness.breaking_points(rows, "open", 0.3)  # mass never breaks "open"
    assert kicks["family"] == "kicks" and kicks["magnitude"] == 0.2
    assert kicks["kept"] == {"open": 0.1, "closed": pytest.approx(0.8)}
    assert robustness.breaking_points(rows, "open", 0.4)[0]["magnitude"] == 0.1


@pytest.mark.slow
def test_the_script_writes_table_plot_json_and_recording(tmp_path):
    result = run_script(
        "robustness.py",
        "policies=[expert,dps_best]",
        "seeds=2",
        "duration=4",
        "workers=2",
        "select=[kicks]",
        "families.kicks.magnitudes=[0.05,0.5]",
        "families.kicks.fixed.kick_rate=20",
        "progress=false",
        f"hydra.run.dir={tmp_path}",
    )
    assert result.returncode == 0, result.stderr
    results = json.loads((tmp_path / "robustness.json").read_text())
    assert [(r["family"], r["magnitude"]) for r in results["rows"]] == [
        ("nominal", None),
        ("nominal", None),
        ("kicks", 0.05),
        ("kicks", 0.05),
        ("kicks", 0.5),
        ("kicks", 0.5),
    ]
    assert all(len(e["throws"]) == 2 for e in results["episodes"])
    nominal = [r for r in results["rows"] if r["family"] == "nominal"]
    assert all(r["mean_seconds_up"] == 4 for r in nominal)  # 4 s episodes keep the ball
    hard = [r for r in results["rows"] if r["magnitude"] == 0.5]
    assert all(r["mean_seconds_up"] < 4 for r in hard)  # 20 kicks/s of 0.5 m/s lose it
    table = (tmp_path / "robustness.md").read_text()
    assert "| kicks | 0.5 m/s | expert |" in table
    assert (tmp_path / "robustness.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    recording = tmp_path / "robustness.rrd"
    assert rrd_verifies(recording)
    steps, throws = column(recording, "robustness/kicks/expert", "Scalars:scalars", "magnitude")
    assert list(steps) == [0, 1, 2] and throws[0] == nominal[0]["mean_throws"]


def test_the_script_names_an_unknown_policy(tmp_path):
    result = run_script(
        "robustness.py",
        "policies=[expert,juggler9000]",
        "reference=expert",
        f"hydra.run.dir={tmp_path}",
    )
    assert result.returncode == 1
    assert result.stderr.strip().startswith("error: policies=juggler9000: no policy file at")
    assert "Traceback" not in result.stderr


def test_a_bad_worker_count_is_named_before_any_episode(tmp_path):
    result = run_script(
        "robustness.py",
        "policies=[expert]",
        "reference=expert",
        "workers=-1",
        f"hydra.run.dir={tmp_path}",
    )
    assert result.returncode == 1
    assert result.stderr.strip() == (
        "error: workers=-1 is out of range: expected an integer in [0, 4096]"
    )


def test_a_policy_that_cannot_load_is_named_before_the_reference(tmp_path):
    result = run_script("robustness.py", "policies=[nope]", f"hydra.run.dir={tmp_path}")
    assert result.returncode == 1
    assert result.stderr.startswith("error: ") and "nope" in result.stderr
    assert "reference" not in result.stderr and "Traceback" not in result.stderr
