"""The shared definition of a throw and of a catch."""

import numpy as np

from jugglerl_envs.events import JuggleEvents, count_throws, crossed_upward


def test_crossing_counts_only_upward_and_in_free_flight():
    assert crossed_upward(0.9, 1.1, True, 1.0)
    assert crossed_upward(0.99, 1.0, True, 1.0)  # reaching the line counts
    assert not crossed_upward(1.1, 0.9, True, 1.0)  # going down
    assert not crossed_upward(0.9, 1.1, False, 1.0)  # carried in contact
    assert not crossed_upward(1.05, 1.2, True, 1.0)  # already above


def test_batched_count_equals_step_by_step_count():
    rng = np.random.default_rng(0)
    heights = 1.0 + 0.3 * np.sin(np.linspace(0, 40, 400))[None] + 0.05 * rng.normal(size=(5, 400))
    in_flight = rng.random((5, 400)) > 0.2
    batched = count_throws(heights, in_flight, 1.0)
    events = JuggleEvents(threshold=np.ones(5), balls=1)  # five envs of one ball, step by step
    envs, yes, no = np.arange(5), np.ones((5, 1), bool), np.zeros((5, 1), bool)
    events.reset(envs, heights[:, :1], clear_of_cup=yes)
    for step in range(1, 400):
        sample = heights[:, step : step + 1], in_flight[:, step : step + 1]
        events.update(envs, *sample, in_cup=no, clear_of_cup=yes, below_cup=no)
    np.testing.assert_array_equal(events.throws[:, 0], batched)
    assert batched.sum() > 0


def test_catch_needs_the_ball_to_have_left_the_cup():
    events = JuggleEvents(threshold=np.ones(1), balls=1)
    env = np.array([0])

    def sample(height, in_flight, in_cup, clear_of_cup, below_cup):
        flags = [np.array([[flag]]) for flag in (in_flight, in_cup, clear_of_cup, below_cup)]
        events.update(env, np.array([[height]]), *flags)

    def counts():
        return events.catches[0, 0], events.streak[0, 0], events.max_streak[0, 0]

    events.reset(env, np.array([[1.5]]), clear_of_cup=np.array([[True]]))
    sample(0.8, True, in_cup=True, clear_of_cup=False, below_cup=False)  # caught
    sample(0.85, True, in_cup=False, clear_of_cup=False, below_cup=False)  # sloshes to the rim
    sample(0.8, False, in_cup=True, clear_of_cup=False, below_cup=False)  # back: the same catch
    assert counts()[0] == 1
    sample(1.2, True, in_cup=False, clear_of_cup=True, below_cup=False)  # thrown
    sample(0.8, False, in_cup=True, clear_of_cup=False, below_cup=False)  # caught again
    assert counts()[:2] == (2, 2)
    sample(0.3, True, in_cup=False, clear_of_cup=True, below_cup=True)  # missed
    sample(0.8, False, in_cup=True, clear_of_cup=False, below_cup=False)  # bounced back in
    assert counts() == (3, 1, 2)
