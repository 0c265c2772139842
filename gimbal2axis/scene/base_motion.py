"""Prescribed motion of the carrier (body 0): fixed, sinusoids, sea-state spectrum, recorded CSV.

Every generator returns, for an array of times, the 15 base inputs of the FMU in the order of
INPUTS: attitude (pitch delta, yaw psi, roll gamma), their rates and accelerations, the velocity
v_a and acceleration a_a of point a in G. Analytic motions give exact derivatives, so the values
the master sets at each step start are kinematically consistent (the FMU extrapolates them inside
the step with constant acceleration). Translations: the bow points along y (roll gamma turns about
y_0, pitch delta about x), so surge = y_G, sway = x_G, heave = z_G (for a zero mean yaw).
"""
from __future__ import annotations

import ctypes
import math
import pathlib
import weakref

import numpy as np

from .. import native
from ..limits import MAX_RECORDING_BYTES, MAX_SEA_STATE_COMPONENTS, TooLarge, over_limit, read_bounded
from ..errors import (SceneError, check_keys as _check_keys, choice, integer, non_negative, number, positive as _positive,
                      shown, within)

INPUTS = ["base.delta", "base.psi", "base.gamma",
          "base.delta_dot", "base.psi_dot", "base.gamma_dot",
          "base.delta_ddot", "base.psi_ddot", "base.gamma_ddot",
          "base.v_a[1]", "base.v_a[2]", "base.v_a[3]",
          "base.a_a[1]", "base.a_a[2]", "base.a_a[3]"]

# scene axis name -> (index of the angle / translation, is an angle)
ANGLE_AXES = {"pitch": 0, "yaw": 1, "roll": 2}           # delta, psi, gamma
TRANSLATION_AXES = {"sway": 0, "surge": 1, "heave": 2}   # x_G, y_G, z_G: the bow along y, as roll is about y
MOTION_KINDS = ("fixed", "sinusoids", "sea_state", "recorded")
SEA_STATE_DEFAULTS = {"components": 100, "seed": 1}    # of a [base_motion] sea state that does not say
DEFAULT_GAMMA = 3.3                                     # JONSWAP's mean peak enhancement
# The range of each number of a sea state's or a sinusoid's table, both ends included: beyond them
# the motion is no carrier's (a wave of 1e-300 s has no finite spectrum, a heave of 1e6 m no
# finite acceleration), so a value outside is refused by its key.
KEY_RANGES = {"significant_amplitude_deg": (0.0, 180.0), "significant_amplitude_m": (0.0, 1000.0),
              "peak_period_s": (1e-3, 1e6), "gamma": (1.0, 100.0),
              "amplitude_deg": (-360.0, 360.0), "amplitude_m": (-1000.0, 1000.0), "period_s": (1e-3, 1e6),
              "frequency_hz": (1e-6, 1e3), "phase_deg": (-360.0, 360.0), "offset_deg": (-360.0, 360.0),
              "velocity_m_s": (-1e4, 1e4)}


class BaseMotion:
    """Base class: `fixed` means every base input stays 0 (the runner then never sets them)."""
    fixed = False
    kind = "?"

    def sample(self, t: np.ndarray) -> np.ndarray:
        """(len(t), 15) array of base inputs in INPUTS order."""
        raise NotImplementedError

    def position(self, t: np.ndarray) -> np.ndarray:
        """(len(t), 3) position of point a in G relative to its start (for plots); zeros if unknown."""
        return np.zeros((len(t), 3))

    # Rows first .. first + count - 1 of the run's grid t_k = k h (k = 0 .. n): the same bits as
    # sample(np.arange(n + 1) * h)[first:first + count], for a run made chunk by chunk
    # (master/streaming.py).
    def sample_rows(self, first: int, count: int, h: float) -> np.ndarray:
        return self.sample(np.arange(first, first + count) * h)

    def position_rows(self, first: int, count: int, h: float) -> np.ndarray:
        """position's rows of the grid, relative to t = 0 as position(whole grid) is."""
        return self.position(np.arange(first, first + count) * h)


class FixedBase(BaseMotion):
    fixed = True
    kind = "fixed"

    def sample(self, t):
        return np.zeros((len(np.atleast_1d(t)), 15))


class _SumOfSines(BaseMotion):
    """q(t) = offset + sum_i A_i sin(w_i t + phi_i) per axis, plus a constant velocity of point a."""

    def __init__(self, angle_terms: dict, translation_terms: dict, offsets: dict, velocity=(0.0, 0.0, 0.0)):
        # terms: axis index -> (A, w, phi) arrays
        self.angle_terms, self.translation_terms = angle_terms, translation_terms
        self.offsets = offsets        # angle axis index -> offset [rad]
        self.velocity = np.asarray(velocity, dtype=float)

    # A uniform time grid is the C kernel's (c_kernel/src/sum_of_sines.c: blockwise, its bits
    # independent of threads and of how many rows are asked for); other times (a single instant,
    # an irregular grid) are evaluated directly here, sin and cos of every entry.
    _CHUNK_ROWS = 8192   # bounds the memory of the direct evaluation's (rows x components) arrays

    @classmethod
    def _eval(cls, terms, t):
        """sum_i A_i sin(w_i t + phi_i) and its first two time derivatives, at the times t."""
        kernel = native.kernel()
        amplitude, omega, phase = (np.ascontiguousarray(x, dtype=float) for x in terms)
        count = len(omega)
        weights = np.empty(3 * count)
        kernel.gimbal_sum_of_sines_weights(count, amplitude.ctypes.data, omega.ctypes.data, weights.ctypes.data)
        n = len(t)
        step = t[1] - t[0] if n > 1 else 0.0
        # Every uniform grid, however short: a row's value then depends only on its index and the step
        # (blocks start at fixed multiples), so a shortened run gives the same bits as the full one.
        if n > 1 and step > 0 and np.array_equal(t, t[0] + np.arange(n) * step):
            results = [np.empty(n) for _ in range(3)]
            if kernel.gimbal_sum_of_sines(n, float(t[0]), float(step), count, omega.ctypes.data, phase.ctypes.data,
                                          weights.ctypes.data, *(r.ctypes.data for r in results)) != 0:
                raise MemoryError("the sum of sinusoids' rotation table")
            return tuple(results)
        weights = weights.reshape(3, count)
        results = [np.empty(n) for _ in range(3)]
        for first in range(0, n, cls._CHUNK_ROWS):
            rows = slice(first, min(first + cls._CHUNK_ROWS, n))
            arg = np.outer(t[rows], omega) + phase
            s, c = np.sin(arg), np.cos(arg)
            # Not `s @ amplitude`: a BLAS matrix-vector product sums in an order that depends on its
            # thread count (Dask workers run BLAS single-threaded), so a case would give other bits on a
            # worker than in a serial sweep. einsum's own loop sums the same way everywhere.
            results[0][rows] = np.einsum("ij,j->i", s, weights[0])
            results[1][rows] = np.einsum("ij,j->i", c, weights[1])
            results[2][rows] = np.einsum("ij,j->i", s, weights[2])
        return tuple(results)

    def sample(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.zeros((len(t), 15))
        for axis in range(3):
            out[:, axis] = self.offsets.get(axis, 0.0)
        for axis, terms in self.angle_terms.items():
            q, qd, qdd = self._eval(terms, t)
            out[:, axis] += q
            out[:, 3 + axis] = qd
            out[:, 6 + axis] = qdd
        out[:, 9:12] = self.velocity
        for axis, terms in self.translation_terms.items():
            _, v, a = self._eval(terms, t)
            out[:, 9 + axis] += v
            out[:, 12 + axis] = a
        return out

    def position(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        pos = np.outer(t, self.velocity)
        for axis, terms in self.translation_terms.items():
            q, _, _ = self._eval(terms, t)
            q0, _, _ = self._eval(terms, np.zeros(1))
            pos[:, axis] += q - q0
        return pos

    @classmethod
    def _eval_rows(cls, terms, first: int, count: int, h: float):
        """_eval's values on the grid t_k = k h for rows first .. first + count - 1: the kernel's rows
        of the same grid (blocks at the same multiples of rows), so the same bits as _eval of the
        whole grid."""
        kernel = native.kernel()
        kernel.gimbal_sum_of_sines_rows.argtypes = [ctypes.c_long, ctypes.c_long, ctypes.c_double, ctypes.c_double,
                                                    ctypes.c_long] + [ctypes.c_void_p] * 7
        kernel.gimbal_sum_of_sines_rows.restype = None
        kernel.gimbal_sum_of_sines_rotation.argtypes = [ctypes.c_double, ctypes.c_long, ctypes.c_void_p,
                                                        ctypes.c_void_p]
        kernel.gimbal_sum_of_sines_rotation.restype = None
        kernel.gimbal_sum_of_sines_rotation_doubles.argtypes = [ctypes.c_long]
        kernel.gimbal_sum_of_sines_rotation_doubles.restype = ctypes.c_long
        amplitude, omega, phase = (np.ascontiguousarray(x, dtype=float) for x in terms)
        components = len(omega)
        weights = np.empty(3 * components)
        kernel.gimbal_sum_of_sines_weights(components, amplitude.ctypes.data, omega.ctypes.data, weights.ctypes.data)
        rotation = np.empty(kernel.gimbal_sum_of_sines_rotation_doubles(components))
        kernel.gimbal_sum_of_sines_rotation(h, components, omega.ctypes.data, rotation.ctypes.data)
        results = [np.empty(count) for _ in range(3)]   # element 0: row `first`
        kernel.gimbal_sum_of_sines_rows(first, count, 0.0, h, components, omega.ctypes.data, phase.ctypes.data,
                                        weights.ctypes.data, rotation.ctypes.data, *(r.ctypes.data for r in results))
        return tuple(results)

    def sample_rows(self, first, count, h):
        if first == 0 and count < 2:   # _eval takes a single instant directly, not by the kernel's grid
            return self.sample(np.arange(first, first + count) * h)
        out = np.zeros((count, 15))
        for axis in range(3):
            out[:, axis] = self.offsets.get(axis, 0.0)
        for axis, terms in self.angle_terms.items():
            q, qd, qdd = self._eval_rows(terms, first, count, h)
            out[:, axis] += q
            out[:, 3 + axis] = qd
            out[:, 6 + axis] = qdd
        out[:, 9:12] = self.velocity
        for axis, terms in self.translation_terms.items():
            _, v, a = self._eval_rows(terms, first, count, h)
            out[:, 9 + axis] += v
            out[:, 12 + axis] = a
        return out

    def position_rows(self, first, count, h):
        if first == 0 and count < 2:
            return self.position(np.arange(first, first + count) * h)
        pos = np.outer(np.arange(first, first + count) * h, self.velocity)
        for axis, terms in self.translation_terms.items():
            q, _, _ = self._eval_rows(terms, first, count, h)
            q0, _, _ = self._eval(terms, np.zeros(1))
            pos[:, axis] += q - q0
        return pos


class Sinusoids(_SumOfSines):
    kind = "sinusoids"


class SeaState(_SumOfSines):
    kind = "sea_state"


def seed_words(*integers: int) -> np.ndarray:
    """The entropy of numpy's default_rng([seed, index]) as the uint32 words numpy makes of it: each
    integer (>= 0) as its base-2**32 digits, least significant first (0 as one word 0), concatenated."""
    words = []
    for seed in integers:
        if seed < 0:
            raise ValueError(f"a seed must be >= 0, not {seed}")
        digits = [0] if seed == 0 else []
        while seed > 0:
            digits.append(seed & 0xFFFFFFFF)
            seed >>= 32
        words.extend(digits)
    return np.array(words, dtype=np.uint32)


_SEA_STATE_REFUSALS = {1: "significant amplitude must be finite and >= 0", 2: "peak period must be finite and > 0",
                       3: "gamma must be finite and >= 1", 4: "components must be >= 1",
                       5: "band must satisfy 0 < band[0] < band[1]"}


def sea_state_components(significant_amplitude: float, peak_period: float, gamma: float, components: int,
                         seed: int, index: int, band=(0.5, 3.0)):
    """Amplitudes, frequencies and phases of a sum of sinusoids whose one-sided spectrum has the
    JONSWAP shape (gamma = 1: Pierson-Moskowitz) and whose variance is (significant_amplitude / 2)**2
    (significant amplitude = mean of the highest third of the amplitudes = 2 sigma for a narrow-band
    Gaussian process). Frequencies: one per equal bin of [band[0], band[1]] * omega_peak, at a random
    place in its bin (so the sum does not repeat); phases uniform; both drawn from numpy's
    default_rng([seed, index]) sequence. Computed by the C kernel (c_kernel/src/sea_state.c), which the
    ship-motion FMU shares: the same parameters give the same bits in both."""
    kernel = native.kernel()
    entropy = seed_words(seed, index)
    amplitude, omega, phase = (np.empty(components) for _ in range(3))
    status = kernel.gimbal_sea_state_components(entropy.ctypes.data, len(entropy), float(significant_amplitude),
                                                float(peak_period), float(gamma), components, float(band[0]),
                                                float(band[1]), amplitude.ctypes.data, omega.ctypes.data,
                                                phase.ctypes.data)
    if status != 0:
        raise ValueError(f"sea state: {_SEA_STATE_REFUSALS.get(status, f'refused ({status})')}")
    return amplitude, omega, phase


class Recorded(BaseMotion):
    """A recorded motion: a comma-separated file with a header row of names (`#` starts a comment).
    Column `time` [s] and any of: delta, psi, gamma [rad] (or pitch_deg, yaw_deg, roll_deg), their
    `_dot` and `_ddot` [rad/s, rad/s2], x, y, z [m] of point a in G. Missing derivatives come from a
    C2 cubic spline through the samples (not-a-knot ends, as scipy's CubicSpline), so attitude, rates
    and accelerations stay consistent; absent quantities are 0. The C kernel reads, checks and splines
    the file (c_kernel/src/recorded_motion.c: anything else is refused with the file, line and column), the
    one the ship-motion FMU reads a recording with, so both give the same bits."""
    kind = "recorded"

    def __init__(self, path: pathlib.Path):
        self.path = path
        try:
            self._text = read_bounded(path, MAX_RECORDING_BYTES, "a recorded motion")
        except OSError as exc:
            raise SceneError(f"base_motion: recorded motion {path}: cannot read it: {exc.strerror}") from None
        except TooLarge as exc:
            raise SceneError(f"base_motion: recorded motion {exc}") from None
        self._open()

    def _open(self) -> None:
        kernel = native.kernel()
        handle = ctypes.c_void_p()
        message = ctypes.create_string_buffer(1024)
        status = kernel.gimbal_recorded_motion_read(self._text, len(self._text), ctypes.byref(handle), message,
                                                    len(message))
        reason = message.value.decode("utf-8", "replace")
        if status == _RECORDING_BAD_TABLE:
            raise SceneError(f"base_motion: recorded motion {self.path}: {reason}")
        if status == _RECORDING_BAD_COLUMNS:
            raise SceneError(f"base_motion: {self.path}: {reason}")
        if status != 0:
            raise MemoryError(f"base_motion: recorded motion {self.path}: {reason}")
        self._handle = handle.value
        weakref.finalize(self, kernel.gimbal_recorded_motion_free, self._handle)
        self.t_start = kernel.gimbal_recorded_motion_start(self._handle)
        self.t_end = kernel.gimbal_recorded_motion_end(self._handle)

    # A scene (and its motion) goes to sweep workers by pickle: the file's bytes go, the kernel's
    # splines are made again from them.
    def __getstate__(self):
        return {"path": self.path, "_text": self._text}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._open()

    def sample(self, t):
        t = np.ascontiguousarray(np.atleast_1d(np.asarray(t, dtype=float)))
        out = np.empty((len(t), 15))
        native.kernel().gimbal_recorded_motion_sample(self._handle, len(t), t.ctypes.data, out.ctypes.data)
        return out

    def position(self, t):
        t = np.ascontiguousarray(np.atleast_1d(np.asarray(t, dtype=float)))
        pos = np.empty((len(t), 3))
        native.kernel().gimbal_recorded_motion_position(self._handle, len(t), t.ctypes.data, pos.ctypes.data)
        return pos - pos[:1]

    def position_rows(self, first, count, h):
        start = np.zeros(1)
        at_start = np.empty((1, 3))
        native.kernel().gimbal_recorded_motion_position(self._handle, 1, start.ctypes.data, at_start.ctypes.data)
        t = np.ascontiguousarray(np.arange(first, first + count) * h)
        pos = np.empty((count, 3))
        native.kernel().gimbal_recorded_motion_position(self._handle, count, t.ctypes.data, pos.ctypes.data)
        return pos - at_start


# What native.gimbal_recorded_motion_read says of a file (recorded_motion.h): its text or its columns refused.
_RECORDING_BAD_TABLE, _RECORDING_BAD_COLUMNS = 1, 2


def _within(where: str, key: str, value) -> float:
    """The finite number `value` of `where`.`key` within KEY_RANGES[key]."""
    return within(f"{where}.{key}", value, *KEY_RANGES[key])


def _sine_terms(axis: str, spec, angle: bool):
    """One table or a list of tables {amplitude_deg | amplitude_m, period_s | frequency_hz, phase_deg}."""
    specs = spec if isinstance(spec, list) else [spec]
    over_limit(f"base_motion.{axis}: the number of sinusoids", len(specs), MAX_SEA_STATE_COMPONENTS)
    amplitude, omega, phase = [], [], []
    unit = "amplitude_deg" if angle else "amplitude_m"
    for item in specs:
        if not isinstance(item, dict):
            raise SceneError(f"base_motion.{axis}: expected a table or a list of tables, got {shown(item)}")
        _check_keys(f"base_motion.{axis}", item, {unit, "period_s", "frequency_hz", "phase_deg"} | (
            {"offset_deg"} if angle else set()))
        if unit not in item:
            raise SceneError(f"base_motion.{axis}: missing '{unit}'")
        if ("period_s" in item) == ("frequency_hz" in item):
            raise SceneError(f"base_motion.{axis}: give exactly one of 'period_s' and 'frequency_hz'")
        where = f"base_motion.{axis}"
        f = 1.0 / _within(where, "period_s", item["period_s"]) if "period_s" in item else \
            _within(where, "frequency_hz", item["frequency_hz"])
        a = _within(where, unit, item[unit])
        amplitude.append(math.radians(a) if angle else a)
        omega.append(2.0 * math.pi * f)
        phase.append(math.radians(_within(where, "phase_deg", item.get("phase_deg", 0.0))))
    offset = sum(math.radians(_within(f"base_motion.{axis}", "offset_deg", item.get("offset_deg", 0.0)))
                 for item in specs) if angle else 0.0
    return (np.array(amplitude), np.array(omega), np.array(phase)), offset


def _velocity(spec: dict) -> tuple:
    v = spec.get("velocity_m_s", [0.0, 0.0, 0.0])
    if not (isinstance(v, list) and len(v) == 3):
        raise SceneError(f"base_motion.velocity_m_s must be a list of 3 numbers (constant velocity of point a in G), "
                         f"got {shown(v)}")
    velocity = tuple(number(f"base_motion.velocity_m_s[{i}]", x) for i, x in enumerate(v))
    low, high = KEY_RANGES["velocity_m_s"]
    for i, x in enumerate(velocity):
        if not low <= x <= high:
            raise SceneError(f"base_motion.velocity_m_s[{i}] = {x:g} is outside [{low:g}, {high:g}]")
    return velocity


def _components(where: str, value) -> int:
    """A sea state's sinusoids per degree of freedom: the kernel allocates and sums that many per step."""
    components = integer(where, value, 1)
    over_limit(where, components, MAX_SEA_STATE_COMPONENTS, " sinusoids")
    return components


def make_base_motion(spec: dict | None, scene_dir: pathlib.Path) -> BaseMotion:
    """Builds the base motion of a scene's [base_motion] table (absent = fixed base)."""
    spec = dict(spec or {"type": "fixed"})
    kind = choice("base_motion.type", spec.get("type", "fixed"), MOTION_KINDS)
    axes = set(ANGLE_AXES) | set(TRANSLATION_AXES)
    if kind == "fixed":
        _check_keys("base_motion", spec, {"type"})
        return FixedBase()
    if kind == "sinusoids":
        _check_keys("base_motion", spec, {"type", "velocity_m_s"} | axes)
        angle_terms, translation_terms, offsets = {}, {}, {}
        for name, axis in ANGLE_AXES.items():
            if name in spec:
                angle_terms[axis], offsets[axis] = _sine_terms(name, spec[name], True)
        for name, axis in TRANSLATION_AXES.items():
            if name in spec:
                translation_terms[axis], _ = _sine_terms(name, spec[name], False)
        return Sinusoids(angle_terms, translation_terms, offsets, _velocity(spec))
    if kind == "sea_state":
        _check_keys("base_motion", spec, {"type", "velocity_m_s", "components", "seed"} | axes)
        components = _components("base_motion.components", spec.get("components", SEA_STATE_DEFAULTS["components"]))
        seed = integer("base_motion.seed", spec.get("seed", SEA_STATE_DEFAULTS["seed"]), 0)
        angle_terms, translation_terms, offsets = {}, {}, {}
        for index, name in enumerate(["pitch", "yaw", "roll", "surge", "sway", "heave"]):
            if name not in spec:
                continue
            item = spec[name]
            angle = name in ANGLE_AXES
            unit = "significant_amplitude_deg" if angle else "significant_amplitude_m"
            if not isinstance(item, dict):
                raise SceneError(f"base_motion.{name}: expected a table, got {shown(item)}")
            _check_keys(f"base_motion.{name}", item, {unit, "peak_period_s", "gamma", "components"})
            for key in (unit, "peak_period_s"):
                if key not in item:
                    raise SceneError(f"base_motion.{name}: missing '{key}'")
            # every value the kernel would refuse (sea_state_components), refused here by its key, and
            # every value out of KEY_RANGES (where the spectrum is no longer finite)
            amplitude = non_negative(f"base_motion.{name}.{unit}", item[unit])
            gamma = number(f"base_motion.{name}.gamma", item.get("gamma", DEFAULT_GAMMA))
            if gamma < 1.0:
                raise SceneError(f"base_motion.{name}.gamma = {gamma:g} (JONSWAP peak enhancement) must be >= 1 "
                                 "(1 = Pierson-Moskowitz)")
            amplitude, gamma = _within(f"base_motion.{name}", unit, amplitude), _within(f"base_motion.{name}", "gamma",
                                                                                       gamma)
            peak_period = _within(f"base_motion.{name}", "peak_period_s",
                                  _positive(f"base_motion.{name}.peak_period_s", item["peak_period_s"]))
            terms = sea_state_components(math.radians(amplitude) if angle else amplitude, peak_period,
                                         gamma, _components(f"base_motion.{name}.components",
                                                            item.get("components", components)), seed, index)
            if angle:
                angle_terms[ANGLE_AXES[name]] = terms
            else:
                translation_terms[TRANSLATION_AXES[name]] = terms
        return SeaState(angle_terms, translation_terms, offsets, _velocity(spec))
    # kind == "recorded"
    _check_keys("base_motion", spec, {"type", "file"})
    if "file" not in spec:
        raise SceneError("base_motion: type 'recorded' needs 'file' (a CSV path relative to the scene file)")
    if not isinstance(spec["file"], str) or not spec["file"]:
        raise SceneError(f"base_motion.file must be a path (a string), got {shown(spec['file'])}")
    return Recorded((scene_dir / spec["file"]).resolve())
