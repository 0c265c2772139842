"""A progress bar on stderr for long runs: silent for the first second, then redrawn at most
five times a second."""
from __future__ import annotations

import sys
import time


class Progress:
    def __init__(self, total_time: float, enabled: bool = True, stream=sys.stderr, quiet_for: float = 1.0):
        self.total, self.enabled, self.stream = total_time, enabled, stream
        self.start = time.perf_counter()
        self.quiet_for = quiet_for
        self.last = 0.0
        self.shown = False

    def update(self, t: float) -> None:
        if not self.enabled:
            return
        now = time.perf_counter() - self.start
        if now < self.quiet_for or now - self.last < 0.2:
            return
        self.last = now
        done = min(t / self.total, 1.0)
        eta = now * (1.0 - done) / done if done > 0 else 0.0
        bar = "#" * int(30 * done)
        self.stream.write(f"\r[{bar:<30}] {100 * done:5.1f} %  t = {t:8.3f} s  "
                          f"{t / now:6.1f}x real time  ~{eta:5.1f} s left ")
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        if self.shown:
            self.update_final()

    def update_final(self) -> None:
        now = time.perf_counter() - self.start
        self.stream.write(f"\r[{'#' * 30}] 100.0 %  t = {self.total:8.3f} s  {self.total / now:6.1f}x real time"
                          + " " * 16 + "\n")
        self.stream.flush()
