"""Progress on stderr for long commands (no dependency): a command's phases timed on one clock.

A phase without a count (building the model, compiling the step) shows its own elapsed time,
redrawn by a small thread: compilation is one blocking call that reports nothing while it works.
A counted phase (the steps, the frames of an animation) shows a bar, the elapsed time of the whole
command and an estimate from the rate measured in that phase alone, so a compilation before it
never enters the estimate; no estimate is shown until some units are done. The phases are
contiguous on the clock, so their durations (`close`) add up to the elapsed time the bar showed,
which is what the command's summary line prints.

Drawn only where wanted (`wanted`): never with --no-progress; JAXSLOSH_PROGRESS=1 forces it on
(a log, a test), =0 off; otherwise only when stderr is a terminal, since a log file would collect
every carriage-return redraw.
"""
from __future__ import annotations

import os
import sys
import threading
import time as _time

#: the environment variable that forces the progress display on (1) or off (0)
ENV = "JAXSLOSH_PROGRESS"
_ON, _OFF = {"1", "true", "yes", "on"}, {"0", "false", "no", "off"}


def wanted(disabled: bool = False, stream=None) -> bool:
    """Whether a command draws its progress (see the module's docstring)."""
    if disabled:
        return False
    v = os.environ.get(ENV, "").strip().lower()
    if v in _ON:
        return True
    if v in _OFF:
        return False
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):      # a closed or replaced stream
        return False


def _seconds(s: float) -> str:
    return f"{s:.1f} s" if s < 600 else f"{int(s // 60)} min {int(s % 60):02d} s"


class Progress:
    """Phases of a command on one clock, drawn on `stream` (stderr) when `enabled`; when not, it
    still times the phases (the summary line needs them)."""

    def __init__(self, enabled: bool = True, stream=None, width: int = 30, tick: float = 0.2):
        self.enabled, self.width, self.tick = enabled, width, tick
        self.stream = sys.stderr if stream is None else stream
        self.t0 = _time.perf_counter()
        self.phases: dict = {}                # name -> seconds, in order
        self._name = None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._drawn = 0                       # length of the line on screen (to blank a shorter one)
        self._last_update = -1.0
        self._thread = None
        if enabled:
            self._thread = threading.Thread(target=self._ticker, name="jaxslosh-progress", daemon=True)
            self._thread.start()

    def elapsed(self) -> float:
        return _time.perf_counter() - self.t0

    def phase(self, name: str, label: str, total: int | None = None, unit: str = "step"):
        """End the current phase (its line stays) and start `name`: a bar of `total` units, or,
        without `total`, the line "`label` ... elapsed"."""
        with self._lock:
            now = _time.perf_counter()
            self._finish(now)
            self._name, self._label, self._unit = name, label, unit
            self._total = None if total is None else max(1, int(total))
            self._start, self._done, self._t_done = now, 0, now
            self._draw(now)

    def update(self, done: int, total: int | None = None):
        """`done` units of the current phase are finished (of `total`, when the phase started
        without knowing it: it turns from a timer into a bar)."""
        with self._lock:
            if total is not None:
                self._total = max(1, int(total))
            now = _time.perf_counter()
            self._done, self._t_done = done, now
            # throttled against the updates only: a redraw by the ticker must not hide new counts
            if now - self._last_update >= self.tick or (self._total is not None and done >= self._total):
                self._last_update = now
                self._draw(now)

    def close(self) -> dict:
        """End the last phase; {phase: seconds}, which add up to `elapsed()` at this moment."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        with self._lock:
            self._finish(_time.perf_counter())
        return dict(self.phases)

    # -- drawing (under the lock) ---------------------------------------------------------------

    def _ticker(self):
        while not self._stop.wait(self.tick):
            with self._lock:
                if self._name is not None:
                    self._draw(_time.perf_counter())

    def _finish(self, now: float):
        if self._name is None:
            return
        self.phases[self._name] = now - self._start
        self._draw(now)
        self._write("\n")
        self._drawn = 0
        self._name = None

    def _line(self, now: float) -> str:
        if self._total is None:
            return f"{self._label} ... {_seconds(now - self._start)}"
        frac = min(1.0, self._done / self._total)
        n = int(frac * self.width)
        if self._done <= 0:
            left = "estimating"            # no rate yet: no estimate
        else:
            # the rate of this phase at the last update, counted down between updates
            rate = self._done / max(self._t_done - self._start, 1e-9)
            left = f"{_seconds(max(0.0, (self._total - self._done) / rate - (now - self._t_done)))} left"
        return (f"{self._label} [{'#' * n}{'-' * (self.width - n)}] {100 * frac:5.1f}% "
                f"{self._unit} {self._done}/{self._total}, {_seconds(now - self.t0)} elapsed, {left}")

    def _draw(self, now: float):
        if not self.enabled or self._name is None:
            return
        line = self._line(now)
        self._write("\r" + line + " " * max(0, self._drawn - len(line)))
        self._drawn = len(line)

    def _write(self, text: str):
        if not self.enabled:
            return
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):         # a closed pipe: progress is never worth a failure
            self.enabled = False
