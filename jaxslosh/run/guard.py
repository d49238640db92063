"""SIGINT and SIGTERM while a run writes its file: the run stops at the next chunk boundary, so that
the file says how it ended and keeps every step computed. A second signal stops it at once.

An exception raised by a signal handler can land anywhere, in a weakref callback or a finalizer
whose exceptions Python ignores, and then the run goes on as if nothing happened; the first
signal therefore only asks, and the loop looks between chunks (`Stop.check`)."""
from __future__ import annotations

import contextlib
import signal
import threading
from typing import Optional


class Interrupted(KeyboardInterrupt):
    """The run was stopped by a signal (its name is the message)."""


class Stop:
    """What the handlers were told: the name of the first signal, or None."""

    def __init__(self):
        self.signal: Optional[str] = None

    def check(self):
        if self.signal is not None:
            raise Interrupted(self.signal)


@contextlib.contextmanager
def interrupts():
    """Within the block, SIGINT and SIGTERM ask the run to stop (a Stop to check); a second one, or
    one outside the main thread's reach, raises Interrupted at once. Both handlers are restored."""
    stop = Stop()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def handler(signum, frame):
        name = signal.Signals(signum).name
        if stop.signal is not None:
            raise Interrupted(name)
        stop.signal = name

    old = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        for s, h in old.items():
            signal.signal(s, h)
