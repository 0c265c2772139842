"""Stability margins, sensitivity S and complementary sensitivity T of a candidate's loop.

The loop is gimbal2axis.analysis.isolation_prediction's sampled-data model of the PID scene (the plant
linearized at the scene's operating point without backlash and dry friction, exactly discretized over a
step, the controller's exact transfer functions, the delay), broken at one motor's computed voltage with
the other axis's loop closed (loop_gain). It is built once per plant (the values of the tuned parameters
that are not controller gains; for a tuning of gains alone, once) and the candidate's gains are put in.
The phase margin and S, T are python-control's (control.frd, control.stability_margins, control.feedback)
on L sampled on a log grid up to the Nyquist frequency; the gain margins are those of the -180 deg
crossings of the same samples (isolation_prediction.stability_margins): the upper one, and the lower
one of a conditionally stable loop (an open-loop unstable plant: a top-heavy payload's elevation), where
python-control's single gain margin would be whichever is nearer 0 dB.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import SceneError

POINTS = 800          # frequencies of the sampled L, log-spaced
F_MIN_HZ = 0.05
AXES = {"1": "az", "2": "el"}
GAIN_KEYS = {"kp", "ki", "kd", "k_gyro", "k_ff", "tau"}


def is_gain(name: str) -> bool:
    """A tuned parameter that changes only the controller's gains (the plant and operating point stay)."""
    parts = name.split(".")
    return len(parts) == 3 and parts[0] == "controller" and parts[1] in ("azimuth", "elevation") \
        and parts[2] in GAIN_KEYS


class LoopModels:
    """The linear loops of a tuning's candidates, one plant built per plant key."""

    def __init__(self, scene, fmu, apply):
        self.scene, self.fmu, self.apply = scene, fmu, apply   # apply(values) -> the scene with them put in
        self.plants: dict = {}

    def loop(self, candidate: dict):
        """The candidate's IsolationLoop, or a SceneError saying why there is none."""
        from ..analysis import frequency_response as fr
        from ..analysis import isolation_prediction as ip

        plant_values = {k: v for k, v in candidate.items() if not is_gain(k)}
        key = repr(sorted(plant_values.items()))
        if key not in self.plants:
            try:   # the plant at the operating point the scene's own gains hold
                self.plants[key] = ip.build_loop(self.apply(plant_values), self.fmu, fr.LINEAR_FIDELITY)
            except SceneError as exc:
                self.plants[key] = exc
        base = self.plants[key]
        if isinstance(base, Exception):
            raise base
        axes, _ = ip.pid_gains(self.apply(candidate), self.fmu)
        return dataclasses.replace(base, axes=axes)

    def margins(self, candidate: dict) -> dict:
        """{gm_<az|el>_db, lower_gm_<az|el>_db, pm_<az|el>_deg, crossover_<az|el>_hz, ms_<az|el>, linear_stable}:
        NaN margins and linear_stable False for a loop with a closed-loop pole on or outside the unit circle."""
        from ..analysis import isolation_prediction as ip

        row = {"linear_stable": False}
        for axis in AXES.values():
            row.update({f"gm_{axis}_db": math.nan, f"lower_gm_{axis}_db": math.nan, f"pm_{axis}_deg": math.nan,
                        f"crossover_{axis}_hz": math.nan, f"ms_{axis}": math.nan})
        try:
            loop = self.loop(candidate)
        except SceneError as exc:
            row["margins_note"] = str(exc)[:300]
            return row
        radius = float(np.max(np.abs(ip.closed_loop_poles(loop))))
        if radius >= 1.0:
            row["margins_note"] = f"linear closed loop unstable (pole at |z| = {radius:.6g})"
            return row
        row["linear_stable"] = True
        for motor, axis in AXES.items():
            response = frequency_response(loop, motor)
            row.update({f"gm_{axis}_db": response["gm_db"], f"lower_gm_{axis}_db": response["lower_gm_db"],
                        f"pm_{axis}_deg": response["pm_deg"],
                        f"crossover_{axis}_hz": response["crossover_hz"], f"ms_{axis}": response["ms"]})
        return row


def frequency_response(loop, motor: str, points: int = POINTS) -> dict:
    """L, S = 1 / (1 + L), T = L / (1 + L) of the loop broken at `motor` ('1' azimuth, '2' elevation) on a log
    grid (Hz) up to Nyquist, with the margins: gain margin [dB] (+inf without a -180 deg crossing where
    |L| <= 1) and the lower gain margin [dB] of a conditionally stable loop (-inf without a crossing where
    |L| > 1), each with its frequency [Hz]; python-control's phase margin [deg] and gain crossover [Hz];
    the peak sensitivity Ms = max |S|."""
    import control

    from ..analysis import isolation_prediction as ip

    f = np.logspace(math.log10(F_MIN_HZ), math.log10(0.5 / loop.h * 0.999), points)
    L = np.array([ip.loop_gain(loop, motor, ip._unit_circle(each, loop.h)) for each in f])
    w = 2 * math.pi * f
    open_loop = control.frd(L, w)
    S = control.feedback(control.frd(np.ones_like(L), w), open_loop)
    T = control.feedback(open_loop, 1)
    _gm, pm, _sm, _wpc, wgc, _wms = control.stability_margins(open_loop)
    crossings = ip.stability_margins(f, L)
    s_values = np.squeeze(_data(S))
    return {"f_hz": f, "L": L, "S": s_values, "T": np.squeeze(_data(T)),
            "gm_db": _or(crossings.gain_margin_db, math.inf), "gm_hz": crossings.phase_crossover_hz,
            "lower_gm_db": _or(crossings.lower_gain_margin_db, -math.inf),
            "lower_gm_hz": crossings.lower_phase_crossover_hz,
            "pm_deg": float(pm) if np.isfinite(pm) else math.inf,
            "crossover_hz": float(wgc) / (2 * math.pi) if np.isfinite(wgc) else math.nan,
            "ms": float(np.max(np.abs(s_values)))}


def _or(margin_db: float, without: float) -> float:
    """A margin, or `without` (+-inf: the gain may go that far) when the loop has no such crossing."""
    return margin_db if math.isfinite(margin_db) else without


def _data(response) -> np.ndarray:
    """An FRD's complex values (frdata; fresp before python-control 0.10.2)."""
    return response.frdata if hasattr(response, "frdata") else response.fresp
