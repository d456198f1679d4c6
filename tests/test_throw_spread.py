"""``scripts/studies/throw_spread.py``: how far a policy's throws scatter sideways."""

import subprocess
import sys
from pathlib import Path

import pytest

from jugglerl.policies.episodes import run_episode
from jugglerl.policies.loading import load_policy
from jugglerl_envs import JuggleEnv

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "studies"
sys.path.insert(0, str(SCRIPT))
from throw_spread import throw_velocities  # noqa: E402


def test_every_throw_is_recorded_with_its_free_flight_speed():
    env = JuggleEnv(balls=2, duration=12.0)
    balls, cups, dropped = throw_velocities(env, load_policy("two_balls", env), seed=0)
    throws = run_episode(env, load_policy("two_balls", env), seed=0).throws
    assert len(balls) == len(cups) == throws >= 7  # a throw every 1.43 s
    assert dropped is None
    assert 0 < abs(balls).max() < 0.2 and abs(cups).max() < 1.0  # m/s: thrown up, not sideways


def test_a_drop_names_the_speed_of_the_dropped_balls_last_throw():
    env = JuggleEnv(balls=2, duration=120.0, action_noise=0.003)
    balls, _, dropped = throw_velocities(env, load_policy("two_balls", env), seed=0)
    assert dropped is not None and dropped in balls[:, 0].tolist()


@pytest.mark.slow
def test_it_prints_a_row_per_noise_level():
    result = subprocess.run(
        [
            sys.executable,
            str(SCRIPT / "throw_spread.py"),
            "--seeds",
            "1",
            "--duration",
            "6",
            "--action-noise",
            "0,0.003",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.strip().splitlines()
    assert lines[0] == "two_balls, 2 ball(s), 6 s, env seeds 0-0"
    assert [line.split()[0] for line in lines[2:]] == ["0.000", "0.003"]
