"""``deferred_interrupt``: hold a Ctrl-C until a block of work that must not be cut has finished.

A ``KeyboardInterrupt`` raised inside TorchRL's losses can surface as another error: DDPG's and
TD3's actor losses swap the critic's parameters in with ``TensorDict.to_module`` as a context
manager, and when the interrupt lands inside it, leaving the context raises ``RuntimeError:
Converting a tensordict to boolean value is not permitted`` in its place (about one Ctrl-C in
40, sent at random moments of a short DDPG run). The trainer then never sees the Ctrl-C,
writes no checkpoint and the user gets a traceback. Holding the interrupt until the updates of a
batch are done keeps Ctrl-C a clean stop, at the cost of waiting for them; a second Ctrl-C
raises at once.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def deferred_interrupt() -> Iterator[None]:
    """Run the block with SIGINT held: one Ctrl-C inside it is raised as ``KeyboardInterrupt``
    when the block ends, a second one at once. Outside the main thread, or where SIGINT is not
    Python's default handler (ignored in a background job, or handled by someone else), the block
    runs as it is."""
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    ):
        yield
        return
    received = []

    def hold(signum, frame):
        if received:
            raise KeyboardInterrupt
        received.append(signum)

    signal.signal(signal.SIGINT, hold)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    if received:
        raise KeyboardInterrupt
