"""How a run ends before its stop time: the kinds (STOP_KINDS), where and why it ended (Stop), and
the request a signal handler makes to end it at its next step (StopRequest)."""
from __future__ import annotations

import contextlib
from dataclasses import dataclass

from ..errors import Interrupted, Terminated

# How a run ended before its stop time (Stop.kind), in the words of the summary line.
STOP_KINDS = {"failed": "failed", "interrupted": "interrupted (SIGINT)", "terminated": "terminated (SIGTERM)"}


@dataclass(frozen=True)
class Stop:
    """Why and where a run ended before its stop time; its record ends at `time` (the last
    communication point whose outputs, sensors and controller output were all recorded)."""
    kind: str       # a key of STOP_KINDS
    time: float     # s
    reason: str     # one line
    details: str | None = None   # a user controller's traceback (gimbal2axis run --traceback), else None


class StopRequest:
    """Asks a running loop to end, keeping what it recorded: `request(kind, reason)` is seen at the
    next step of the Python loop or at the next chunk boundary of the compiled loop (CHUNK_STEPS
    steps, a few tens of milliseconds).

    A signal handler calls `signal_received`: while the run steps (`stepping`), the first signal
    only asks; a repeated one, or one in any other phase (preparing, the metrics, the plots, the
    files), raises at once (errors.Interrupted, Terminated), so that no phase can ignore Ctrl-C.
    Inside `shield()` (a file being written whole) a signal only asks, and whoever holds the
    shield looks at `kind` after it."""

    def __init__(self):
        self.kind, self.reason = None, None
        self.stepping, self.shields, self.signals = False, 0, 0
        self.phase = "running"   # what the run was doing, for the message of a signal that ends it

    def request(self, kind: str, reason: str) -> None:
        if kind not in STOP_KINDS:
            raise ValueError(f"unknown stop kind {kind!r}")
        self.kind, self.reason = kind, reason

    def signal_received(self, kind: str, reason: str) -> None:
        self.signals += 1
        if self.kind is None or self.kind == "failed":
            self.request(kind, reason)
        if self.shields == 0 and (self.signals > 1 or not self.stepping):
            self.raise_stop()

    def raise_stop(self) -> None:
        """Raises the exception of the signal asked for (after a shield, or at a phase's start)."""
        if self.kind == "terminated":
            raise Terminated(self.reason)
        if self.kind == "interrupted":
            raise Interrupted(self.reason)

    @contextlib.contextmanager
    def shield(self):
        self.shields += 1
        try:
            yield self
        finally:
            self.shields -= 1
