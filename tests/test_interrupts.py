"""``deferred_interrupt``: Ctrl-Cs inside the block wait for its end; ``stop_on_interrupt``: the
first Ctrl-C stops, the later ones are ignored."""

import os
import signal

import pytest

from jugglerl.runs.interrupts import deferred_interrupt, stop_on_interrupt


def ctrl_c():
    os.kill(os.getpid(), signal.SIGINT)


def test_a_ctrl_c_inside_the_block_is_raised_when_it_ends():
    done = []
    with pytest.raises(KeyboardInterrupt), deferred_interrupt():
        ctrl_c()
        done.append("after the Ctrl-C")
    assert done == ["after the Ctrl-C"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_two_ctrl_cs_inside_the_block_are_one_interrupt_when_it_ends():
    done = []
    with pytest.raises(KeyboardInterrupt), deferred_interrupt():
        ctrl_c()
        ctrl_c()
        done.append("after the second")
    assert done == ["after the second"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_after_the_first_ctrl_c_of_a_run_the_others_are_ignored():
    done = []
    try:
        with pytest.raises(KeyboardInterrupt), stop_on_interrupt():
            with deferred_interrupt():
                ctrl_c()
                ctrl_c()
                done.append("the updates finish")
            done.append("not reached")
        ctrl_c()  # while the run saves and exits
        done.append("saved")
        assert done == ["the updates finish", "saved"]
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def test_a_run_without_ctrl_c_leaves_the_handler_as_it_was():
    with stop_on_interrupt():
        value = 1
    assert value == 1 and signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_block_without_ctrl_c_runs_and_leaves_the_handler_as_it_was():
    with deferred_interrupt():
        value = 1
    assert value == 1 and signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_where_ctrl_c_is_ignored_it_stays_ignored():
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with deferred_interrupt():
            ctrl_c()
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, previous)


def test_a_ctrl_c_while_a_checkpoint_is_written_waits_for_the_file(tmp_path):
    """A Ctrl-C landing in a periodic checkpoint (syncing the replay buffers through tensordict,
    which an interrupt turns into another error) is raised once the file is whole."""
    import torch

    from jugglerl.batch.actor_training import ActorTraining

    class Saving(ActorTraining):
        run_dir, seconds = tmp_path, {}

        def state_dict(self) -> dict:
            ctrl_c()  # the press lands while the state is gathered
            return {"weights": torch.ones(3)}

    try:
        with pytest.raises(KeyboardInterrupt), stop_on_interrupt():
            Saving().save()
    finally:  # the run's first Ctrl-C left SIGINT ignored, as a stopping run needs
        signal.signal(signal.SIGINT, signal.default_int_handler)
    assert torch.equal(torch.load(tmp_path / "checkpoint.pt")["weights"], torch.ones(3))
