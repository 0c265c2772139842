"""A run's record: derived line-of-sight signals, metrics, requirement checks, CSV and summary line;
the line-of-sight error's spectrum per axis and the isolation estimated from a moving base
(spectra.py, docs/jitter.md)."""
from __future__ import annotations

import math
import pathlib

import numpy as np

from ..scene import geometry
from ..scene.controllers import AXES
from ..scene.drives import command_columns
from . import spectra, units
from .stopping import STOP_KINDS

# Per-axis signed pointing errors (line of sight minus target) [rad]: cross-elevation (the azimuth
# error times cos of the target's elevation, an angle across the line of sight) and elevation.
AXIS_ERRORS = {"los_error_xel": "cross-elevation", "los_error_el": "elevation"}
# The carrier's inertial angular velocity in the payload's frame 2, the input of the isolation estimate
# whose output is the gyro component about the same axis (los.omega[i]).
CARRIER_RATES = [f"base.omega2[{i}]" for i in (1, 2, 3)]
ISOLATION_AXES = {1: "elevation", 3: "cross_elevation"}


def tracking_signals(moving, s: dict) -> dict:
    """The tracking signals (scene.TRACKING_SIGNALS) of a record `s` toward the moving target: its
    azimuth, elevation (as target_direction's) and range in G, and the pointing command for the
    carrier's exact attitude, rates and accelerations (the base inputs), its azimuth in the 2 pi
    branch nearest the recorded alpha; "_direction": the unit vectors (3, n)."""
    from ..target import PointingCommand

    u, u_dot, u_ddot, distance, _ = moving.kinematics(s["time"])
    base = [np.array([s[f"base.{n}{suffix}"] for n in ("delta", "psi", "gamma")]) for suffix in ("", "_dot", "_ddot")]
    command = PointingCommand(u, u_dot, u_ddot, *base)
    alpha_cmd = command.alpha + 2.0 * np.pi * np.round((s["alpha"] - command.alpha) / (2.0 * np.pi))
    return {"target_azimuth": np.arctan2(-u[0], u[1]), "target_elevation": np.arctan2(u[2], np.hypot(u[0], u[1])),
            "target_range": distance, "alpha_cmd": alpha_cmd, "beta_cmd": command.beta,
            "alpha_cmd_dot": command.alpha_dot, "beta_cmd_dot": command.beta_dot,
            "alpha_cmd_ddot": command.alpha_ddot, "beta_cmd_ddot": command.beta_ddot, "_direction": u}


class RunResult:
    """`stop_time`: the end of the record (the last communication point recorded). `stopped`: None
    for a whole run, else a stopping.Stop (kind, time, reason) of a run that ended early, whose record
    covers [0, stopped.time] (master.run(keep_partial=True)); `requested_stop_time` is where it was
    to end."""

    def __init__(self, scene, signals: dict, wall_time: float, stop_time: float):
        self.scene, self.signals, self.wall_time, self.stop_time = scene, signals, wall_time, stop_time
        self.stopped, self.requested_stop_time = None, stop_time
        s = signals
        attitude = (s["base.delta"], s["base.psi"], s["base.gamma"])
        s["alpha_error"] = s["alpha_ref"] - s["alpha"]
        s["beta_error"] = s["beta_ref"] - s["beta"]
        az, el = geometry.los_azimuth_elevation(s["alpha"], s["beta"], *attitude)
        s["los_azimuth"], s["los_elevation"] = az, el
        moving = scene.moving_target
        if moving is not None:
            # a moving target: the error to where it is at each sample, the pointing command toward it
            tracking = tracking_signals(moving, s)
            direction = tracking.pop("_direction")
            s["los_error"] = geometry.angle_between(geometry.los_direction(s["alpha"], s["beta"], *attitude),
                                                    direction)
        elif scene.target_spec is not None:
            s["los_error"] = geometry.los_error(s["alpha"], s["beta"], *attitude,
                                                math.radians(scene.target_spec["azimuth_deg"]),
                                                math.radians(scene.target_spec["elevation_deg"]))
        else:
            s["los_error"] = np.full_like(s["alpha"], np.nan)
        # Signals derived for the spectra. Kept apart from `signals` (whose set is the record the golden
        # digests hold fixed), written to the CSV with them and readable by name through signal().
        self.derived = {}
        if moving is not None:
            self.derived.update(zip(AXIS_ERRORS, geometry.los_axis_errors(
                s["alpha"], s["beta"], *attitude, tracking["target_azimuth"], tracking["target_elevation"])))
            self.derived.update(tracking)
        elif self.has_target:
            self.derived.update(zip(AXIS_ERRORS, geometry.los_axis_errors(
                s["alpha"], s["beta"], *attitude, math.radians(scene.target_spec["azimuth_deg"]),
                math.radians(scene.target_spec["elevation_deg"]))))
        if self.base_moves:
            rates = (s["base.delta_dot"], s["base.psi_dot"], s["base.gamma_dot"])
            self.derived.update(zip(CARRIER_RATES, geometry.carrier_rate_in_payload(
                s["alpha"], s["beta"], s["base.psi"], s["base.gamma"], *rates)))

    @property
    def base_moves(self) -> bool:
        s = self.signals
        return any(np.any(s[f"base.{n}_dot"] != 0) for n in ("delta", "psi", "gamma")) if "base.delta_dot" in s \
            else False

    def final(self, name: str) -> float | None:
        """The last recorded value of a signal (None when not recorded)."""
        return float(self.signals[name][-1]) if name in self.signals else None

    def window_bounds(self) -> tuple[float, float]:
        """The first and last time of the metrics window (metrics_window)."""
        t = self.signals["time"][self.metrics_window()]
        return float(t[0]), float(t[-1])

    def carrier_spectrum(self, i: int) -> np.ndarray:
        """The PSD [(rad/s)^2/Hz] of the carrier's rate about payload axis i over the metrics window, at
        the isolation estimate's resolution."""
        return spectra.psd(self.derived[f"base.omega2[{i}]"][self.metrics_window()], 1.0 / self.scene.step_size,
                           self.scene.analysis.isolation_resolution_hz).psd

    def signal(self, name: str) -> np.ndarray:
        """A recorded or a derived signal by name."""
        return self.signals[name] if name in self.signals else self.derived[name]

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

    def metrics_window(self, from_s: float | None = None) -> np.ndarray:
        """The samples los_metrics takes: from `from_s` (default the requirements window's start), the
        whole run when the run ends before it."""
        start = self.window_start() if from_s is None else from_s
        window = self.signals["time"] >= start - 1e-12
        return window if window.any() else np.ones_like(window)

    def los_spectra(self, from_s: float | None = None) -> dict:
        """{cross-elevation error, elevation error: spectra.Spectrum} over the metrics window (empty
        without a target or with fewer than 2 samples there)."""
        cache = self.__dict__.setdefault("_los_spectra", {})
        if from_s not in cache:
            window = self.metrics_window(from_s)
            cache[from_s] = {} if not self.has_target or window.sum() < 2 else {
                name: spectra.psd(self.derived[name][window], 1.0 / self.scene.step_size,
                                  self.scene.analysis.psd_resolution_hz) for name in AXIS_ERRORS}
        return cache[from_s]

    def band_rms(self, from_s: float | None = None) -> dict:
        """{band name: RMS [rad] of the line-of-sight error in the band, both axes combined
        (root-sum-square of the cross-elevation and elevation band RMS)} for the scene's
        [analysis.bands]; nan when there is no spectrum."""
        found = self.los_spectra(from_s)
        return {name: math.hypot(*(sp.band_rms(lo, hi) for sp in found.values())) if found else math.nan
                for name, (lo, hi) in self.scene.analysis.bands.items()}

    def isolation_estimates(self) -> dict:
        """{1: elevation, 3: cross-elevation: spectra.TransferEstimate} of the gyro los.omega[i] against
        the carrier's rate about the same payload axis, over the metrics window; empty on a still base."""
        window = self.metrics_window()
        if not self.base_moves or window.sum() < 2:
            return {}
        return {i: spectra.transfer_estimate(self.derived[f"base.omega2[{i}]"][window],
                                             self.signals[f"los.omega[{i}]"][window], 1.0 / self.scene.step_size,
                                             self.scene.analysis.isolation_resolution_hz)
                for i in ISOLATION_AXES}

    def write_psd_csv(self, path: pathlib.Path) -> bool:
        """<scene>_psd.csv: frequency and, per axis, the PSD [rad^2/Hz] and the cumulative RMS [rad] of the
        line-of-sight error; a comment line states the estimate. False (nothing written) without one."""
        found = self.los_spectra()
        if not found:
            return False
        first = next(iter(found.values()))
        columns, names = [first.frequency], ["frequency_hz"]
        for name, spectrum in found.items():
            columns += [spectrum.psd, spectrum.cumulative_rms()]
            names += [f"psd_{name[len('los_error_'):]}_rad2_per_hz", f"cumulative_rms_{name[len('los_error_'):]}_rad"]
        t = self.window_bounds()
        means = ", ".join(f"{AXIS_ERRORS[n]} {sp.mean:.6g} rad" for n, sp in found.items())
        comment = (f"# Welch PSD of the line-of-sight error (line of sight minus target) over [{t[0]:g}, {t[-1]:g}] s: "
                   f"Hann window, {spectra.OVERLAP:.0%} overlap, {first.resolution:g} Hz resolution, "
                   f"{first.segments} segment(s); the mean was removed (static offset: {means})")
        np.savetxt(path, np.column_stack(columns), delimiter=",", header=comment + "\n" + ",".join(names),
                   comments="", fmt="%.10g")
        return True

    def write_isolation_csv(self, path: pathlib.Path) -> bool:
        """<scene>_isolation.csv: per payload axis the carrier rate's PSD [(rad/s)^2/Hz], the H1 gain and
        phase of the gyro against it and the coherence. False (nothing written) on a still base."""
        found = self.isolation_estimates()
        if not found:
            return False
        first = next(iter(found.values()))
        columns, names = [first.frequency], ["frequency_hz"]
        for i, estimate in found.items():
            axis = ISOLATION_AXES[i]
            carrier = self.carrier_spectrum(i)   # where the sea has energy
            with np.errstate(divide="ignore"):
                gain_db = 20 * np.log10(np.abs(estimate.response))
            columns += [carrier, np.abs(estimate.response), gain_db, np.degrees(np.angle(estimate.response)),
                        estimate.coherence, estimate.random_error, estimate.coherent.astype(int)]
            names += [f"{axis}_carrier_psd", f"{axis}_gain", f"{axis}_gain_db", f"{axis}_phase_deg", f"{axis}_coherence",
                      f"{axis}_gain_random_error", f"{axis}_coherent"]
        t = self.window_bounds()
        comment = (f"# H1 estimate of los.omega[i] against the carrier's inertial rate about the same payload axis "
                   f"(i = 1 elevation, 3 cross-elevation) over [{t[0]:g}, {t[-1]:g}] s: {spectra.WINDOW} window, "
                   f"{spectra.OVERLAP:.0%} overlap, {first.resolution:g} Hz resolution, {first.segments} segment(s); "
                   f"coherence from {first.segments} segments is about {1 / max(first.segments, 1):.2g} where "
                   f"nothing is related; coherent = 1 where the gain's random error (1 sigma, Bendat & Piersol, "
                   f"{first.averages:.3g} independent averages) is at most {spectra.H1_RANDOM_ERROR:.0%}, i.e. the "
                   f"coherence is at least {first.coherence_bound:.3g}: elsewhere the gain is not known")
        np.savetxt(path, np.column_stack(columns), delimiter=",", header=comment + "\n" + ",".join(names),
                   comments="", fmt="%.10g")
        return True

    def tracking_metrics(self):
        """The target.metrics.TrackingMetrics of a run with a moving target (else None), over the
        metrics window."""
        if self.scene.moving_target is None:
            return None
        from ..target.metrics import NEEDED, TrackingMetrics

        spec = self.scene.target_spec
        metrics = TrackingMetrics(spec["beam_width_mrad"], spec["keyhole_deg"], self.scene.step_size,
                                  self.window_start())
        metrics.add({name: np.asarray(self.signal(name)) for name in NEEDED
                     if name in self.signals or name in self.derived})
        return metrics

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
        return [name for name in self.signals if not name.startswith("_")] + list(self.derived)

    def write_csv(self, path: pathlib.Path) -> None:
        """One row per output_interval (SI units: rad, rad/s, V, A, N.m, m); all recorded signals."""
        every = int(round(self.scene.output_interval / self.scene.step_size))
        names = self.csv_columns()
        rows = np.arange(0, len(self.signals["time"]), every)
        if rows[-1] != len(self.signals["time"]) - 1:
            rows = np.append(rows, len(self.signals["time"]) - 1)
        data = np.column_stack([np.asarray(self.signal(n), dtype=float)[rows] for n in names])
        np.savetxt(path, data, delimiter=",", header=units.csv_header(names), comments="", fmt="%.12g")

    def summary(self) -> str:
        """The summary line: how long the run took, the pointing, the tracking, the bands, the events,
        the clamps and the requirements, each where the run has them."""
        parts = [self._timing_summary(), self._pointing_summary()]
        tracking = self.tracking_metrics()
        if tracking is not None:
            parts.append(tracking.summary())
        if self.has_target and self.scene.analysis.bands:
            parts.append(self._band_summary())
        if self.final("events.total") is not None:
            parts.append(f"{int(self.final('events.total'))} events")
        clamp = getattr(self, "voltage_clamp", None)   # results.ClampCount, set by the run
        if clamp is not None and clamp.summary():
            parts.append(clamp.summary())
        if self.scene.requirements and self.has_target:
            parts.append(self._requirements_summary())
        return "; ".join(parts)

    def _timing_summary(self) -> str:
        rtf = self.stop_time / self.wall_time if self.wall_time > 0 else math.inf
        timing = f"{self.stop_time:g} s simulated in {self.wall_time:.2f} s wall ({rtf:.1f}x real time)"
        if self.stopped is None:
            return f"{self.scene.name}: {timing}"
        return (f"{self.scene.name}: PARTIAL, {STOP_KINDS[self.stopped.kind]} at t = {self.stopped.time:g} s "
                f"of {self.requested_stop_time:g} s; {timing}")

    def _pointing_summary(self) -> str:
        if not self.has_target:
            return (f"final alpha {math.degrees(self.final('alpha')):.4f} deg, "
                    f"beta {math.degrees(self.final('beta')):.4f} deg")
        m = self.los_metrics()
        # the window the RMS and max were taken over as it was, not as asked: a run that ends before the
        # requirements' from_s is measured over the whole run (metrics_window)
        window = " over [{:g}, {:g}] s".format(*self.window_bounds())
        return (f"LOS error final {m['final'] * 1e3:.4g} mrad, RMS{window} {m['rms'] * 1e3:.4g} mrad "
                f"(max {m['max'] * 1e3:.4g} mrad)")

    def _band_summary(self) -> str:
        spectrum = next(iter(self.los_spectra().values()), None)
        resolution = f"{spectrum.resolution:g} Hz resolution" if spectrum else "no spectrum"
        rms = self.band_rms()
        window = " over [{:g}, {:g}] s".format(*self.window_bounds())
        bands = self.scene.analysis.bands
        return f"LOS RMS by band{window} ({resolution}): " + ", ".join(
            f"{name} [{lo:g}, {hi:g}) Hz {rms[name] * 1e3:.4g} mrad" for name, (lo, hi) in bands.items())

    def _requirements_summary(self) -> str:
        failures = self.requirement_failures()
        if self.window_start() >= self.stop_time:
            return "requirements not judged (run ends before their window)"
        return "requirements met" if not failures else "REQUIREMENTS FAILED: " + "; ".join(failures)


class ClampCount:
    """How often the controller's commands were clamped (voltages to +-U_L, current commands to
    +-i_L: scene/drives.py), per axis, accumulated over a run (or its chunks): the steps whose applied
    command differs from what the controller asked, of all steps, and the largest |command| asked on
    that axis."""

    def __init__(self, drives=None):
        self.clamped, self.steps, self.max_asked = [0, 0], 0, [0.0, 0.0]
        self.kinds = [("voltage", "V") if drive is None or drive.kind == "voltage" else ("current command", "A")
                      for drive in (drives or (None, None))]

    def add(self, asked: np.ndarray, commanded: np.ndarray) -> None:
        """`asked`, `commanded`: (rows, 2), the controller's outputs before and after the clamp."""
        self.steps += len(asked)
        for axis in (0, 1):
            self.clamped[axis] += int(np.count_nonzero(asked[:, axis] != commanded[:, axis]))
            if len(asked):
                self.max_asked[axis] = max(self.max_asked[axis], float(np.max(np.abs(asked[:, axis]))))

    def summary(self) -> str | None:
        """"voltage clamped on 1,234 of 60,000 steps (azimuth), max asked 1e+06 V; ..." ("current command
        clamped ..., max asked 12 A" for a motor in current drive) or None when nothing was clamped."""
        parts = [f"{self.kinds[axis][0]} clamped on {self.clamped[axis]:,} of {self.steps:,} steps ({AXES[axis]}), "
                 f"max asked {self.max_asked[axis]:.4g} {self.kinds[axis][1]}" for axis in (0, 1) if self.clamped[axis]]
        return "; ".join(parts) or None


def clamp_count(signals: dict) -> ClampCount:
    """The ClampCount of a run's recorded signals (Plan.chunk_signals), each axis by the columns of its drive."""
    drives = [command_columns(signals, motor) for motor in (1, 2)]
    count = ClampCount(drives)
    count.add(np.column_stack([signals[drive.asked] for drive in drives]),
              np.column_stack([signals[drive.commanded] for drive in drives]))
    return count
