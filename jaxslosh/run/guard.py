"""SIGTERM handled like Ctrl-C while a run writes its file, so that the file says how the run ended."""
from __future__ import annotations

import contextlib
import signal
import threading


class Interrupted(KeyboardInterrupt):
    """The run was stopped by a signal (its name is the message)."""


@contextlib.contextmanager
def interrupts():
    """Within the block, SIGTERM raises Interrupted in the main thread, as SIGINT raises
    KeyboardInterrupt (Python's own handler); both handlers are restored after it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        raise Interrupted(signal.Signals(signum).name)

    old_term = signal.signal(signal.SIGTERM, handler)
    old_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old_term)
        signal.signal(signal.SIGINT, old_int)
