"""The stability margins of the simulated loop-gain curves of a freqresp loop-gain dwell."""
from __future__ import annotations

import math

from . import frequency_response as fr
from .isolation_prediction import stability_margins


def measured_margins(rows: list[dict]) -> list[str]:
    """A line per simulated curve: the margins of its loop_gain points (interpolated between the dwell's
    frequencies, so only as fine as its grid; a point of low coherence may place a crossing anywhere)."""
    lines = []
    for (curve, output), points in fr.curves(rows).items():
        if output != fr.LOOP_GAIN or curve == fr.LINEAR_CURVE or len(points) < 2:
            continue
        f = [r["frequency_hz"] for r in points]
        L = [r["gain"] * complex(math.cos(math.radians(r["phase_deg"])), math.sin(math.radians(r["phase_deg"])))
             for r in points]
        lines.append(f"{curve}, from its {len(points)} points: {stability_margins(f, L).describe()}")
    return lines
