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
    for row in range(5):
        events = JuggleEvents(threshold=1.0)
        events.reset(heights[row, 0], clear_of_cup=True)
        for h, free in zip(heights[row, 1:], in_flight[row, 1:], strict=True):
            events.update(h, free, in_cup=False, clear_of_cup=True, below_cup=False)
        assert events.throws == batched[row]
    assert batched.sum() > 0


def test_catch_needs_the_ball_to_have_left_the_cup():
    events = JuggleEvents(threshold=1.0)
    events.reset(1.5, clear_of_cup=True)
    events.update(0.8, True, in_cup=True, clear_of_cup=False, below_cup=False)  # caught
    events.update(0.85, True, in_cup=False, clear_of_cup=False, below_cup=False)  # sloshes to rim
    events.update(0.8, False, in_cup=True, clear_of_cup=False, below_cup=False)  # back: same catch
    assert events.catches == 1
    events.update(1.2, True, in_cup=False, clear_of_cup=True, below_cup=False)  # thrown
    events.update(0.8, False, in_cup=True, clear_of_cup=False, below_cup=False)  # caught again
    assert (events.catches, events.streak) == (2, 2)
    events.update(0.3, True, in_cup=False, clear_of_cup=True, below_cup=True)  # missed
    events.update(0.8, False, in_cup=True, clear_of_cup=False, below_cup=False)  # bounced back in
    assert (events.catches, events.streak, events.max_streak) == (3, 1, 2)
