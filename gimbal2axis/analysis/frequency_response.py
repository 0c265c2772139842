"""Frequency responses of the nonlinear FMU by simulation: sine dwell, one run per frequency.

Three excitations:
  - "voltage": a motor voltage u_R<axis> = offset + amplitude sin(w t), open loop (the Replay
    controller; the other motor at 0 V). The scene's base motion is used as given (normally fixed).
  - "base": the carrier's roll, pitch or yaw *rate* is a sine of the given rate amplitude (base motion
    type "sinusoids" on that one axis, angle amplitude = rate amplitude / w), through the scene's own
    closed loop (its controller).
  - "injection": the loop gain of the scene's own closed loop broken at one motor's voltage (the
    control engineer's voltage injection): the scene's controller runs, wrapped (InjectingController)
    so that D_k = amplitude sin(w t_k) is added to axis <axis>'s *computed* voltage at t_k, after the
    controller's own clamp and before the master's delay and hold. What the master records as the
    command u_R<axis>_cmd is then A = U + D, U the controller's own output; A is what the delay line
    and the hold pass on to the motor. The loop gain at that point is L = -U / A (the other axis's loop
    closed), the sensitivity A / D = 1 / (1 + L). The base is fixed (a carrier at rest).

Each run settles for max(settle_periods / f, settle_s) and then measures over exactly
`measure_periods` periods. The frequency is snapped so that those periods span an integer number of
communication steps (the reported frequency_hz is the one simulated): the single-bin DFT
    X = (2 / n) sum_k x_k exp(-j w t_k)       (k over the measurement window)
is then exactly orthogonal to the mean and to every other harmonic. Gain and phase are Y / U.

The input's fundamental is the *continuous-time* one: an applied motor voltage is a staircase
(held over each step, zero-order hold), whose fundamental is the samples' one times
exp(-j w h / 2) sin(w h / 2) / (w h / 2); without that correction the phase would be off by w h / 2
(1.8 deg at 10 Hz with h = 1 ms). The base rates are exact sine values at the step starts (the FMU
moves the carrier on with the exact acceleration), the outputs are exact samples: no correction.

"coherence" here is the fraction of the output's power (its variance over the window) that is in
the fundamental: |Y|^2 / 2 / var(y), computed as the projection of y on the sine and cosine at f
(power_fraction), hence in [0, 1] by construction. 1 for a linear response without noise; less when
the nonlinear plant puts power into harmonics, sub-harmonics or a drift. It is NOT Welch's
magnitude-squared coherence (a sine dwell has one frequency per run, so that estimator has nothing to
average over).

A frequency that the snapping leaves with fewer than MIN_STEPS_PER_PERIOD steps per period is refused
(check_resolvable, SceneError) before it runs: nearer the Nyquist frequency the samples alias.

Each point carries the window's own measures of linearity (harmonic_amplitude, drift_amplitude:
linearity_measures) and the window's mean gimbal angles; mark_rows writes into `marks` why a point is
not a frequency response to LINEARITY_TOLERANCE (harmonics, drift, off the linear prediction, measured
away from the prediction's operating point), marks_summary counts them in one line and plot_bode draws
such points grey (docs/frequency_response.md, "Points that are not a frequency response").

For a base excitation the combined line-of-sight output "los" is sqrt(|G_1|^2 + |G_3|^2) of the two
gyro components that move the line of sight (los.omega[1], elevation; los.omega[3], cross-elevation):
the isolation (stabilization) ratio, LOS inertial rate / carrier rate. It has no phase (NaN).
"""
from __future__ import annotations

import csv
import dataclasses
import hashlib
import math
import pathlib

import numpy as np

from ..errors import SceneError

BASE_AXES = {"pitch": "base.delta_dot", "yaw": "base.psi_dot", "roll": "base.gamma_dot"}
LOS_OUTPUTS = ["los.omega[1]", "los.omega[3]"]
LINEAR_FIDELITY = {"gear1.model": 1, "gear2.model": 1, "dry_friction": False}


MOTOR_AXES = ("1", "2")
LOOP_GAIN = "loop_gain"        # output: -U / A at the injection point
SENSITIVITY = "sensitivity"    # output: A / D = 1 / (1 + L)
INJECTION_OUTPUTS = {"1": ["los.omega[3]"], "2": ["los.omega[1]"]}   # the LOS rate each motor moves


@dataclasses.dataclass(frozen=True)
class Excitation:
    kind: str                 # "voltage", "base" or "injection"
    axis: str                 # "1" / "2" (motor) or "roll" / "pitch" / "yaw"
    amplitude: float          # V, or rad/s (rate amplitude of the carrier)
    offset: float = 0.0       # V, a constant voltage added (voltage only)
    # the excited motor's drive (scene/drives.py): in "current" drive the open-loop excitation is its current
    # command i_R<axis>_cmd [A] (amplitude and offset in A) and an injection adds to its current command
    drive: str = "voltage"

    def __post_init__(self):
        if self.kind not in ("voltage", "base", "injection"):
            raise ValueError(f"excitation kind must be 'voltage', 'base' or 'injection', got {self.kind!r}")
        if self.kind in ("voltage", "injection") and self.axis not in MOTOR_AXES:
            raise ValueError(f"a {self.kind} excitation needs axis '1' or '2', got {self.axis!r}")
        if self.kind == "base" and self.axis not in BASE_AXES:
            raise ValueError(f"a base excitation needs axis roll, pitch or yaw, got {self.axis!r}")

    @property
    def input_signal(self) -> str:
        """The signal the gains are referred to: for an injection the injected sine D itself."""
        if self.kind == "voltage":
            return f"u_R{self.axis}" if self.drive == "voltage" else f"i_R{self.axis}_cmd"
        return BASE_AXES[self.axis] if self.kind == "base" else injection_signal(self.axis)

    def default_outputs(self) -> list[str]:
        if self.kind == "voltage":
            return ["alpha_dot", "los.omega[3]"] if self.axis == "1" else ["beta_dot", "los.omega[1]"]
        if self.kind == "injection":
            return list(INJECTION_OUTPUTS[self.axis])
        return list(LOS_OUTPUTS)


def injection_signal(axis: str) -> str:
    """The name of the injected sine D on motor `axis` (rows' input of the responses to it)."""
    return f"injection_R{axis}"


def command_signal(axis: str, drive: str = "voltage") -> str:
    """The recorded computed voltage of motor `axis` (its current command in current drive): A = U + D
    during an injection."""
    return f"u_R{axis}_cmd" if drive == "voltage" else f"i_R{axis}_ctrl"


class InjectingController:
    """The scene's controller with `amplitude sin(2 pi f t_k)` added to motor `axis`'s computed voltage.

    The sine is added to what the controller returns at t_k (after its own clamp and anti-windup, which
    see only its own output U), so the master records A = U + D as the command and delays and holds A
    like any command. Everything else (prepare, start, the references it records) is the wrapped
    controller's: it behaves as in the scene. Being no built-in class, it runs in the Python loop."""

    kind = "injection"

    def __init__(self, controller, axis: str, amplitude: float, frequency_hz: float):
        if axis not in MOTOR_AXES:
            raise SceneError(f"injection axis must be '1' or '2', got {axis!r}")
        self.controller = controller
        self.index = int(axis) - 1
        self.amplitude = float(amplitude)
        self.w = 2 * math.pi * float(frequency_hz)

    def injection(self, t):
        """D at the time(s) t: the same expression the loop adds, for the analysis to subtract."""
        return self.amplitude * np.sin(self.w * np.asarray(t, float))

    @property
    def reference(self):
        return self.controller.reference

    @property
    def u_limit(self):
        return self.controller.u_limit

    @property
    def asked(self):
        """The wrapped controller's voltages before its own clamp (the injection is added after it)."""
        return self.controller.asked

    def prepare(self, times, h, attitude, rates) -> None:
        self.controller.prepare(times, h, attitude, rates)

    def start(self, step_size: float, scene_name: str) -> None:
        self.controller.start(step_size, scene_name)

    def __call__(self, t, h, alpha, beta, gyro, base_attitude, base_rates, step=None):
        u = list(self.controller(t, h, alpha, beta, gyro, base_attitude, base_rates, step=step))
        u[self.index] += self.amplitude * math.sin(self.w * t)
        return tuple(u)


@dataclasses.dataclass(frozen=True)
class Dwell:
    settle_periods: float = 5.0
    settle_s: float = 0.0      # at least this long (for a closed loop slower than a few periods)
    measure_periods: int = 4


def log_frequencies(f_min: float, f_max: float, points: int) -> list[float]:
    return np.logspace(math.log10(f_min), math.log10(f_max), points).tolist()


# The fewest communication steps per period a dwell is run at. The dwell's samples and the held input
# alias above 1 / (2 h) (at 1 / (2 h) the single-bin DFT is no longer orthogonal to the mean, at 1 / h it
# is the mean), and the continuous-time G(j w) drawn as the linear prediction departs from what a sampled,
# held loop measures as f nears 1 / (2 h). Measured at h = 1 ms, no backlash or dry friction, 0.5 V, both
# axes, dwell against G(j w): 10 steps per period 5e-5 and 0.003 deg, 5 steps 1.7e-3 and 0.08 deg,
# 4 steps 6.3e-3 and 0.32 deg, 3 steps 3.7e-2 and 2.1 deg (against the sampled-data form
# held_frequency_response within 6e-5 throughout). 4 keeps the prediction within the 1 % and 1 deg the
# tests hold it to: at most 250 Hz at a 1 ms step.
MIN_STEPS_PER_PERIOD = 4


def highest_frequency(h: float, dwell: Dwell) -> float:
    """The highest frequency a dwell is run at with step h: at least MIN_STEPS_PER_PERIOD steps per period
    after snapping (the measured periods a whole number of steps, at least MIN_STEPS_PER_PERIOD each)."""
    return 1.0 / (MIN_STEPS_PER_PERIOD * h)


def check_resolvable(frequencies, h: float, dwell: Dwell, what: str = "frequency") -> None:
    """Refuses (SceneError, one line) a requested frequency that the snapping would run at fewer than
    MIN_STEPS_PER_PERIOD steps per period: with step h the sine would alias and gain, phase and
    coherence would be meaningless."""
    if dwell.measure_periods < 1:
        raise SceneError(f"measure periods {dwell.measure_periods}: need at least 1")
    for requested in frequencies:
        f, _, n_measure = snapped_grid(requested, h, dwell, checked=False)
        if n_measure < MIN_STEPS_PER_PERIOD * dwell.measure_periods:
            raise SceneError(
                f"{what} {requested:g} Hz is beyond what the scene's step of {h:g} s resolves, "
                f"{highest_frequency(h, dwell):g} Hz: a dwell needs at least {MIN_STEPS_PER_PERIOD} steps per "
                f"period (2 is the Nyquist frequency; below {MIN_STEPS_PER_PERIOD} the measurement and the linear "
                f"prediction part by more than 1 % and 1 deg), and snapped so that {dwell.measure_periods} periods "
                f"are a whole number of steps it would run at {f:g} Hz, {n_measure / dwell.measure_periods:g} "
                f"steps per period")


def snapped_grid(frequency: float, h: float, dwell: Dwell, checked: bool = True):
    """(f actually simulated, steps to settle, steps to measure): the `measure_periods` periods span
    n_measure = round(measure_periods / (frequency h)) whole steps, f = measure_periods / (n_measure h).
    Refuses a frequency that leaves fewer than MIN_STEPS_PER_PERIOD steps per period (checked)."""
    if checked:
        check_resolvable([frequency], h, dwell)
    n_measure = max(int(round(dwell.measure_periods / (frequency * h))), 1)
    f = dwell.measure_periods / (n_measure * h)
    n_settle = int(math.ceil(max(dwell.settle_periods / f, dwell.settle_s) / h - 1e-9))
    return f, n_settle, n_measure


def fundamental(x: np.ndarray, t: np.ndarray, f: float) -> complex:
    """Complex amplitude X of x ~ Re(X exp(j w t)) over a window of whole periods (single-bin DFT)."""
    return complex(2.0 / len(x) * np.sum(x * np.exp(-2j * math.pi * f * t)))


def zoh_fundamental(samples_fundamental: complex, f: float, h: float) -> complex:
    """The continuous-time fundamental of a staircase held over each step from its samples' one."""
    half = math.pi * f * h
    return samples_fundamental * complex(math.cos(half), -math.sin(half)) * (math.sin(half) / half)


def power_fraction(x: np.ndarray, t: np.ndarray, f: float) -> float:
    """The fraction of the variance of x that a sine of frequency f explains: the squared norm of the
    least-squares projection of x - mean(x) on cos(w t), sin(w t), over the squared norm of x - mean(x).
    A projection is never longer than what it projects, so it lies in [0, 1] whatever f and the window
    (the clip removes only round-off). Over whole periods below the Nyquist frequency cos and sin are
    orthogonal with norm n/2, and it equals |X|^2 / 2 / var(x) of the single-bin DFT X."""
    centred = np.asarray(x, float) - np.mean(x)
    total = float(centred @ centred)
    if total == 0:
        return math.nan
    w = 2 * math.pi * f
    basis = np.column_stack([np.cos(w * t), np.sin(w * t)])
    coefficients, *_ = np.linalg.lstsq(basis, centred, rcond=None)
    explained = basis @ coefficients
    return min(max(float(explained @ explained) / total, 0.0), 1.0)


def _scene_for(scene, excitation: Excitation, f: float, stop_time: float, fidelity: dict | None):
    changes = {"stop_time": stop_time}
    if fidelity:
        merged = dict(scene.fidelity)
        merged.update(fidelity)
        changes["fidelity"] = merged
    if excitation.kind == "injection":   # the loop gain at the operating point of a carrier at rest
        changes["base_motion_spec"] = {"type": "fixed"}
    if excitation.kind == "base":
        changes["base_motion_spec"] = {
            "type": "sinusoids",
            excitation.axis: {"amplitude_deg": math.degrees(excitation.amplitude / (2 * math.pi * f)),
                              "frequency_hz": f}}
    return scene.with_changes(**changes)


def measure_point(scene, fmu, frequency: float, excitation: Excitation, dwell: Dwell = Dwell(),
                  outputs: list[str] | None = None, fidelity: dict | None = None, slave=None, log=None) -> list[dict]:
    """One sine dwell at `frequency`: one row per output (and 'los' for a base excitation; for an
    injection first 'loop_gain' = -U / A, input u_R<axis>_cmd, coherence that of U, and 'sensitivity' =
    A / D, then the outputs per D, input injection_R<axis>)."""
    from ..master.master import run

    h = scene.step_size
    f, n_settle, n_measure = snapped_grid(frequency, h, dwell)
    n = n_settle + n_measure
    run_scene = _scene_for(scene, excitation, f, n * h, fidelity)
    controller = _controller_for(run_scene, fmu, excitation, f, n)
    result = run(run_scene, fmu, controller=controller, slave=slave, log=log)
    sig = dict(result.signals)
    if excitation.kind == "injection":
        sig[excitation.input_signal] = controller.injection(sig["time"])
    window = slice(n_settle, n_settle + n_measure)
    t = sig["time"][window]
    u = np.asarray(sig[excitation.input_signal])[window]
    U = fundamental(u, t, f)
    if excitation.kind == "voltage":
        U = zoh_fundamental(U, f, h)
    common = dict(frequency_hz=f, requested_hz=frequency, input=excitation.input_signal,
                  input_amplitude=abs(U), samples_per_period=1.0 / (f * h), settle_s=n_settle * h,
                  measure_periods=dwell.measure_periods, current_limited_fraction=_limited_fraction(sig, window),
                  alpha_mean_deg=math.degrees(float(np.mean(sig["alpha"][window]))),
                  beta_mean_deg=math.degrees(float(np.mean(sig["beta"][window]))))
    rows = _injection_rows(common, sig, window, t, f, excitation.axis, U) if excitation.kind == "injection" else []
    gains = {}
    for name in outputs or excitation.default_outputs():
        y = np.asarray(sig[name])[window]
        Y = fundamental(y, t, f)
        gains[name] = Y / U
        rows.append(_gain_row(common, name, Y / U, y, Y, t, f))
    if excitation.kind == "base" and all(name in gains for name in LOS_OUTPUTS):
        rows.append(_los_row(common, rows, gains, U))
    return rows


def _limited_fraction(sig: dict, window: slice) -> float:
    """The share of the window's steps in which a motor's current was at its limit."""
    limited = np.zeros(window.stop - window.start, bool)
    for j in (1, 2):
        if f"motor{j}.limited" in sig:
            limited |= np.asarray(sig[f"motor{j}.limited"])[window] != 0
    return float(limited.mean())


def _los_row(common: dict, rows: list[dict], gains: dict, U: complex) -> dict:
    """The combined line-of-sight row 'los' of a base excitation: sqrt(|G_1|^2 + |G_3|^2), no phase."""
    g = math.sqrt(sum(abs(gains[name]) ** 2 for name in LOS_OUTPUTS))
    parts = [r for r in rows if r["output"] in LOS_OUTPUTS]
    total_var = sum(r["output_variance"] for r in parts)
    # the variance-weighted mean of the components' fractions: the explained power over the total, in [0, 1]
    explained = sum(r["coherence"] * r["output_variance"] for r in parts)
    return dict(common, output="los", gain=g, gain_db=20 * math.log10(g) if g > 0 else -math.inf,
                phase_deg=math.nan,
                coherence=explained / total_var if total_var > 0 else math.nan,
                output_amplitude=g * abs(U), output_mean=math.nan, output_variance=total_var,
                harmonic_amplitude=math.hypot(*(r["harmonic_amplitude"] for r in parts)),
                drift_amplitude=math.hypot(*(r["drift_amplitude"] for r in parts)))


def _controller_for(run_scene, fmu, excitation: Excitation, f: float, n: int):
    """The controller of the run: None (the scene's own), Replay of the sine (voltage), or the scene's
    own wrapped by InjectingController (injection)."""
    from ..scene.controllers import Replay

    h = run_scene.step_size
    if excitation.kind == "voltage":
        t = np.arange(n + 1) * h
        voltages = np.zeros((n + 1, 2))
        # the command at t_k is applied delay steps later: its phase does not matter, u_R<j> is measured
        voltages[:, int(excitation.axis) - 1] = excitation.offset + excitation.amplitude * np.sin(2 * math.pi * f * t)
        return Replay(voltages)
    if excitation.kind == "injection":
        from ..scene.drives import scene_drives

        u_limit = tuple(drive.limit for drive in scene_drives(run_scene, fmu))
        return InjectingController(run_scene.controller(u_limit), excitation.axis, excitation.amplitude, f)
    return None


def _gain_row(common: dict, output: str, G: complex, y: np.ndarray, Y: complex, t: np.ndarray, f: float,
              **extra) -> dict:
    """A row of gain G for `output` whose samples over the window (times t) are y, fundamental Y at f,
    with the window's own measures of linearity (linearity_measures)."""
    harmonics, drift = linearity_measures(y, common["measure_periods"])
    return dict(common, output=output, gain=abs(G), gain_db=20 * math.log10(abs(G)) if G != 0 else -math.inf,
                phase_deg=math.degrees(math.atan2(G.imag, G.real)), coherence=power_fraction(y, t, f),
                output_amplitude=abs(Y), output_mean=float(np.mean(y)), output_variance=float(np.var(y)),
                harmonic_amplitude=harmonics, drift_amplitude=drift, **extra)


# -- does a point describe a frequency response? ----------------------------------------------------------
#
# A sine dwell measures the frequency response of a linear, time-invariant system only if the output has
# settled to a sine of the input's frequency about a fixed operating point, and it is the *linear
# prediction's* frequency response only if the run stays at the operating point the prediction was made
# at. Each point is checked against both, with one tolerance: the accuracy the linear prediction is held
# to where it applies (the tests' 1 % and 1 deg; measured within 0.6 % and 0.32 deg up to 4 steps per
# period, 5e-5 and 0.003 deg below). A point whose output departs from a steady sine by more than that, or
# from the prediction by more, is not read to that accuracy as a frequency response. The reasons, in the
# CSV's column `marks` (empty: a frequency response), docs/frequency_response.md, "Points that are not a
# frequency response":
#   harmonics   the output's power at 2f, 3f, ... (up to the Nyquist frequency), as an amplitude, over the
#               fundamental's: a nonlinearity at work (the fundamental is then a describing function)
#   drift       the output is not periodic over the window: the change of its fundamental from the first
#               to the last measured period, or the change of its mean (as the error it puts on the
#               fundamental's estimate, below), over the fundamental; needs 2 measured periods
#   vs linear   a curve of the prediction's fidelity (no backlash, no dry friction) off the prediction
#               by more than the tolerance in gain or phase
#   operating point  the linear model at the window's gimbal angles (open loop: where gravity has moved
#               an unbalanced payload) predicts a gain or phase off the prediction's by more than the
#               tolerance: the prediction was made at a point the run is no longer at
LINEARITY_TOLERANCE = 0.01          # relative, of the fundamental's amplitude (gain ratio - 1)
PHASE_TOLERANCE_DEG = 1.0


def linearity_measures(y: np.ndarray, periods: int) -> tuple[float, float]:
    """(harmonic amplitude, drift amplitude) of the samples y over a window of `periods` whole periods of
    the fundamental (equally spaced samples, not necessarily a whole number per period), both in y's unit,
    to be compared with the fundamental's amplitude |Y|.

    harmonic amplitude: sqrt(sum over k >= 2 of |Y_k|^2), Y_k the window's single-bin DFT at k f (the bins
    k * periods of the window's FFT, up to the Nyquist bin), single-sided amplitudes like Y.
    drift amplitude: y fitted by least squares over the window with its harmonics and a mean and a
    fundamental that both change linearly in time, m0 + m1 tau + Re((X0 + X1 tau) exp(j w t)), tau from
    -1/2 to 1/2 over the window. The larger of |X1| (periods - 1) / periods, the change of the fundamental from the first to
    the last measured period's centre (the response still settling), and |m1| / (pi periods), the error a
    ramp of the mean by m1 over the window puts on the single-bin DFT (a ramp's Fourier coefficient at
    the periods-th harmonic). NaN with fewer than 2 periods (a change within one period is not told from
    a harmonic)."""
    y = np.asarray(y, float)
    n = len(y)
    amplitudes = np.abs(np.fft.rfft(y - y.mean())) * (2.0 / n)
    if n % 2 == 0:
        amplitudes[-1] /= 2   # the Nyquist bin is not doubled in a single-sided amplitude
    harmonic = float(np.sqrt(np.sum(amplitudes[2 * periods::periods] ** 2)))
    if periods < 2:
        return harmonic, math.nan
    phase = 2 * math.pi * periods * np.arange(n) / n   # w t over the window
    tau = (np.arange(n) - (n - 1) / 2) / n
    basis = np.column_stack([np.ones(n), tau, np.cos(phase), np.sin(phase), tau * np.cos(phase), tau * np.sin(phase)])
    # fitted together with every harmonic: tau sin(w t) is not orthogonal to sin(k w t) over the window, so
    # a steady harmonic left out would read as a changing fundamental. The harmonics' DFT bins are an
    # orthogonal basis, so fitting y and the basis with those bins removed is that joint least squares.
    (_, mean_slope, _, _, cos_slope, sin_slope), *_ = np.linalg.lstsq(
        _without_harmonics(basis, periods), _without_harmonics(y, periods), rcond=None)
    amplitude_change = abs(complex(cos_slope, -sin_slope)) * (periods - 1) / periods
    return harmonic, max(amplitude_change, abs(mean_slope) / (math.pi * periods))


def _without_harmonics(x: np.ndarray, periods: int) -> np.ndarray:
    """x (along its first axis, a window of `periods` whole periods) with its DFT bins at 2f, 3f, ...
    removed: the orthogonal projection off the harmonics of f."""
    n = x.shape[0]
    spectrum = np.fft.rfft(x, axis=0)
    spectrum[2 * periods::periods] = 0
    return np.fft.irfft(spectrum, n, axis=0)


def linearity_marks(row: dict, predicted: complex | None = None, operating_point_change: complex | None = None,
                    operating_point: str = "") -> list[str]:
    """The reasons (module comment above LINEARITY_TOLERANCE) why `row` is not a frequency response to the
    tolerance: [] if it is. `predicted`: the linear prediction's G at the row's frequency, for a row of the
    prediction's fidelity; `operating_point_change`: the linear model's G at the window's operating point
    (described by `operating_point`) over its G at the prediction's point, at the row's frequency."""
    reasons = []
    amplitude = row["output_amplitude"]
    if amplitude > 0:
        if row.get("harmonic_amplitude", 0) > LINEARITY_TOLERANCE * amplitude:
            reasons.append(f"harmonics {100 * row['harmonic_amplitude'] / amplitude:.3g} %")
        drift = row.get("drift_amplitude", math.nan)
        if drift > LINEARITY_TOLERANCE * amplitude:
            reasons.append(f"drift {100 * drift / amplitude:.3g} %")
    elif row.get("output_variance", 0) > 0:   # an output that moves, but not at all at f
        reasons.append("no fundamental")
    if predicted is not None:
        mismatch = _mismatch(row["gain"], row["phase_deg"], predicted)
        if mismatch:
            reasons.append(f"vs linear {mismatch}")
    if operating_point_change is not None:
        change = _mismatch(abs(operating_point_change), math.degrees(np.angle(operating_point_change)), 1.0)
        if change:
            reasons.append(f"operating point {operating_point}: linear there {change}")
    return reasons


def _mismatch(gain: float, phase_deg: float, predicted: complex) -> str:
    """'' when gain and phase (NaN: none) are within the tolerance of `predicted`, else the departure in
    dB and deg."""
    if predicted == 0 or gain == 0:
        return "" if gain == abs(predicted) else "against an exact zero"
    ratio = gain / abs(predicted)
    phase = math.nan if math.isnan(phase_deg) else (phase_deg - math.degrees(np.angle(predicted)) + 180) % 360 - 180
    if abs(ratio - 1) <= LINEARITY_TOLERANCE and not abs(phase) > PHASE_TOLERANCE_DEG:
        return ""
    return f"{20 * math.log10(ratio):+.3g} dB" + ("" if math.isnan(phase) else f" {phase:+.3g} deg")


def mark_rows(rows: list[dict], prediction_curve=lambda curve: False, predicted=None,
              operating_point_change=None) -> None:
    """Writes row['marks'] (linearity_marks joined by '; ', '' for a frequency response) into every
    measured row. `prediction_curve(curve)`: whether the curve has the prediction's fidelity;
    `predicted(output, frequency_hz)`: the prediction's complex G, or None where it has none;
    `operating_point_change(row)`: (the linear model's G at the row's window operating point over the
    prediction's, its description) or None."""
    for row in rows:
        if row.get("curve") == LINEAR_CURVE:
            continue
        G = predicted(row["output"], row["frequency_hz"]) if predicted and prediction_curve(row.get("curve", "")) \
            else None
        change = operating_point_change(row) if operating_point_change else None
        row["marks"] = "; ".join(linearity_marks(row, G, *(change or (None, ""))))


def marks_summary(rows: list[dict]) -> str | None:
    """One line: per simulated curve how many of its points are not a frequency response, with the
    reasons counted; None when every checked point is one."""
    by_curve: dict = {}
    for row in rows:
        if row.get("curve") != LINEAR_CURVE and "marks" in row:
            by_curve.setdefault(row["curve"], []).append(row)
    if not any(r["marks"] for points in by_curve.values() for r in points):
        return None
    parts = [_curve_marks(curve, points) for curve, points in by_curve.items()]
    return (f"not a frequency response to {100 * LINEARITY_TOLERANCE:g} % and {PHASE_TOLERANCE_DEG:g} deg "
            f"(CSV column marks, grey in the plot; docs/frequency_response.md): " + "; ".join(parts))


def _curve_marks(curve: str, points: list[dict]) -> str:
    """'<curve> <marked> of <points> (<reason> <count>, ...)'."""
    marked = [r for r in points if r["marks"]]
    counts: dict = {}
    for row in marked:
        for reason in row["marks"].split("; "):
            key = next(k for k in ("harmonics", "drift", "vs linear", "operating point", reason)
                       if reason.startswith(k))
            counts[key] = counts.get(key, 0) + 1
    why = ", ".join(f"{key} {count}" for key, count in counts.items())
    return f"{curve or 'simulated'} {len(marked)} of {len(points)}" + (f" ({why})" if why else "")


def _injection_rows(common: dict, sig: dict, window: slice, t: np.ndarray, f: float, axis: str, D: complex) -> list:
    """'loop_gain' = -U / A (A = the recorded command, U = A - D the controller's own output; all samples
    at t_k, so no hold correction: the prediction is of samples too) and 'sensitivity' = A / D."""
    from ..scene.drives import command_columns

    command = command_columns(sig, int(axis)).commanded
    a = np.asarray(sig[command])[window]
    d = np.asarray(sig[injection_signal(axis)])[window]
    u = a - d
    A, U = fundamental(a, t, f), fundamental(u, t, f)
    loop_gain = _gain_row(dict(common, input=command, input_amplitude=abs(A)), LOOP_GAIN, -U / A, u, U,
                          t, f)
    return [loop_gain, _gain_row(common, SENSITIVITY, A / D, a, A, t, f)]


# -- the linear model's prediction ------------------------------------------------------------------

LINEAR_CURVE = "linear model"


def linear_point(scene, fmu, excitation: Excitation, fidelity: dict | None = None) -> dict:
    """The operating point of an open-loop dwell as linearize() takes it: the scene's fidelity (with
    `fidelity` over it), parameters and initial state, the base fixed, the voltage at its offset."""
    from ..scene.scene import start_values

    if excitation.kind != "voltage":
        raise ValueError("the linear model's prediction is drawn for the open-loop (voltage) excitation only")
    values = start_values(scene, fmu, np.zeros(15))
    values.update(fidelity or {})
    values["base.fixed"] = True
    values[excitation.input_signal] = excitation.offset
    return values


def linear_rows(model, rows: list[dict]) -> list[dict]:
    """The linear model's G(j w) = C (j w I - A)^-1 B + D at the frequencies and for the outputs of the
    simulated `rows` (one row each, curve LINEAR_CURVE; coherence 1 by definition)."""
    out, seen = [], set()
    for row in rows:
        key = (row["output"], row["frequency_hz"])
        if key in seen or row["output"] not in model.outputs:
            continue
        seen.add(key)
        G = complex(model.frequency_response([row["frequency_hz"]], row["input"], row["output"])[0])
        out.append(dict(curve=LINEAR_CURVE, input=row["input"], output=row["output"], requested_hz=row["requested_hz"],
                        frequency_hz=row["frequency_hz"], gain=abs(G),
                        gain_db=20 * math.log10(abs(G)) if G != 0 else -math.inf,
                        phase_deg=math.degrees(math.atan2(G.imag, G.real)), coherence=1.0))
    return out


def prediction_errors(rows: list[dict], predicted) -> list[tuple]:
    """(row, gain ratio - 1, phase difference in deg) of each measured row against `predicted(output,
    frequency_hz)`, a complex gain; the phase difference is wrapped to +-180 and NaN where the row has no
    phase (the combined 'los')."""
    out = []
    for row in rows:
        G = complex(predicted(row["output"], row["frequency_hz"]))
        phase = math.nan if math.isnan(row["phase_deg"]) else \
            (row["phase_deg"] - math.degrees(math.atan2(G.imag, G.real)) + 180) % 360 - 180
        out.append((row, row["gain"] / abs(G) - 1, phase))
    return out


def linear_lines(model, input_signal: str, outputs: list[str], f_min: float, f_max: float, points: int = 400) -> list:
    """Dense Bode lines of the linear model for plot_bode: [(label, frequencies, complex G), ...] (a 4th
    element False marks a line without phase)."""
    f = np.logspace(math.log10(f_min), math.log10(f_max), points)
    return [(f"{LINEAR_CURVE}: {name}", f, model.frequency_response(f, input_signal, name)) for name in outputs
            if name in model.outputs]


# -- many frequencies: serially or on Dask -----------------------------------------------------------

def _point_task(fmu_bytes: bytes, digest: str, scene, frequency, excitation, dwell, outputs, fidelity):
    from ..fmu.worker_cache import loaded_fmu

    loaded = loaded_fmu(fmu_bytes, digest)
    return measure_point(scene, loaded.fmu, frequency, excitation, dwell, outputs, fidelity,
                         slave=loaded.instance(), log=loaded.log)


def sweep(scene, fmu_path, frequencies, excitation: Excitation, dwell: Dwell = Dwell(), outputs=None,
          fidelity: dict | None = None, client=None, curve: str = "") -> list[dict]:
    """measure_point at every frequency; on `client` (a Dask Client) in parallel, else serially in this
    process on one FMU instance. Rows carry `curve` (a label of the variant)."""
    fmu_path = pathlib.Path(fmu_path)
    if client is None:
        from ..fmu import FMU

        rows = []
        with FMU(fmu_path) as fmu:
            log: list = []
            slave = fmu.instantiate("frequency_response", log)
            try:
                for f in frequencies:
                    rows += measure_point(scene, fmu, f, excitation, dwell, outputs, fidelity, slave=slave, log=log)
            finally:
                slave.freeInstance()
    else:
        data = fmu_path.read_bytes()
        digest = hashlib.sha256(data).hexdigest()
        # a key of its own (hash=False): a second sweep scattering the same bytes must not share the key
        # the first one releases when it returns
        data_future = client.scatter(data, broadcast=True, hash=False)
        futures = [client.submit(_point_task, data_future, digest, scene, f, excitation, dwell, outputs, fidelity,
                                 pure=False) for f in frequencies]
        rows = [row for future in futures for row in future.result()]
    for row in rows:
        row["curve"] = curve
    return rows


COLUMNS = ["curve", "input", "output", "requested_hz", "frequency_hz", "gain", "gain_db", "phase_deg", "coherence",
           "input_amplitude", "output_amplitude", "output_mean", "output_variance", "current_limited_fraction", "samples_per_period",
           "settle_s", "measure_periods", "harmonic_amplitude", "drift_amplitude", "alpha_mean_deg", "beta_mean_deg",
           "marks"]


def write_csv(rows: list[dict], path) -> None:
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, COLUMNS, extrasaction="ignore")
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in row.items()})


def curves(rows: list[dict]) -> dict:
    """{(curve, output): rows sorted by frequency}."""
    out: dict = {}
    for row in rows:
        out.setdefault((row["curve"], row["output"]), []).append(row)
    return {key: sorted(value, key=lambda r: r["frequency_hz"]) for key, value in out.items()}


GAIN_RANGE_DB = 120.0   # the gain axis spans at most this far below the largest gain; lower points sit on its floor


def read_sea_estimate(path, f_min: float, f_max: float, scale: dict | None = None) -> list:
    """The isolation a sea-state run estimated (`gimbal2axis run` writes <scene>_isolation.csv) as
    overlay curves for plot_bode: (label, frequency, gain, coherence, known) per payload axis, between
    f_min and f_max; `known`: the bins whose gain the run knows to spectra.H1_RANDOM_ERROR (the CSV's
    `<axis>_coherent`; all, from a CSV of an older version without that column). `scale` {axis name: factor} puts a per-axis ratio on the dwell's scale (the dwell divides
    by the carrier's rate about one carrier axis, the sea estimate by its rate about the payload axis)."""
    import pathlib

    path = pathlib.Path(path)
    try:
        data = np.genfromtxt(path, delimiter=",", names=True, skip_header=1)
    except (OSError, ValueError) as exc:
        raise ValueError(f"--sea-estimate {path}: cannot read it ({exc})") from None
    if data.dtype.names is None or "frequency_hz" not in data.dtype.names:
        raise ValueError(f"--sea-estimate {path}: not an isolation CSV of gimbal2axis run (no frequency_hz column)")
    f = np.atleast_1d(data["frequency_hz"])
    keep = (f >= f_min) & (f <= f_max) & (f > 0)
    curves = []
    for axis, output in (("elevation", "los.omega[1]"), ("cross_elevation", "los.omega[3]")):
        if f"{axis}_gain" not in data.dtype.names:
            continue
        factor = (scale or {}).get(axis, 1.0)
        label = f"sea-state run: {output} / carrier rate about payload axis" + (
            f" x {factor:.3g} (dwell's scale)" if factor != 1.0 else "")
        gain = np.atleast_1d(data[f"{axis}_gain"])[keep] * factor
        known = np.ones(gain.shape, bool)
        if f"{axis}_coherent" in data.dtype.names:
            known = np.atleast_1d(data[f"{axis}_coherent"])[keep] == 1
            label += f" ({int((~known).sum())} of {known.size} bins of low coherence dotted)"
        curves.append((label, f[keep], gain, np.atleast_1d(data[f"{axis}_coherence"])[keep], known))
    if not curves:
        raise ValueError(f"--sea-estimate {path}: no elevation_gain or cross_elevation_gain column")
    return curves


def plot_bode(rows: list[dict], path, title: str = "", lines: list | None = None, sea: list | None = None) -> None:
    """Gain (dB), phase (deg, unwrapped along each curve) and coherence against frequency, every point
    marked, each curve with its own marker and line style (coinciding curves stay visible). The phase and
    coherence axes are autoscaled to every value. The gain axis spans at most GAIN_RANGE_DB below the
    largest gain: a lower gain (a load that does not move at all gives -200 dB or less) or a gain of exactly 0
    is drawn on the floor as a downward triangle and counted in the legend; its value is in the CSV.
    `lines` (linear_lines) are drawn as thin continuous lines under the points; the linear model's rows
    among `rows` are then not drawn again as points. `sea` (read_sea_estimate): the isolation estimated
    from a sea-state run, thin grey lines in the gain panel (dotted where its coherence is too low to know
    the gain) and its magnitude-squared coherence in the third."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_g, ax_p, ax_c) = plt.subplots(3, 1, figsize=(9, 10), sharex=True)
    if lines:
        rows = [r for r in rows if r.get("curve") != LINEAR_CURVE]
    floor = _gain_floor(rows, lines or [], sea or [])
    for index, line in enumerate(lines or []):
        _draw_line(ax_g, ax_p, index, line, floor)
    for index, ((curve, output), points) in enumerate(curves(rows).items()):
        _draw_curve((ax_g, ax_p, ax_c), index, f"{curve}: {output}" if curve else output, points, floor)
    for index, overlay in enumerate(sea or []):
        _draw_sea(ax_g, ax_c, index, overlay, floor)
    if sea:
        ax_c.legend(fontsize=7)
    ax_g.set_ylabel("gain [dB]")
    ax_p.set_ylabel("phase [deg] (unwrapped)")
    ax_c.set_ylabel("power fraction at the fundamental")
    ax_c.set_xlabel("frequency [Hz]")
    for ax in (ax_g, ax_p, ax_c):
        ax.grid(True, which="both", alpha=0.3)
    ax_g.legend(fontsize=7)
    ax_g.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _gain_floor(rows: list[dict], lines: list, sea: list) -> float:
    """The gain axis's floor [dB]: the lowest finite gain of the points, lines and sea estimate, at most
    GAIN_RANGE_DB below the highest."""
    finite_gains = [r["gain_db"] for r in rows if math.isfinite(r["gain_db"])]
    for _, _, G, *_ in lines:
        finite_gains += [20 * math.log10(abs(g)) for g in G if g != 0]
    for _, _, gain, *_ in sea:   # the sea's bins set the gain axis too: none is put on a floor it did not need
        finite_gains += [20 * math.log10(g) for g in gain if np.isfinite(g) and g > 0]
    if not finite_gains:
        return -GAIN_RANGE_DB
    return max(min(finite_gains), max(finite_gains) - GAIN_RANGE_DB)


def _draw_line(ax_g, ax_p, index: int, line: tuple, floor: float) -> None:
    """A thin black Bode line of the linear model (linear_lines), its gain only above the floor."""
    label, f, G = line[:3]
    has_phase = line[3] if len(line) > 3 else True
    style = ["-", "--", ":"][index % 3]
    gain = 20 * np.log10(np.maximum(np.abs(G), 1e-300))
    shown = gain >= floor
    ax_g.semilogx(f[shown], gain[shown], style, color="k", lw=0.9,
                  label=label + ("" if has_phase else " (gain only)")
                  + ("" if shown.all() else f" ({(~shown).sum()} points below {floor:.0f} dB not drawn)"))
    if has_phase:
        ax_p.semilogx(f, np.degrees(np.unwrap(np.angle(G))), style, color="k", lw=0.9)


def _draw_curve(axes: tuple, index: int, label: str, points: list[dict], floor: float) -> None:
    """One simulated curve in the three panels: gain (below the floor on it, a downward triangle), phase
    and coherence, each with its own marker and line style; the points that are not a frequency response
    (column marks) filled grey over their hollow marker."""
    ax_g, ax_p, ax_c = axes
    markers, styles = "osD^vP*X", ["-", "--", ":", "-."]
    marker, style = markers[index % len(markers)], styles[index % len(styles)]
    size = max(7 - index, 3)
    f = np.array([r["frequency_hz"] for r in points])
    g = np.array([r["gain_db"] for r in points], float)
    p = np.array([r["phase_deg"] for r in points], float)
    c = np.array([r["coherence"] for r in points], float)
    marked = np.array([bool(r.get("marks")) for r in points])
    low = ~(np.isfinite(g) & (g >= floor))
    if low.any():
        label += f" ({low.sum()} below {floor:.0f} dB: on the floor)"
    if marked.any():
        label += f" ({marked.sum()} of {len(points)} not a frequency response: grey)"
    shown_g = np.where(low, floor, g)
    line, = ax_g.semilogx(f, shown_g, style, marker=marker, ms=size, mfc="none", label=label)
    if low.any():
        ax_g.semilogx(f[low], np.full(low.sum(), floor), "v", color=line.get_color(), ms=9)
    kw = dict(color=line.get_color(), linestyle=style, marker=marker, ms=size, mfc="none")
    grey = dict(linestyle="none", marker=marker, ms=size, color="0.55", mfc="0.75", zorder=3)
    ax_g.semilogx(f[marked], shown_g[marked], **grey)
    finite = np.isfinite(p)
    if finite.any():
        unwrapped = np.degrees(np.unwrap(np.radians(p[finite])))
        ax_p.semilogx(f[finite], unwrapped, **kw)
        ax_p.semilogx(f[finite][marked[finite]], unwrapped[marked[finite]], **grey)
    ax_c.semilogx(f, c, **kw)
    ax_c.semilogx(f[marked], c[marked], **grey)


def _draw_sea(ax_g, ax_c, index: int, overlay: tuple, floor: float) -> None:
    """A sea-state run's isolation estimate (read_sea_estimate): thin grey lines of its gain, dotted where
    the run does not know it (low coherence), and its coherence."""
    label, f, gain, coherence, known = overlay
    color = ["0.45", "0.7"][index % 2]
    with np.errstate(divide="ignore"):
        db = 20 * np.log10(gain)
    low = ~(np.isfinite(db) & (db >= floor))
    shown = np.where(low, floor, db)
    ax_g.semilogx(f, shown, ":", color=color, lw=0.6)
    ax_g.semilogx(f, np.where(known, shown, np.nan), "-", marker=".", ms=4, color=color, lw=0.9,
                  label=label + (f" ({low.sum()} bins below {floor:.0f} dB: on the floor)" if low.any() else ""))
    ax_c.semilogx(f, coherence, "-", color=color, lw=0.8, label=f"{label.split(':')[0]}: magnitude-squared coherence")
