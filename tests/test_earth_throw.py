"""scripts/studies/earth_throw.py: a throw over the threshold at real gravity within the speed
limit."""

import math

import numpy as np
import pytest
from cli import run_script

from jugglerl.studies import earth_throw

#: The best throw of ``python scripts/studies/earth_throw.py`` (defaults, seed 1), as it prints
#: it: a wind-up raising the upper arm, then lift and elbow swinging up together (env=earth).
START = [-1.507, 1.675, 0.187]  # lift, elbow (rad), tilt
KNOTS = [[0.58, -0.640, 1.640], [0.246, -1.516, 0.649], [0.29, 0.0, 2.696]]  # s, lift, elbow
FOUND = np.array(START + [value for knot in KNOTS for value in knot])


def test_the_found_throw_clears_one_metre_within_pi_rad_per_s_and_the_cup_limit():
    throw = earth_throw.simulate(FOUND)
    assert throw.throws == 1 and throw.apex > 1.3
    assert max(throw.peak_speed) <= math.pi and throw.max_cup <= 0.76
    assert 0.4 < throw.landing_offset < 0.5  # it comes down away from where it left


def test_the_experts_elbow_flick_does_not_leave_the_cup_at_earth():
    # expert.yaml's throw: elbow 2.15 -> 1.5 rad with the upper arm vertical, the cup upright
    flick = np.array(
        [-1.5708, 2.15, 0.15, 0.5, -1.5708, 1.5, 0.5, -1.5708, 2.15, 0.5, -1.5708, 2.15]
    )
    throw = earth_throw.simulate(flick)
    assert throw is not None and throw.throws == 0 and throw.apex == 0.0  # never leaves
    assert max(throw.peak_speed) < 0.7 * math.pi  # the lagging servo never reaches the limit


@pytest.mark.slow
def test_a_short_search_prints_its_throw_and_bad_budgets_are_one_error_line():
    result = run_script("studies/earth_throw.py", "--restarts", "1", "--generations", "2")
    assert result.returncode == 0, result.stderr[-2000:]
    last = result.stdout.strip().splitlines()[-1]
    assert last.startswith("apex ") and "peak joint speeds" in last
    bad = run_script("studies/earth_throw.py", "--restarts", "0")
    assert bad.returncode == 2 and bad.stderr.strip().splitlines()[-1].endswith("must be >= 1")
    bad = run_script("studies/earth_throw.py", "--landing-weight", "-1")
    assert bad.returncode == 2 and bad.stderr.strip().splitlines()[-1].endswith("must be >= 0")


def test_the_score_is_the_apex_less_the_cup_overshoot_and_the_weighted_landing_distance():
    throw = earth_throw.Throw(
        apex=1.2, max_cup=0.8, peak_speed=(0.0, 1.0, 1.0), landing_offset=0.3, throws=1
    )
    assert earth_throw.score(throw, max_cup=0.76) == pytest.approx(1.2 - 0.4)
    assert earth_throw.score(throw, 0.76, landing_weight=2.0) == pytest.approx(1.2 - 0.4 - 0.6)
    assert earth_throw.score(None, 0.76) == -1.0
