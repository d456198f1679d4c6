"""Via-point commands: timing, file format, errors, and the shipped expert."""

import numpy as np
import pytest

from jugglerl.commands import CommandError, ViaPointCommand, load_command, save_command
from jugglerl.policies.command import CommandPolicy
from jugglerl.policies.episodes import run_episode
from jugglerl.runs.policy_files import PolicyFileError
from jugglerl_envs import JuggleEnv


def test_setpoints_follow_via_points_and_wrap_around_the_cycle():
    command = ViaPointCommand(2.0, ((0.5, -1.0, 1.0), (1.5, -1.2, 2.0)), pan=0.1)
    np.testing.assert_allclose(command.setpoints(0.0), [0.1, -1.2, 2.0])  # before t_1: last point
    np.testing.assert_allclose(command.setpoints(0.5), [0.1, -1.0, 1.0])
    np.testing.assert_allclose(command.setpoints(1.49), [0.1, -1.0, 1.0])
    np.testing.assert_allclose(command.setpoints(1.5), [0.1, -1.2, 2.0])
    np.testing.assert_allclose(command.setpoints(2.7), [0.1, -1.0, 1.0])  # next cycle


def test_lead_in_holds_the_cycles_start_pose_then_plays_the_cycle_later():
    cyclic = ViaPointCommand(2.0, ((0.5, -1.0, 1.0), (1.5, -1.2, 2.0)), pan=0.1)
    led = ViaPointCommand(2.0, cyclic.via_points, pan=0.1, lead_in=0.7)
    np.testing.assert_allclose(led.setpoints([0.0, 0.69]), cyclic.setpoints([0.0, 0.0]))
    times = np.linspace(0.7, 6.0, 200)
    np.testing.assert_allclose(led.setpoints(times), cyclic.setpoints(times - 0.7))
    np.testing.assert_allclose(led.cycle_setpoints(times), cyclic.setpoints(times))
    with pytest.raises(CommandError, match="lead_in=-0.1 must be a number of seconds >= 0"):
        ViaPointCommand(2.0, cyclic.via_points, lead_in=-0.1)


def test_save_and_load_round_trip(tmp_path):
    command = ViaPointCommand(2.5, ((0.0, -1.5, 2.1), (1.2, -1.5, 1.4)), lead_in=0.5, name="mine")
    for suffix in (".yaml", ".json"):
        assert load_command(save_command(command, tmp_path / f"c{suffix}")) == command


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("cycle: 3.0\n", "missing key 'via_points'"),
        (
            "cycle: 3.0\nvia_points: [[0.0, -1.5, 2.0], [0.0, -1.5, 1.5]]\n",
            "must increase strictly",
        ),
        ("cycle: 1.0\nvia_points: [[0.0, -1.5, 2.0], [1.5, -1.5, 1.5]]\n", "within [0, cycle=1.0)"),
        ("cycle: -1\nvia_points: [[0.0, -1.5, 2.0]]\n", "cycle=-1.0 must be a positive"),
        ("cycle: 3.0\nvia_points: [[0.0, -1.5]]\n", "via_points must be a list of [t, a2, a3]"),
        ("cycle: 3.0\nvia_points: [[0.0, x, 2.0]]\n", "must be numbers"),
        ("cycle: 3.0\nlead_in: -1\nvia_points: [[0.0, -1.5, 2.0]]\n", "lead_in=-1.0 must be"),
        ("cycle: 3.0\nspeed: 2\nvia_points: [[0.0, -1.5, 2.0]]\n", "unknown keys ['speed']"),
        ("cycle: [3.0\n", "not valid YAML"),
        ("- 1\n- 2\n", "expected a mapping"),
    ],
)
def test_malformed_command_file_gives_a_clear_error(tmp_path, content, message):
    path = tmp_path / "bad.yaml"
    path.write_text(content)
    with pytest.raises(PolicyFileError) as error:
        load_command(path)
    assert message in str(error.value) and str(path) in str(error.value)


def test_missing_command_names_the_path_and_the_shipped_ones(tmp_path):
    for path in ("/dev/null", tmp_path / "no_run_here"):  # a path is never a shipped name
        with pytest.raises(PolicyFileError, match=f"^{path}: not a run directory, a checkpoint"):
            load_command(path)
    with pytest.raises(PolicyFileError, match="no policy file at .*shipped policies: closed_loop,"):
        load_command("no_such_command")
    with pytest.raises(PolicyFileError, match=r"\(shelved: closed_loop_gains, .*two_balls_start"):
        load_command("no_such_command")
    with pytest.raises(CommandError, match="kind='feedback' is not a command"):
        load_command("closed_loop")
    with pytest.raises(PolicyFileError, match="not valid JSON"):
        (tmp_path / "c.json").write_text("{")
        load_command(tmp_path / "c.json")


def test_a_shelved_policy_loads_by_name_and_is_not_listed_as_shipped():
    from jugglerl.runs.policy_files import policy_file, shelved_names, shipped_names

    assert policy_file("closed_loop_gains").parent.name == "superseded"
    assert policy_file("two_balls_throw_start").parent.name == "starts"
    assert "earth_expert" in shelved_names() and "earth_expert" not in shipped_names()
    assert {"expert", "closed_loop", "lstm_centred"} <= set(shipped_names())


def test_shorten_hold_moves_the_rest_of_the_command_earlier():
    command = ViaPointCommand(3.0, ((0.2, -1.5, 2.1), (1.5, -1.5, 1.4), (2.0, -1.6, 2.0)))
    cut = command.shorten_hold(0, 0.25)
    assert cut.cycle == pytest.approx(2.75)
    np.testing.assert_allclose([t for t, _, _ in cut.via_points], [0.2, 1.25, 1.75])
    held = np.linspace(0.0, 1.24, 50)  # before and during via-point 0's hold: unchanged
    np.testing.assert_allclose(cut.setpoints(held), command.setpoints(held))
    later = np.linspace(1.25, 2.74, 50)  # after it: the original, 0.25 s later
    np.testing.assert_allclose(cut.setpoints(later), command.setpoints(later + 0.25))
    # the last via-point's hold runs to the cycle's end; a negative cut holds longer
    assert command.shorten_hold(2, 0.5).via_points == command.via_points
    assert command.shorten_hold(2, 0.5).cycle == pytest.approx(2.5)
    assert command.shorten_hold(1, -0.5).cycle == pytest.approx(3.5)


@pytest.mark.parametrize(
    ("index", "cut", "message"),
    [(3, 0.1, "via-point 3 does not exist"), (1, 0.5, "cannot cut 0.5 s from via-point 1")],
)
def test_shorten_hold_refuses_what_cannot_be_cut(index, cut, message):
    command = ViaPointCommand(3.0, ((0.2, -1.5, 2.1), (1.5, -1.5, 1.4), (2.0, -1.6, 2.0)))
    with pytest.raises(CommandError, match=message):
        command.shorten_hold(index, cut)


@pytest.mark.slow
def test_expert_juggles_at_least_seven_throws_in_the_paper_preset():
    env = JuggleEnv()
    metrics = run_episode(env, CommandPolicy(load_command("expert")), seed=0)
    assert metrics.throws >= 7
    assert metrics.catches >= metrics.throws
