"""scripts/studies/imitation_gap.py: a student's gap to its teacher on the student's own episode."""

from cli import run_script


def run(*args: str) -> list[str]:
    result = run_script("studies/imitation_gap.py", *args)
    assert result.returncode == 0, result.stderr[-2000:]
    return result.stdout.splitlines()


def numbers(line: str, start: str, end: str) -> list[float]:
    return [float(x) for x in line.split(start)[1].split(end)[0].split()]


def test_a_policy_has_no_gap_to_itself_and_its_flights_clear_the_threshold():
    lines = run("closed_loop", "--duration", "12")
    assert numbers(lines[1], "RMS [", "]") == [0.0, 0.0, 0.0]
    throws = int(lines[0].split(": ")[1].split()[0])
    apexes = numbers(lines[2], ":", "\n")
    assert throws >= 3 and sum(apex > 1.0 for apex in apexes) == throws


def test_another_policy_shows_a_gap_on_every_actuator():
    lines = run("closed_loop_gains", "--teacher", "closed_loop", "--duration", "6")
    assert all(gap > 0 for gap in numbers(lines[1], "RMS [", "]"))
    assert len(numbers(lines[3], ":", "\n")) == len(numbers(lines[2], ":", "\n"))


def test_a_bad_policy_is_one_error_line():
    result = run_script("studies/imitation_gap.py", "no_such_policy")
    assert result.returncode == 1
    assert result.stderr.strip().splitlines()[-1].startswith("error: no policy file")
