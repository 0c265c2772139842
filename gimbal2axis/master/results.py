"""A run's record: derived line-of-sight signals, metrics, requirement checks, CSV and summary line."""
from __future__ import annotations

import math
import pathlib

import numpy as np

from ..scene import geometry


class RunResult:
    def __init__(self, scene, signals: dict, wall_time: float, stop_time: float):
        self.scene, self.signals, self.wall_time, self.stop_time = scene, signals, wall_time, stop_time
        s = signals
        attitude = (s["base.delta"], s["base.psi"], s["base.gamma"])
        s["alpha_error"] = s["alpha_ref"] - s["alpha"]
        s["beta_error"] = s["beta_ref"] - s["beta"]
        az, el = geometry.los_azimuth_elevation(s["alpha"], s["beta"], *attitude)
        s["los_azimuth"], s["los_elevation"] = az, el
        if scene.target_spec is not None:
            s["los_error"] = geometry.los_error(s["alpha"], s["beta"], *attitude,
                                                math.radians(scene.target_spec["azimuth_deg"]),
                                                math.radians(scene.target_spec["elevation_deg"]))
        else:
            s["los_error"] = np.full_like(s["alpha"], np.nan)

    @property
    def has_target(self) -> bool:
        return self.scene.target_spec is not None

    def window_start(self) -> float:
        return float(self.scene.requirements.get("from_s", 0.0))

    def los_metrics(self, from_s: float | None = None) -> dict:
        """Final and RMS line-of-sight error [rad], the RMS over [from_s, end] (default: the scene's
        requirements window, else the whole run), and the maximum there."""
        t, e = self.signals["time"], self.signals["los_error"]
        start = self.window_start() if from_s is None else from_s
        window = t >= start - 1e-12
        if not window.any():
            window = np.ones_like(t, dtype=bool)
        return {"final": float(e[-1]), "rms": float(np.sqrt(np.mean(e[window] ** 2))),
                "max": float(np.max(e[window])), "from_s": start, "rms_all": float(np.sqrt(np.mean(e ** 2)))}

    def requirement_failures(self) -> list[str]:
        """The scene's [requirements] this run does not meet (empty: all met, or none stated). A
        window that starts after the end of a shortened run cannot be judged and is skipped."""
        req = self.scene.requirements
        if not req or not self.has_target or self.window_start() >= self.stop_time:
            return []
        m = self.los_metrics()
        failures = []
        if "los_rms_max_mrad" in req and not m["rms"] * 1e3 <= req["los_rms_max_mrad"]:
            failures.append(f"RMS LOS error {m['rms'] * 1e3:.4g} mrad > {req['los_rms_max_mrad']:g} mrad")
        if "los_final_max_mrad" in req and not m["final"] * 1e3 <= req["los_final_max_mrad"]:
            failures.append(f"final LOS error {m['final'] * 1e3:.4g} mrad > {req['los_final_max_mrad']:g} mrad")
        return failures

    def csv_columns(self) -> list[str]:
        return [name for name in self.signals if not name.startswith("_")]

    def write_csv(self, path: pathlib.Path) -> None:
        """One row per output_interval (SI units: rad, rad/s, V, A, N.m, m); all recorded signals."""
        every = int(round(self.scene.output_interval / self.scene.step_size))
        names = self.csv_columns()
        rows = np.arange(0, len(self.signals["time"]), every)
        if rows[-1] != len(self.signals["time"]) - 1:
            rows = np.append(rows, len(self.signals["time"]) - 1)
        data = np.column_stack([np.asarray(self.signals[n], dtype=float)[rows] for n in names])
        np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.12g")

    def summary(self) -> str:
        s = self.signals
        rtf = self.stop_time / self.wall_time if self.wall_time > 0 else math.inf
        parts = [f"{self.scene.name}: {self.stop_time:g} s simulated in {self.wall_time:.2f} s wall "
                 f"({rtf:.1f}x real time)"]
        if self.has_target:
            m = self.los_metrics()
            window = f" from {m['from_s']:g} s" if m["from_s"] > 0 else ""
            parts.append(f"LOS error final {m['final'] * 1e3:.4g} mrad, RMS{window} {m['rms'] * 1e3:.4g} mrad "
                         f"(max {m['max'] * 1e3:.4g} mrad)")
        else:
            parts.append(f"final alpha {math.degrees(s['alpha'][-1]):.4f} deg, beta {math.degrees(s['beta'][-1]):.4f} deg")
        if "events.total" in s:
            parts.append(f"{int(s['events.total'][-1])} events")
        if self.scene.requirements and self.has_target:
            failures = self.requirement_failures()
            if self.window_start() >= self.stop_time:
                parts.append("requirements not judged (run ends before their window)")
            else:
                parts.append("requirements met" if not failures else "REQUIREMENTS FAILED: " + "; ".join(failures))
        return "; ".join(parts)
