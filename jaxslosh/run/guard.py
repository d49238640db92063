"""SIGINT and SIGTERM while a run writes its file: the run stops at the next chunk boundary, so that
the file says how it ended and keeps every step computed. A second signal stops it at once.

An exception raised by a signal handler can land anywhere, in a weakref callback or a finalizer
whose exceptions Python ignores, and then the run goes on as if nothing happened; the first
signal therefore only asks, and the loop looks between chunks (`Stop.check`)."""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
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
        _HANDLED[0] += 1                # this signal is answered here, not by `stop_on_signals`' watcher
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


# The command line's own regime (jaxslosh/entry.py, for the whole process): a signal stops the
# command at once, with one line and exit status 130. Where no command asks otherwise (a run or a
# campaign enters `interrupts` above, which keeps its file and says how it ended), a KeyboardInterrupt
# would land wherever Python was (JAX's import: a 40-line traceback; a callback of XLA's garbage
# collection: ignored, and the command went on to write its figure and exit 0). And Python runs a
# handler only between its own bytecodes, not while XLA computes: a thread woken through the
# signal's wakeup file descriptor stops the process then. A file being written when the signal
# comes is finished first (`finishing`), never left half-written.

#: what `finishing` blocks hold off: their depth, and the signals that came meanwhile
_FINISHING = [0]
_ASKED: list = []
#: SIGINT and SIGTERM: how many a Python handler of this module has run for, and how many wakeup
#: bytes the watcher has read (one a signal; Python may run one handler call for two quick ones)
_HANDLED = [0]
_READ = [0]
#: how long the watcher leaves the main thread to run a handler itself, in seconds: longer means a
#: computation in XLA that keeps it from Python
GRACE = 0.25
_EXITING = threading.Lock()
#: the exit status of an interrupted command (128 + SIGINT, the shell's convention; cli/common.py's)
EXIT_INTERRUPTED = 130


def _stop_now():
    if not _EXITING.acquire(blocking=False):        # the other path (handler or watcher) is on it
        return
    try:
        sys.stderr.write("interrupted\n")
        sys.stderr.flush()
    finally:
        os._exit(EXIT_INTERRUPTED)


def _stop_handler(signum, frame):
    _HANDLED[0] += 1
    if _FINISHING[0]:
        _ASKED.append(signum)
    else:
        _stop_now()


def _watch(fd):
    """The signals' wakeup bytes, read while the main thread may be inside XLA (which does not
    hold Python's lock). A signal that no handler has answered within GRACE, while ours is the
    handler, stops the process; one that `interrupts` answered (a run, a campaign) is left to it,
    even where its block has ended and ours is back by the time the byte is read."""
    while True:
        try:
            data = os.read(fd, 64)
        except OSError:
            return
        if not data:
            return
        for signum in data:
            if signum not in (signal.SIGINT, signal.SIGTERM):
                continue
            _READ[0] += 1
            deadline = time.monotonic() + GRACE
            while _HANDLED[0] < _READ[0] and time.monotonic() < deadline:
                time.sleep(0.01)
            if _HANDLED[0] >= _READ[0]:
                continue
            _HANDLED[0] = _READ[0]          # counted answered: the counts stay in step
            try:
                ours = signal.getsignal(signum) is _stop_handler
            except (ValueError, OSError):
                ours = False
            if ours and not _FINISHING[0]:
                _stop_now()


def stop_on_signals():
    """From now on, in this process (the main thread only), SIGINT and SIGTERM stop it at once:
    "interrupted" on stderr and exit status 130, except inside `finishing` blocks (which end
    first) and while `interrupts` has the signals."""
    if threading.current_thread() is not threading.main_thread():
        return
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, _stop_handler)
    r, w = os.pipe()
    os.set_blocking(w, False)
    signal.set_wakeup_fd(w, warn_on_full_buffer=False)
    threading.Thread(target=_watch, args=(r,), name="signal-watch", daemon=True).start()


@contextlib.contextmanager
def finishing():
    """A block that writes a file: a signal under `stop_on_signals` waits for its end, then stops the
    process (the file whole). Elsewhere, nothing changes."""
    _FINISHING[0] += 1
    try:
        yield
    finally:
        _FINISHING[0] -= 1
        if _ASKED and not _FINISHING[0]:
            _stop_now()
