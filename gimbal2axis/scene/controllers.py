"""Digital controllers of the master: none (constant voltages), PID per axis, state feedback, and
the user's own (type "python": a class of the user's, see UserController).

A controller is called once per communication step with the measured signals at t_k and returns
the voltages (u_R1, u_R2) computed from them; the master applies them later (one-sample delay,
its zero-order hold). Axis 1 is the azimuth (alpha, motor 1), axis 2 the elevation (beta, motor 2).

Angle references: per axis from references.py, or `reference = "target"` in [controller]: both
set points by inverse kinematics of the line-of-sight target for the measured base attitude.

Rate signals: the payload gyro los.omega (frame 2) gives the inertial rate about the elevation
axis, w[1], and the cross-elevation rate w[3]; w[3] / cos(beta) is the azimuth rate that moves
the line of sight (secant correction). On a fixed base these equal beta_dot and alpha_dot.

The built-in controllers' arithmetic is the C kernel's (c_kernel/src/controllers.c), one
implementation for the Python loop (through ctypes, here) and the compiled loop: each object keeps
its state in the kernel's struct (`state`), which the compiled loop copies.
"""
from __future__ import annotations

import ctypes
import importlib.util
import inspect
import math
import numbers
import pathlib
import sys
from math import isfinite

import numpy as np

from . import geometry
from .. import native
from ..errors import SceneError, StopSignal, check_keys, did_you_mean, excerpt, number, shown
from .references import Reference
from .setpoints import plan_set_points
from ..target import MovingTarget, pointing

AXES = ("azimuth", "elevation")
PID_KEYS = {"kp", "ki", "kd", "k_gyro", "k_ff", "k_acc", "d_filter_s", "i_limit_V", "reference"}


def gyro_axis_rates(gyro, beta: float):
    """(azimuth, elevation) inertial rates of the line of sight from the payload gyro."""
    return gyro[2] / max(math.cos(beta), 0.2), gyro[0]


class Controller:
    """Base: constant voltages (type 'none'); subclasses close the loop."""
    kind = "none"

    def __init__(self, voltage=(0.0, 0.0), u_limit=(math.inf, math.inf)):
        self.voltage = tuple(voltage)
        self.u_limit = tuple(u_limit)
        self.reference = (math.nan, math.nan)   # last set points, for the record
        self._setup_kernel()

    def _setup_kernel(self) -> None:
        """The kernel's struct of this controller (kind, limits, constant voltages) and the buffers
        a step passes it: measured (alpha, beta, gyro), set point, voltages, reference."""
        kernel = native.kernel()
        self.state = native.struct("GimbalController")()
        self.state.kind = kernel.gimbal_controller_kind(self.kind.encode())
        self.state.voltage[:] = self.voltage
        self.state.u_limit[:] = self.u_limit
        self._buffer = (ctypes.c_double * 13)()
        address, size = ctypes.addressof(self._buffer), ctypes.sizeof(ctypes.c_double)
        self._measured, self._set_point, self._u, self._reference = (address + i * size for i in (0, 5, 9, 11))

    def _step(self, step: int, h: float, alpha: float, beta: float, gyro, set_point=None) -> tuple:
        """The kernel's controller at communication point `step`; set_point (r1, r2, r1_dot, r2_dot),
        or None for the prepared set points of that step."""
        buffer = self._buffer
        buffer[0], buffer[1], buffer[2:5] = alpha, beta, gyro
        if set_point is not None:
            buffer[5:9] = set_point
        native.kernel().gimbal_controller_step(ctypes.addressof(self.state), step, h, self._measured,
                                               None if set_point is None else self._set_point, self._u,
                                               self._reference)
        return buffer[9], buffer[10]

    @property
    def asked(self) -> tuple:
        """The last step's voltages before the clamp to +-u_limit (the kernel's)."""
        asked = self.state.asked
        return asked[0], asked[1]

    def start(self, step_size: float, scene_name: str) -> None:
        """Called by the master before every run (the built-in controllers need nothing)."""

    def prepare(self, times, h: float, attitude, rates, accelerations=None) -> None:
        """Called by the master before the loop with the measured base attitude and rates of the
        whole run ((n + 1) x 3 arrays), and the base's angular accelerations (for a moving target's
        set points; None: zero): the built-in controllers compute their set points here."""

    def __call__(self, t: float, h: float, alpha: float, beta: float, gyro, base_attitude, base_rates,
                 step: int | None = None) -> tuple:
        return self._step(step or 0, h, alpha, beta, gyro)

    def clamp(self, u: float, axis: int) -> float:
        limit = self.u_limit[axis]
        return min(max(u, -limit), limit)


class _ReferenceMixin:
    set_points = None   # SetPoints of the run, once prepared

    def prepare(self, times, h, attitude, rates, accelerations=None) -> None:
        points = self.set_points = plan_set_points(self.refs, self.target, times, h, attitude, rates, accelerations)
        kernel_points = self.state.set_points
        kernel_points.values, kernel_points.rates = points.values.ctypes.data, points.rates.ctypes.data
        kernel_points.unwrap[:] = points.unwrap
        # a moving target's (None: NULL, the kernel's fixed-target arithmetic)
        kernel_points.accelerations, kernel_points.gyro_rates = (None if a is None else a.ctypes.data
                                                                 for a in (points.accelerations, points.gyro_rates))

    def _step_with_references(self, t, h, alpha, beta, gyro, base_attitude, base_rates, step) -> tuple:
        """The kernel's step with the prepared set points of `step`, or, called outside a run (no
        step, or not prepared), with set points computed here from the references."""
        if step is None or self.set_points is None:
            set_point = self._references(t, alpha, base_attitude, base_rates, h)
            u = self._step(step or 0, h, alpha, beta, gyro, set_point)
        else:
            u = self._step(step, h, alpha, beta, gyro)
        self.reference = (self._buffer[11], self._buffer[12])
        return u

    @staticmethod
    def state_nearest_turn(principal: float, measured: float) -> float:
        """The kernel's choice of the azimuth's 2 pi branch (gimbal_angle_nearest_turn)."""
        return native.kernel().gimbal_angle_nearest_turn(principal, measured)

    def _setup_references(self, spec: dict, target):
        self.target = target
        self.refs = []
        for axis in AXES:
            sub = spec.get(axis, {}).get("reference", spec.get("reference"))
            if sub == "target":
                if target is None:
                    raise SceneError(f"[controller.{axis}] reference 'target' needs a [target] table")
                self.refs.append("target")
            elif isinstance(sub, dict):
                self.refs.append(Reference(f"controller.{axis}.reference", sub))
            else:
                raise SceneError(f"[controller.{axis}] needs a reference: 'target' or a table "
                                 f"{{type = 'constant'|'step'|'ramp'|'sine', ...}}, got {shown(sub)}")

    def _references(self, t, alpha, base_attitude, base_rates=None, h=None):
        """Set points (r1, r2) and, with base_rates and h, their rates: for 'target' the exact
        derivative of the inverse kinematics along the measured base rates, else a difference
        quotient of the reference over one step."""
        if "target" in self.refs and isinstance(self.target, MovingTarget):
            command = pointing(self.target, [t], [base_attitude], [base_rates if base_rates is not None else (0, 0, 0)])
            a_t = self.state_nearest_turn(float(command.alpha[0]), alpha)
            b_t = float(command.beta[0])
            target_rates = (float(command.alpha_dot[0]), float(command.beta_dot[0]))
        elif "target" in self.refs:
            a_t, b_t = geometry.gimbal_angles_for(self.target, *base_attitude, alpha_near=alpha)
        r1 = a_t if self.refs[0] == "target" else self.refs[0].at(t)
        r2 = b_t if self.refs[1] == "target" else self.refs[1].at(t)
        if h is None:
            return r1, r2
        if "target" in self.refs and not isinstance(self.target, MovingTarget):
            eps = 1e-6
            ahead = [q + eps * w for q, w in zip(base_attitude, base_rates)]
            a_e, b_e = geometry.gimbal_angles_for(self.target, *ahead, alpha_near=a_t)
            target_rates = ((a_e - a_t) / eps, (b_e - b_t) / eps)
        rates = [target_rates[i] if ref == "target" else (ref.at(t + h) - r) / h
                 for i, (ref, r) in enumerate(zip(self.refs, (r1, r2)))]
        return r1, r2, rates[0], rates[1]


class AxisPID:
    """The gains of one axis of the PID (the kernel's GimbalAxisPid computes it, with its state):
    u = kp e + ki int(e) + kd de/dt - k_gyro w + k_ff r_dot, e = reference - encoder angle, de/dt a
    backward difference through a first-order filter (time constant d_filter_s), w the gyro rate
    about the axis, r_dot the rate of the reference relative to the base (feed-forward: k_ff = N k_emf
    cancels the motor's back-emf). Toward a moving target (gimbal2axis/target) w is the gyro rate's
    departure from the line of sight's rate on track, and + k_acc r_ddot feeds the reference's
    acceleration forward [V s2/rad]: R J / (N k_torque) gives the torque of the reflected inertia J.
    Anti-windup: the integral stops while the output is saturated in the direction of e,
    and ki*int(e) is kept within +-i_limit_V."""

    def __init__(self, where: str, spec: dict, u_limit: float):
        check_keys(where, spec, PID_KEYS)
        self.kp, self.ki, self.kd, self.k_gyro, self.k_ff, self.k_acc = (
            number(f"{where}.{k}", spec.get(k, 0.0)) for k in ("kp", "ki", "kd", "k_gyro", "k_ff", "k_acc"))
        self.tau = number(f"{where}.d_filter_s", spec.get("d_filter_s", 0.0))
        self.i_limit = number(f"{where}.i_limit_V", spec["i_limit_V"]) if "i_limit_V" in spec else u_limit
        self.u_limit = u_limit

    def to_kernel(self, axis) -> None:
        """Writes the gains into the kernel's GimbalAxisPid `axis` (its state starts at rest)."""
        axis.kp, axis.ki, axis.kd, axis.k_gyro, axis.k_ff = self.kp, self.ki, self.kd, self.k_gyro, self.k_ff
        axis.d_filter_s, axis.i_limit, axis.u_limit = self.tau, self.i_limit, self.u_limit
        axis.k_acc = self.k_acc


class PID(_ReferenceMixin, Controller):
    kind = "pid"

    def __init__(self, spec: dict, target, u_limit):
        super().__init__(u_limit=u_limit)
        self.axes = [AxisPID(f"controller.{axis}", spec.get(axis, {}), u_limit[i]) for i, axis in enumerate(AXES)]
        for axis, kernel_axis in zip(self.axes, self.state.axis):
            axis.to_kernel(kernel_axis)
        self._setup_references(spec, target)

    def __call__(self, t, h, alpha, beta, gyro, base_attitude, base_rates, step=None):
        return self._step_with_references(t, h, alpha, beta, gyro, base_attitude, base_rates, step)


class StateFeedback(_ReferenceMixin, Controller):
    """u = -K x + ki * int(reference - angle), x = [alpha - alpha_ref, beta - beta_ref, w_az, w_el],
    K a 2x4 matrix [V/rad, V s/rad]; rates from the gyro (rate_source = "gyro") or from backward
    differences of the encoder angles ("encoder"). Computed by the kernel (GimbalController)."""
    kind = "state_feedback"

    def __init__(self, spec: dict, target, u_limit):
        super().__init__(u_limit=u_limit)
        self._setup_references(spec, target)
        K = spec.get("K")
        if not (isinstance(K, list) and len(K) == 2 and all(isinstance(r, list) and len(r) == 4 for r in K)):
            raise SceneError("[controller] state_feedback needs K = [[4 numbers], [4 numbers]] "
                             "(rows u_R1, u_R2; columns alpha error, beta error, azimuth rate, elevation rate)")
        self.K = [[number("controller.K", v) for v in row] for row in K]
        ki = spec.get("ki", [0.0, 0.0])
        self.ki = [number("controller.ki", v) for v in ki]
        self.rate_source = spec.get("rate_source", "gyro")
        if self.rate_source not in ("gyro", "encoder"):
            raise SceneError("[controller] rate_source must be 'gyro' or 'encoder'")
        self.state.gain[:] = self.K[0] + self.K[1]
        self.state.state_ki[:] = self.ki
        self.state.rate_from_encoder = self.rate_source == "encoder"

    def __call__(self, t, h, alpha, beta, gyro, base_attitude, base_rates, step=None):
        return self._step_with_references(t, h, alpha, beta, gyro, base_attitude, base_rates, step)


class Replay(Controller):
    """Voltages given in advance, one row per communication point ((n + 1) x 2): replays a run's
    commands, for measuring what the FMU alone costs (gimbal2axis bench)."""
    kind = "replay"

    def __init__(self, voltages, u_limit=(math.inf, math.inf)):
        super().__init__(u_limit=u_limit)
        self.voltages = np.ascontiguousarray(voltages, dtype=float)
        self.state.replayed = self.voltages.ctypes.data


# The measurements a user controller's step() gets, in this order (Measurements' attributes): name,
# unit, shape (a single run; a batch class gets a leading axis of N cases), and what the values are.
# The one definition: Measurements' slots, docs/controller_api.md (scripts/controller_api_page.py).
MEASUREMENT_FIELDS = (
    ("alpha", "rad", "()", "azimuth encoder angle: the yoke (body 1, motor 1) about the azimuth axis z0"),
    ("beta", "rad", "()", "elevation encoder angle: the payload (body 2, motor 2) about the elevation axis x1"),
    ("gyro", "rad/s", "(3,)", "(w1, w2, w3): the payload's inertial angular velocity in frame 2 from its gyro "
                              "(los.omega): w1 about the elevation axis, w2 about the line of sight, w3 the "
                              "cross-elevation rate (about z2); "
                              "gyro_axis_rates turns them into the rates that move the line of sight"),
    ("base_attitude", "rad", "(3,)", "(delta, psi, gamma): the carrier's attitude from its IMU, in this order "
                                     "pitch (delta, about x_G), yaw (psi, about the pitched z), roll (gamma, about "
                                     "y0): not roll, pitch, yaw (docs/physics.md, section 2); zeros on a fixed "
                                     "base"),
    ("base_rates", "rad/s", "(3,)", "(delta_dot, psi_dot, gamma_dot): the rates of base_attitude, same order"),
)

# What reset(context) is told about the run (ControllerContext's attributes): name, unit, meaning.
CONTEXT_FIELDS = (
    ("step_size", "s", "the communication step h: step() is called at t_k = k h"),
    ("u_limit", "V", "(U_L1, U_L2): the motors' voltage limits; the master clamps step()'s voltages to +-U_L "
                     "(counted, and recorded as u_R1_asked / u_R1_cmd). For a motor in current drive "
                     "(motor<j>.drive = current) step() returns its current command [A] instead, and its "
                     "limit here is motor<j>.i_L [A] (recorded as i_R1_asked / i_R1_ctrl)"),
    ("target", "-", "the line-of-sight target, a unit vector in frame G, or None when the scene has no [target]"),
    ("delay_steps", "-", "steps between a voltage's computation and its application (1: computed at t_k, "
                         "applied over [t_k+1, t_k+2])"),
    ("scene_name", "-", "the scene's name (its file name without .toml)"),
    ("cases", "-", "how many cases step() gets at once: 1 in a single run; N for a batch class in lockstep, "
                   "where u_limit is a pair of (N,) arrays and target an (N, 3) array if they differ between "
                   "the cases"),
)


class Measurements:
    """What the controller sees at t_k, after the sensor models (MEASUREMENT_FIELDS: names, units,
    shapes, order)."""
    __slots__ = tuple(name for name, *_ in MEASUREMENT_FIELDS)

    def __init__(self, alpha, beta, gyro, base_attitude, base_rates):
        self.alpha, self.beta = alpha, beta
        self.gyro, self.base_attitude, self.base_rates = gyro, base_attitude, base_rates


class ControllerContext:
    """What a user controller's reset() is told about the run (CONTEXT_FIELDS)."""
    __slots__ = tuple(name for name, *_ in CONTEXT_FIELDS)

    def __init__(self, step_size, u_limit, target, delay_steps, scene_name, cases=1):
        self.step_size, self.u_limit, self.target = step_size, tuple(u_limit), target
        self.delay_steps, self.scene_name, self.cases = delay_steps, scene_name, cases


class ControllerError(SceneError):
    """A user controller that raised or returned what is not two voltages: the run's failure is
    the controller's, not the FMU's. The message is one line naming the class, the user's file
    and line; `details` holds the Python traceback (gimbal2axis run --traceback prints it)."""

    def __init__(self, message: str, details: str | None = None):
        super().__init__(message)
        self.details = details


def user_exception(label: str, call: str, exc: BaseException, path: pathlib.Path | None,
                   t: float | None = None) -> ControllerError:
    """The ControllerError of an exception raised in the user's `call` ("step()", "reset()", ...)
    at time t: its class and message, and where in the user's file it was raised."""
    import traceback

    text = exception_text(exc)
    when = "" if t is None else f" at t = {t:.6g} s"
    message = (f"{label}: {call} raised {excerpt(type(exc).__name__)}{': ' + text if text else ''}{when}"
               f"{raised_where(exc, path)}")
    # the traceback from the user's code on: its first frame is the call here, the runner's own
    tb = exc.__traceback__.tb_next if exc.__traceback__ is not None and exc.__traceback__.tb_next else exc.__traceback__
    return ControllerError(message, "".join(traceback.format_exception(type(exc), exc, tb)))


def exception_text(exc: BaseException) -> str:
    """The user's exception message as an excerpt (one line, cut: a megabyte of text is not quoted
    whole); what went wrong when its __str__ itself raises."""
    try:
        return excerpt(str(exc))
    except Exception as failure:
        return f"(its message: str() raised {type(failure).__name__})"


def raised_where(exc: BaseException, path: pathlib.Path | None) -> str:
    """" (<file>:<line>, in <function>)" of the innermost frame of exc's traceback in the user's
    file `path` (the user's line that failed, also when a library it called raised), else of the
    innermost frame; "" without a traceback."""
    import traceback

    frames = traceback.extract_tb(exc.__traceback__)
    resolved = path.resolve() if path is not None else None
    mine = [f for f in frames if resolved is not None and pathlib.Path(f.filename).resolve() == resolved]
    if mine:   # the file as the scene names it
        return f" ({path}:{mine[-1].lineno}, in {mine[-1].name})"
    return f" ({frames[-1].filename}:{frames[-1].lineno}, in {frames[-1].name})" if frames else ""


def _fits_float(value: int) -> bool:
    try:
        float(value)
        return True
    except OverflowError:
        return False


def _is_real(value) -> bool:
    """A real number: int, float or numpy's, not bool (True is not a voltage), str or None."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def scalar_voltages(label: str, t: float, u) -> tuple[float, float]:
    """The voltages a (scalar) user controller's step() returned: exactly two finite real numbers,
    as a tuple, a list or an array of shape (2,); anything else is refused, naming the class, the
    time and what was returned. (Called every step: the common case, two floats, checks fastest.)"""
    kind = type(u)
    if (kind is tuple or kind is list) and len(u) == 2:
        u1, u2 = u
    elif kind is np.ndarray and u.shape == (2,) and u.dtype.kind in "fiu":
        u1, u2 = u.tolist()
    else:
        what = f"an array of shape {u.shape}" if isinstance(u, np.ndarray) else shown(u)
        raise ControllerError(f"{label}: step() at t = {t:.6g} s returned {what}; it must return (u_R1, u_R2), "
                              "two finite numbers in V")
    if not (type(u1) is float or _is_real(u1)) or not (type(u2) is float or _is_real(u2)):
        raise ControllerError(f"{label}: step() at t = {t:.6g} s returned {shown(u)}; the voltages must be numbers "
                              "(not strings, booleans or None)")
    u1, u2 = _as_float(label, t, "step() returned voltages", u1), _as_float(label, t, "step() returned voltages", u2)
    if not (isfinite(u1) and isfinite(u2)):
        raise ControllerError(f"{label}: step() at t = {t:.6g} s returned ({u1}, {u2}): the voltages must be finite")
    return u1, u2


def _as_float(label: str, t: float, what: str, value) -> float:
    """float(value) of a real number the user's code gave; a ControllerError naming it when it is
    beyond a float's range (an int such as 10**400)."""
    try:
        return float(value)
    except OverflowError:
        raise ControllerError(f"{label}: {what.replace('()', f'() at t = {t:.6g} s', 1)} {shown(value)}, a number "
                              "beyond a float's range (about 1.8e308)") from None


def user_reference(label: str, t: float, reference) -> tuple[float, float]:
    """A scalar controller's `self.reference` as two floats for the record: a pair of real numbers
    (NaN: none); anything else is refused, naming the class, the time and the value."""
    if isinstance(reference, (tuple, list, np.ndarray)) and len(reference) == 2 and all(
            _is_real(r) or (type(r) is np.ndarray and r.shape == () and r.dtype.kind in "fiu") for r in reference):
        pair = tuple(_as_float(label, t, "step() set self.reference to", r) for r in reference)
        if not (math.isinf(pair[0]) or math.isinf(pair[1])):
            return pair
    raise ControllerError(f"{label}: step() at t = {t:.6g} s set self.reference to {shown(reference)}; it must be "
                          "(alpha_ref, beta_ref), two finite numbers in rad (or NaN for none)")


def batch_voltages(label: str, t: float, u, cases: int):
    """The voltages a batch class's step() returned, as an (N, 2) float array: an array of shape
    (N, 2), or a tuple/list (u_R1, u_R2) of two arrays of shape (N,) (or scalars, for all cases), of
    real numbers (not strings, booleans or None). Anything else is refused (ControllerError) with a
    message naming the class, the time and what was returned. Finiteness is the caller's, per case."""
    if type(u) is np.ndarray and u.shape == (cases, 2) and u.dtype == np.float64:
        return u
    what = None
    try:
        if isinstance(u, (tuple, list)) and len(u) == 2:
            try:   # the common case first: two (N,) arrays
                pair = np.array(u)
                if pair.shape == (2, cases) and pair.dtype.kind in "fiu":
                    return pair.T.astype(float)
            except ValueError:
                pass
            columns = [np.asarray(c) for c in u]
            if all(c.shape in ((), (cases,)) and c.dtype.kind in "fiu" for c in columns):
                return np.column_stack([np.broadcast_to(c.astype(float), (cases,)) for c in columns])
            what = "(" + ", ".join(f"shape {c.shape} of {c.dtype.name}" for c in columns) + ")"
        else:
            array = np.asarray(u)
            if array.shape == (cases, 2) and array.dtype.kind in "fiu":
                return array.astype(float)
            what = f"shape {array.shape} of {array.dtype.name}"
            if array.dtype == object and any(isinstance(x, int) and not _fits_float(x) for x in array.flat):
                what += " (an integer beyond a float's range, about 1.8e308)"
    except (TypeError, ValueError, OverflowError):
        pass
    raise ControllerError(f"{label}: step() at t = {t:.6g} s returned {what or shown(u)}; a batch controller (batch = True) "
                          f"must return the voltages as numbers, an array of shape ({cases}, 2) or (u_R1, u_R2), "
                          f"two arrays of shape ({cases},)")


def batch_reference(label: str, user, cases: int, t: float | None = None):
    """A batch class's `reference` as an (N, 2) float array (NaN if it sets none): a pair
    (alpha_ref, beta_ref) of (N,) arrays or scalars; `t` the step's time, for the message."""
    reference = getattr(user, "reference", None)
    if reference is None:
        return np.full((cases, 2), math.nan)
    try:
        pair = np.array(reference, dtype=float)
        if pair.shape == (2, cases):
            return pair.T
        if pair.shape == (2,):
            return np.broadcast_to(pair, (cases, 2))
    except (ValueError, TypeError, OverflowError):   # an array and a number: below
        pass
    try:
        first, second = reference
        return np.column_stack([np.broadcast_to(np.asarray(c, dtype=float), (cases,)) for c in (first, second)])
    except (TypeError, ValueError, OverflowError):
        when = "" if t is None else f" (set by step() at t = {t:.6g} s)"
        raise ControllerError(f"{label}: self.reference{when} must be (alpha_ref, beta_ref), two arrays of shape "
                              f"({cases},) or numbers; got {shown(reference)}") from None


class UserController(Controller):
    """A controller written by the user, named in a scene:

        [controller]
        type = "python"
        file = "my_controller.py"       # a Python file, relative to the scene file (or `module =`)
        class = "MyController"          # a class defined in that file
        options = { kp = 40.0 }         # keyword arguments of the class

    The file is code that runs with the user's rights: only a .py file the scene names is loaded,
    never an importable module, and the class is checked (defined in that file, with callable
    reset and step) before it is built. The class needs two methods:
        reset(self, context)            # before every run (a ControllerContext)
        step(self, t, measurements)     # at every communication point t_k -> (u_R1, u_R2) [V]
    and may set `self.reference = (alpha_ref, beta_ref)` for the record. The master applies the
    voltages with the scene's delay and saturates them at +-U_L like a DAC (`asked`: the voltages
    before that clamp, recorded as u_R1_asked, u_R2_asked). Two values that are not finite real
    numbers, or an exception in the user's code, stop the run with a ControllerError naming the
    class, the file and the line.

    A class with the class attribute `batch = True` is written for N cases at once (arrays; a
    sweep runs its cases in lockstep, gimbal2axis/master/lockstep.py). In a single run like this one it is
    built with the options as given, and step() gets arrays of one case: alpha, beta of shape (1,),
    gyro, base_attitude, base_rates of shape (1, 3); it returns (1, 2) voltages (batch_voltages)."""
    kind = "python"
    asked = (math.nan, math.nan)   # Controller's property, here the instance's own (set by __call__)

    def __init__(self, spec: dict, target, u_limit, base_dir: pathlib.Path | None):
        super().__init__(u_limit=u_limit)
        self.target = target
        cls, self.path = load_user_class(spec, base_dir)
        self.label = class_label(cls, self.path)
        options = spec.get("options", {})
        if not isinstance(options, dict):
            raise SceneError("[controller] options must be a table of keyword arguments")
        self.user = build_user(cls, self.label, self.path, options)
        self.delay_steps = int(spec.get("delay_steps", 1))
        self.batch = getattr(cls, "batch", False) is True

    def _setup_kernel(self) -> None:
        """None: the user's class computes the voltages, in Python."""

    def start(self, step_size: float, scene_name: str) -> None:
        context = ControllerContext(step_size, self.u_limit, self.target, self.delay_steps, scene_name)
        try:
            self.user.reset(context)
        except StopSignal:
            raise
        except BaseException as exc:   # sys.exit, a KeyboardInterrupt of its own: the code's failure
            raise user_exception(self.label, "reset()", exc, self.path, 0.0) from None

    def __call__(self, t, h, alpha, beta, gyro, base_attitude, base_rates, step=None):
        if self.batch:
            u1, u2 = self._call_batch_of_one(t, alpha, beta, gyro, base_attitude, base_rates)
        else:
            try:
                u = self.user.step(t, Measurements(alpha, beta, gyro, base_attitude, base_rates))
            except StopSignal:
                raise
            except BaseException as exc:
                raise user_exception(self.label, "step()", exc, self.path, t) from None
            u1, u2 = scalar_voltages(self.label, t, u)
            try:   # a property of the user's: its code too
                reference = getattr(self.user, "reference", (math.nan, math.nan))
            except StopSignal:
                raise
            except BaseException as exc:
                raise user_exception(self.label, "reference", exc, self.path, t) from None
            self.reference = user_reference(self.label, t, reference)
        self.asked = (u1, u2)
        return self.clamp(u1, 0), self.clamp(u2, 1)

    def _call_batch_of_one(self, t, alpha, beta, gyro, base_attitude, base_rates):
        m = Measurements(np.array([alpha]), np.array([beta]), np.array([gyro], dtype=float),
                         np.array([base_attitude], dtype=float), np.array([base_rates], dtype=float))
        try:
            u = self.user.step(t, m)
        except StopSignal:
            raise
        except BaseException as exc:   # sys.exit, a KeyboardInterrupt of its own: the code's failure
            raise user_exception(self.label, "step()", exc, self.path, t) from None
        u1, u2 = batch_voltages(self.label, t, u, 1)[0].tolist()
        if not (math.isfinite(u1) and math.isfinite(u2)):
            raise ControllerError(f"{self.label}: step() at t = {t:.6g} s returned ({u1}, {u2}): the voltages must be "
                                  "finite")
        self.reference = tuple(batch_reference(self.label, self.user, 1, t)[0].tolist())
        return u1, u2


def class_label(cls, path: pathlib.Path) -> str:
    """How messages name a user controller class: the class and the user's file."""
    return f"{excerpt(cls.__qualname__)} ({path})"


def build_user(cls, label: str, path: pathlib.Path, options: dict):
    """The user's object, cls(**options); an exception in its __init__ is the controller's."""
    try:
        return cls(**options)
    except StopSignal:
        raise
    except BaseException as exc:
        if isinstance(exc, TypeError) and exc.__traceback__ is not None and exc.__traceback__.tb_next is None:
            # raised by the call itself, not inside __init__: the options do not fit its signature
            raise SceneError(f"[controller] {label}: the options ({excerpt(', '.join(map(str, options))) or 'none'}) "
                             f"do not fit its __init__: {exception_text(exc)}") from None
        raise user_exception(label, "__init__()", exc, path) from None


def controller_file(spec: dict, base_dir: pathlib.Path | None) -> pathlib.Path:
    """The user controller's file a [controller] table names (`file =`, or `module =` of older
    scenes): a .py file, relative to the scene's folder (base_dir) unless absolute. Anything else,
    an importable module name included, is refused before anything is loaded."""
    if "file" in spec and "module" in spec:
        raise SceneError("[controller] has both file and module: give the controller's .py file once, as file = ...")
    key = "file" if "file" in spec else "module"
    name = spec.get(key)
    if not isinstance(name, str) or not isinstance(spec.get("class"), str):
        raise SceneError("[controller] type = 'python' needs file = '<controller file>.py' (relative to the scene) "
                         "and class = '<name of a class defined in it>'")
    path = pathlib.Path(name)
    if path.suffix != ".py":
        raise SceneError(f"[controller] {key} = {shown(name)} is not a .py file: a user controller is a Python file, "
                         "given as a path relative to the scene (file = \"my_controller.py\"); modules are not "
                         "imported")
    if base_dir is not None and not path.is_absolute():
        path = base_dir / path
    if not path.is_file():
        raise SceneError(f"[controller] {key} = {shown(name)}: controller file {path} not found (a path relative to the "
                         "scene file)")
    return path


def load_user_class(spec: dict, base_dir: pathlib.Path | None):
    """(class, file) of a user controller: the file (controller_file) is run as a module of its own
    and the class taken from it, refused unless it is a class defined in that file (not imported
    into it) with callable reset and step. Nothing of the class runs here."""
    path = controller_file(spec, base_dir)
    class_name = spec["class"]
    module_name = f"gimbal_user_controller_{abs(hash(str(path.resolve())))}"
    module = sys.modules.get(module_name)
    if module is None:
        loader_spec = importlib.util.spec_from_file_location(module_name, path)
        module = importlib.util.module_from_spec(loader_spec)
        try:
            loader_spec.loader.exec_module(module)
        except StopSignal:
            raise
        except BaseException as exc:  # the user's file failed to load (or called sys.exit): say where
            raise user_exception(f"[controller] {path}", "loading", exc, path) from None
        sys.modules[module_name] = module
    cls = vars(module).get(class_name)
    if cls is None:
        defined = sorted(name for name, value in vars(module).items()
                         if inspect.isclass(value) and value.__module__ == module_name)
        raise SceneError(f"[controller] {path} has no class '{class_name}' (classes defined there: "
                         f"{', '.join(defined) or 'none'})")
    if not inspect.isclass(cls):
        raise SceneError(f"[controller] '{class_name}' in {path} is a {type(cls).__name__}, not a class")
    if cls.__module__ != module_name:
        raise SceneError(f"[controller] class '{class_name}' is imported into {path} (from {cls.__module__}), not "
                         "defined there: a controller class must be defined in the scene's controller file")
    for method in ("reset", "step"):
        if not callable(getattr(cls, method, None)):
            raise SceneError(f"[controller] {class_label(cls, path)} has no method {method}(); a controller class "
                             "needs reset(context) and step(t, measurements)")
    return cls, path


CONTROLLER_KEYS = {"type", "delay_steps", "reference", "voltage_V", "K", "ki", "rate_source", "file", "module",
                   "class", "options"} | set(AXES)


def make_controller(spec: dict | None, target, u_limit, base_dir: pathlib.Path | None = None) -> Controller:
    """Builds the controller of a scene's [controller] table; `target` a unit vector in G, a moving
    target (gimbal2axis.target.MovingTarget: the built-in controllers' set points follow it) or None,
    `u_limit` the motors' voltage limits (the controller output saturates there, like a DAC),
    `base_dir` where a user controller's module file is looked for first (the scene's folder)."""
    spec = dict(spec or {"type": "none"})
    check_keys("controller", spec, CONTROLLER_KEYS)
    kind = spec.get("type", "none")
    if kind == "none":
        check_keys("controller", spec, {"type", "delay_steps", "voltage_V"})
        v = spec.get("voltage_V", [0.0, 0.0])
        if not (isinstance(v, list) and len(v) == 2):
            raise SceneError("[controller] voltage_V must be [u_R1, u_R2]")
        return Controller([number("controller.voltage_V", x) for x in v], u_limit)
    if kind == "pid":
        check_keys("controller", spec, {"type", "delay_steps", "reference"} | set(AXES))
        return PID(spec, target, u_limit)
    if kind == "state_feedback":
        check_keys("controller", spec, {"type", "delay_steps", "reference", "K", "ki", "rate_source"} | set(AXES))
        for axis in AXES:
            check_keys(f"controller.{axis}", spec.get(axis, {}), {"reference"})
        return StateFeedback(spec, target, u_limit)
    if kind == "python":
        check_keys("controller", spec, {"type", "delay_steps", "file", "module", "class", "options"})
        # a user controller's context.target is a fixed direction or None (docs/targets.md: a moving target
        # is not passed to user controllers yet; the record still measures the error to it)
        return UserController(spec, None if isinstance(target, MovingTarget) else target, u_limit, base_dir)
    raise SceneError(f"[controller] type must be 'none', 'pid', 'state_feedback' or 'python', got {shown(kind)}"
                     f"{did_you_mean(kind, ('none', 'pid', 'state_feedback', 'python'))}")
