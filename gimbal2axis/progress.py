"""Progress on stderr, through tqdm: a bar redrawn in place on a terminal; into a pipe or a log file
whole lines (LineLog), never a carriage return.

A scene run (Progress) is silent for its first second (short runs stay quiet), then shows the
simulated time, the real-time factor and the time left: on a terminal redrawn at most five times a
second, into a log a line per 10 % of the run (or per 30 s)."""
from __future__ import annotations

import os
import sys
import time

from tqdm import tqdm

LOG_EVERY_S = 30.0   # into a log, a line at least this often (besides one per 10 % of the total)


class LineLog(tqdm):
    """A tqdm that writes whole lines instead of redrawing one: at the first progress, whenever
    another 10 % of the total is done or LOG_EVERY_S passed, and at the end. `fields`: more names
    for the bar format (a dict the caller may update)."""

    def __init__(self, fields: dict | None = None, **kwargs):
        self.fields = fields if fields is not None else {}
        self.line_decile, self.line_n, self.line_t = -1, 0, time.monotonic()
        # Every update reaches display(), which decides; leave=False: closing draws nothing more
        # (the end has its line already) and writes no "\r".
        super().__init__(mininterval=0, leave=False, **kwargs)

    def display(self, msg=None, pos=None):
        if msg is not None:           # tqdm clearing or overwriting its line: nothing to clear here
            return None
        n, total = self.n, self.total or 0
        decile = int(10 * n / total) if total else 10
        due = decile != self.line_decile or time.monotonic() - self.line_t >= LOG_EVERY_S or n >= total
        if n == 0 or n == self.line_n or not due:
            return None
        self.line_decile, self.line_n, self.line_t = decile, n, time.monotonic()
        self.fp.write(self.format_meter(**self.format_dict, **self.fields) + "\n")
        self.fp.flush()
        return None


def is_terminal(stream) -> bool:
    return hasattr(stream, "isatty") and stream.isatty()


def terminal_columns(stream) -> int:
    """The terminal's width, 0 when it reports none (a pty without a size, e.g. `script` run without
    a terminal, where tqdm would draw nothing: it takes 0 columns and 0 rows from it)."""
    try:
        return os.get_terminal_size(stream.fileno()).columns
    except (AttributeError, OSError, ValueError):
        return 0


class Progress:
    """`update(t)` with the simulated time reached; `close()` at the end."""

    def __init__(self, total_time: float, enabled: bool = True, stream=None, quiet_for: float = 1.0):
        stream = sys.stderr if stream is None else stream   # the stderr of now, not of the first import
        # The rate tqdm shows is simulated seconds per wall second: the real-time factor.
        # miniters=0: every update is looked at (tqdm would otherwise guess how many to skip)
        common = dict(total=total_time, disable=not enabled, file=stream, delay=quiet_for, unit="s", unit_scale=False,
                      miniters=0)
        if is_terminal(stream):
            self.bar = tqdm(**common, mininterval=0.2, dynamic_ncols=False, leave=True,
                            ncols=None if terminal_columns(stream) else 80,
                            nrows=None if terminal_columns(stream) else 20,
                            bar_format="{l_bar}{bar:24}| t = {n:.3f} of {total:g} s [{elapsed}<{remaining}, {rate_fmt}]")
        else:
            self.bar = LineLog(**common, bar_format="t = {n:.3f} of {total:g} s  {percentage:5.1f} %  "
                                                    "{rate_noinv_fmt}  ~{remaining} left")

    def update(self, t: float) -> None:
        self.bar.update(t - self.bar.n)

    def close(self, complete: bool = True) -> None:
        """Ends the bar; `complete` False (a run that stopped early) leaves it where the run got to."""
        if complete and self.bar.n < self.bar.total:
            self.bar.update(self.bar.total - self.bar.n)
        self.bar.close()
