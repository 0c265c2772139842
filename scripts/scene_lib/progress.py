"""Progress of a long scene run on stderr, through tqdm: silent for the first second (short runs
stay quiet), then redrawn at most five times a second with the simulated time, the real-time factor
and the time left."""
from __future__ import annotations

import sys

from tqdm import tqdm


class Progress:
    """`update(t)` with the simulated time reached; `close()` at the end."""

    def __init__(self, total_time: float, enabled: bool = True, stream=sys.stderr, quiet_for: float = 1.0):
        self.bar = tqdm(total=total_time, disable=not enabled, file=stream, delay=quiet_for, mininterval=0.2,
                        unit="s", unit_scale=False, bar_format="{l_bar}{bar:30}| t = {n:.3f} of {total:g} s "
                        "[{elapsed}<{remaining}, {rate_fmt}]", dynamic_ncols=False, leave=True)

    def update(self, t: float) -> None:
        # The rate tqdm shows is simulated seconds per wall second: the real-time factor.
        self.bar.update(t - self.bar.n)

    def close(self) -> None:
        if self.bar.n < self.bar.total:
            self.bar.update(self.bar.total - self.bar.n)
        self.bar.close()
