"""Ctrl-C as a clean stop: the first press stops a run, later ones are ignored.

``stop_on_interrupt`` covers a whole run: its first Ctrl-C raises ``KeyboardInterrupt``, and from
then on SIGINT is ignored, so that saving the checkpoint, closing the recording and the
interpreter's exit all finish. (A second press 20 ms after the first used to land inside that
work, in a loss or in torch's ``atexit`` handlers, and end the run with a traceback.)

``deferred_interrupt`` holds a Ctrl-C until a block of work that must not be cut has finished. A
``KeyboardInterrupt`` raised inside TorchRL's losses can surface as another error: DDPG's and
TD3's actor losses swap the critic's parameters in with ``TensorDict.to_module`` as a context
manager, and when the interrupt lands inside it, leaving the context raises ``RuntimeError:
Converting a tensordict to boolean value is not permitted`` in its place (about one Ctrl-C in
40, sent at random moments of a short DDPG run). The trainer then never sees the Ctrl-C, writes
no checkpoint and the user gets a traceback. Holding the interrupt until the updates of a batch
are done keeps Ctrl-C a clean stop, at the cost of waiting for them. A checkpoint is held
likewise: syncing the memory-mapped replay buffers (TorchRL's ``dumps``) unlocks a tensordict in
a context that fails the same way.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager


def _stop(signum=None, frame=None) -> None:
    """The first Ctrl-C of a run: ignore the later ones, then raise."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    raise KeyboardInterrupt


def _ours_to_handle(*handlers) -> bool:
    """SIGINT is handled by one of ``handlers`` and this is the main thread (the only one a
    handler can be set in). A background job ignores SIGINT: it stays ignored."""
    return (
        threading.current_thread() is threading.main_thread()
        and signal.getsignal(signal.SIGINT) in handlers
    )


@contextmanager
def stop_on_interrupt() -> Iterator[None]:
    """Run the block so that its first Ctrl-C raises ``KeyboardInterrupt`` and every later one,
    in the block or after it (the process is stopping), is ignored. Without a Ctrl-C the handler
    is left as it was."""
    if not _ours_to_handle(signal.default_int_handler):
        yield
        return
    signal.signal(signal.SIGINT, _stop)
    try:
        yield
    finally:
        if signal.getsignal(signal.SIGINT) is _stop:
            signal.signal(signal.SIGINT, signal.default_int_handler)


@contextmanager
def deferred_interrupt() -> Iterator[None]:
    """Run the block with SIGINT held: a Ctrl-C inside it (one or several) is raised as one
    ``KeyboardInterrupt`` when the block ends. Outside the main thread, or where SIGINT is
    neither Python's default handler nor ``stop_on_interrupt``'s, the block runs as it is."""
    handler = signal.getsignal(signal.SIGINT)
    if not _ours_to_handle(signal.default_int_handler, _stop):
        yield
        return
    received = []

    def hold(signum, frame):
        received.append(signum)

    signal.signal(signal.SIGINT, hold)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, handler)
    if received:
        handler(signal.SIGINT, None)
