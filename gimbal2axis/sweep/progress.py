"""Progress of a sweep on stderr, through tqdm (as gimbal2axis/progress.py for a scene run): cases
done of the total, ok and failed, the rate and the time left. On a terminal a bar redrawn in
place; into a pipe or a log file one plain line per 10 % of the cases (or per 30 s), starting
"[done/total]" (gimbal2axis.progress.LineLog), and never a carriage return."""
from __future__ import annotations

import sys

from tqdm import tqdm

from ..progress import LineLog, is_terminal, terminal_columns


class Progress:
    """`update(status)` per finished case ("ok" or else failed); `restart_clock()` where the
    cases start running (the rate counts from there); `close()` at the end."""

    def __init__(self, total: int, enabled: bool = True, stream=None):
        stream = sys.stderr if stream is None else stream   # the stderr of now, not of the first import
        self.counts = {"ok": 0, "failed": 0}
        # smoothing=0: the rate is the average since the start; miniters=1: no tqdm guess of how
        # often to look at the clock
        common = dict(total=total, disable=not enabled, file=stream, unit=" cases", smoothing=0, miniters=1)
        if is_terminal(stream):
            # the terminal's width, followed as it changes; 80 columns if it reports none (a pty
            # without a size, e.g. `script` run without a terminal, where tqdm would draw nothing)
            known = terminal_columns(stream) > 0
            self.bar = tqdm(**common, mininterval=0.2, dynamic_ncols=known, ncols=None if known else 80,
                            nrows=None if known else 20,
                            leave=True, postfix=self._postfix(),
                            bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}<{remaining}, "
                                       "{rate_noinv_fmt}{postfix}]")
        else:
            width = len(str(total))
            self.bar = LineLog(self.counts, **common,
                                 bar_format=f"[{{n_fmt:>{width}}}/{{total_fmt}}] {{percentage:5.1f}} %  ok {{ok}}  "
                                            "failed {failed}  {rate_noinv_fmt}  ~{remaining} left")

    def _postfix(self) -> str:
        return f"ok {self.counts['ok']}, failed {self.counts['failed']}"

    def update(self, status: str) -> None:
        self.counts["ok" if status == "ok" else "failed"] += 1
        if not isinstance(self.bar, LineLog):
            self.bar.set_postfix_str(self._postfix(), refresh=False)
        self.bar.update(1)

    def restart_clock(self) -> None:
        """The time from the last update to now (a cluster's start-up) does not count: the rate and
        the time left are those of the cases running."""
        self.bar.unpause()

    def close(self) -> None:
        self.bar.close()
