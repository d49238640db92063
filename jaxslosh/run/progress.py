"""A progress bar on stderr for long runs (no dependency; quiet when disabled)."""
from __future__ import annotations

import sys
import time as _time


class Progress:
    """A progress bar on stderr (no dependency; quiet when stderr is not a terminal unless forced)."""

    def __init__(self, total: int, enabled: bool = True, width: int = 30):
        self.total, self.enabled, self.width = max(1, total), enabled, width
        self.t0 = _time.perf_counter()
        self.last = -1.0

    def update(self, done: int, extra: str = ""):
        if not self.enabled:
            return
        now = _time.perf_counter()
        if now - self.last < 0.2 and done < self.total:
            return
        self.last = now
        frac = min(1.0, done / self.total)
        bar = "#" * int(frac * self.width) + "-" * (self.width - int(frac * self.width))
        el = now - self.t0
        eta = el / frac - el if frac > 0 else 0.0
        sys.stderr.write(f"\r[{bar}] {100 * frac:5.1f}% step {done}/{self.total} {el:6.1f}s elapsed, {eta:6.1f}s left {extra}")
        sys.stderr.flush()

    def close(self):
        if self.enabled:
            sys.stderr.write("\n")
            sys.stderr.flush()
