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

The built-in controllers' arithmetic is the C kernel's (gimbal2axis/native/controllers.c), one
implementation for the Python loop (through ctypes, here) and the compiled loop: each object keeps
its state in the kernel's struct (`state`), which the compiled loop copies.
"""
from __future__ import annotations

import ctypes
import importlib
import importlib.util
import inspect
import math
import pathlib
import sys

from . import geometry
from .. import native
from ..errors import SceneError, check_keys, number
from .references import Reference
from .setpoints import plan_set_points

AXES = ("azimuth", "elevation")
PID_KEYS = {"kp", "ki", "kd", "k_gyro", "k_ff", "d_filter_s", "i_limit_V", "reference"}


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

    def start(self, step_size: float, scene_name: str) -> None:
        """Called by the master before every run (the built-in controllers need nothing)."""

    def prepare(self, times, h: float, attitude, rates) -> None:
        """Called by the master before the loop with the measured base attitude and rates of the
        whole run ((n + 1) x 3 arrays): the built-in controllers compute their set points here."""

    def __call__(self, t: float, h: float, alpha: float, beta: float, gyro, base_attitude, base_rates,
                 step: int | None = None) -> tuple:
        return self._step(step or 0, h, alpha, beta, gyro)

    def clamp(self, u: float, axis: int) -> float:
        limit = self.u_limit[axis]
        return min(max(u, -limit), limit)


class _ReferenceMixin:
    set_points = None   # SetPoints of the run, once prepared

    def prepare(self, times, h, attitude, rates) -> None:
        points = self.set_points = plan_set_points(self.refs, self.target, times, h, attitude, rates)
        kernel_points = self.state.set_points
        kernel_points.values, kernel_points.rates = points.values.ctypes.data, points.rates.ctypes.data
        kernel_points.unwrap[:] = points.unwrap

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
                                 f"{{type = 'constant'|'step'|'ramp'|'sine', ...}}, got {sub!r}")

    def _references(self, t, alpha, base_attitude, base_rates=None, h=None):
        """Set points (r1, r2) and, with base_rates and h, their rates: for 'target' the exact
        derivative of the inverse kinematics along the measured base rates, else a difference
        quotient of the reference over one step."""
        if "target" in self.refs:
            a_t, b_t = geometry.gimbal_angles_for(self.target, *base_attitude, alpha_near=alpha)
        r1 = a_t if self.refs[0] == "target" else self.refs[0].at(t)
        r2 = b_t if self.refs[1] == "target" else self.refs[1].at(t)
        if h is None:
            return r1, r2
        if "target" in self.refs:
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
    cancels the motor's back-emf). Anti-windup: the integral stops while the output is saturated in the direction of e,
    and ki*int(e) is kept within +-i_limit_V."""

    def __init__(self, where: str, spec: dict, u_limit: float):
        check_keys(where, spec, PID_KEYS)
        self.kp, self.ki, self.kd, self.k_gyro, self.k_ff = (number(f"{where}.{k}", spec.get(k, 0.0))
                                                             for k in ("kp", "ki", "kd", "k_gyro", "k_ff"))
        self.tau = number(f"{where}.d_filter_s", spec.get("d_filter_s", 0.0))
        self.i_limit = number(f"{where}.i_limit_V", spec["i_limit_V"]) if "i_limit_V" in spec else u_limit
        self.u_limit = u_limit

    def to_kernel(self, axis) -> None:
        """Writes the gains into the kernel's GimbalAxisPid `axis` (its state starts at rest)."""
        axis.kp, axis.ki, axis.kd, axis.k_gyro, axis.k_ff = self.kp, self.ki, self.kd, self.k_gyro, self.k_ff
        axis.d_filter_s, axis.i_limit, axis.u_limit = self.tau, self.i_limit, self.u_limit


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
        import numpy as np

        super().__init__(u_limit=u_limit)
        self.voltages = np.ascontiguousarray(voltages, dtype=float)
        self.state.replayed = self.voltages.ctypes.data


class Measurements:
    """What the controller sees at t_k, after the sensor models: the encoder angles alpha, beta
    [rad]; gyro = (w1, w2, w3), the payload's inertial angular velocity in frame 2 [rad/s] (w1 about
    the elevation axis, w3 the cross-elevation rate; gyro_axis_rates turns them into the rates that
    move the line of sight); the carrier attitude (delta, psi, gamma) [rad] and its rates [rad/s]."""
    __slots__ = ("alpha", "beta", "gyro", "base_attitude", "base_rates")

    def __init__(self, alpha, beta, gyro, base_attitude, base_rates):
        self.alpha, self.beta = alpha, beta
        self.gyro, self.base_attitude, self.base_rates = gyro, base_attitude, base_rates


class ControllerContext:
    """What a user controller's reset() is told about the run: the communication step h [s], the
    motors' voltage limits (U_L1, U_L2) [V], the target direction in G (or None), the delay of the
    voltages in steps, the scene's name, and `cases`: how many cases step() gets at once (1 for a
    single run; N for a batch class run in lockstep, where u_limit is a pair of (N,) arrays and the
    target an (N, 3) array if they differ between the cases: see gimbal2axis/master/lockstep.py)."""
    __slots__ = ("step_size", "u_limit", "target", "delay_steps", "scene_name", "cases")

    def __init__(self, step_size, u_limit, target, delay_steps, scene_name, cases=1):
        self.step_size, self.u_limit, self.target = step_size, tuple(u_limit), target
        self.delay_steps, self.scene_name, self.cases = delay_steps, scene_name, cases


def batch_voltages(label: str, t: float, u, cases: int):
    """The voltages a batch class's step() returned, as an (N, 2) float array: an array of shape
    (N, 2), or a tuple/list (u_R1, u_R2) of two arrays of shape (N,) (or scalars, for all cases).
    Anything else is refused with a message naming the class."""
    import numpy as np

    if type(u) is np.ndarray and u.shape == (cases, 2) and u.dtype == np.float64:
        return u
    try:
        if isinstance(u, (tuple, list)) and len(u) == 2:
            try:   # the common case first: two (N,) arrays
                pair = np.array(u, dtype=float)
                if pair.shape == (2, cases):
                    return pair.T
            except ValueError:
                pass
            columns = [np.asarray(c, dtype=float) for c in u]
            if all(c.shape in ((), (cases,)) for c in columns):
                return np.column_stack([np.broadcast_to(c, (cases,)) for c in columns])
            shape = f"({', '.join(str(c.shape) for c in columns)})"
        else:
            array = np.asarray(u, dtype=float)
            if array.shape == (cases, 2):
                return array
            shape = str(array.shape)
    except (TypeError, ValueError):
        shape = repr(u)
    raise SceneError(f"{label}.step(t = {t:.6g}) returned {shape}; a batch controller (batch = True) must return "
                     f"the voltages as an array of shape ({cases}, 2) or as (u_R1, u_R2), two arrays of shape "
                     f"({cases},)")


def batch_reference(label: str, user, cases: int):
    """A batch class's `reference` as an (N, 2) float array (NaN if it sets none): a pair
    (alpha_ref, beta_ref) of (N,) arrays or scalars."""
    import numpy as np

    reference = getattr(user, "reference", None)
    if reference is None:
        return np.full((cases, 2), math.nan)
    try:
        pair = np.array(reference, dtype=float)
        if pair.shape == (2, cases):
            return pair.T
        if pair.shape == (2,):
            return np.broadcast_to(pair, (cases, 2))
    except ValueError:   # an array and a number: below
        pass
    try:
        first, second = reference
        return np.column_stack([np.broadcast_to(np.asarray(c, dtype=float), (cases,)) for c in (first, second)])
    except (TypeError, ValueError):
        raise SceneError(f"{label}.reference must be (alpha_ref, beta_ref), two arrays of shape ({cases},) or "
                         f"numbers; got {reference!r}") from None


class UserController(Controller):
    """A controller written by the user, named in a scene:

        [controller]
        type = "python"
        module = "my_controller.py"     # a file (relative to the scene file) or an importable module
        class = "MyController"
        options = { kp = 40.0 }         # keyword arguments of the class

    The class needs two methods:
        reset(self, context)            # before every run (a ControllerContext)
        step(self, t, measurements)     # at every communication point t_k -> (u_R1, u_R2) [V]
    and may set `self.reference = (alpha_ref, beta_ref)` for the record. The master applies the
    voltages with the scene's delay and saturates them at +-U_L like a DAC; a voltage that is not a
    finite number stops the run with a message naming the class.

    A class with the class attribute `batch = True` is written for N cases at once (arrays; a
    sweep runs its cases in lockstep, gimbal2axis/master/lockstep.py). In a single run like this one it is
    built with the options as given, and step() gets arrays of one case: alpha, beta of shape (1,),
    gyro, base_attitude, base_rates of shape (1, 3); it returns (1, 2) voltages (batch_voltages)."""
    kind = "python"

    def __init__(self, spec: dict, target, u_limit, base_dir: pathlib.Path | None):
        super().__init__(u_limit=u_limit)
        self.target = target
        cls = _load_class(spec, base_dir)
        options = spec.get("options", {})
        if not isinstance(options, dict):
            raise SceneError("[controller] options must be a table of keyword arguments")
        self.label = f"{cls.__module__}.{cls.__qualname__}"
        try:
            self.user = cls(**options)
        except TypeError as exc:
            raise SceneError(f"[controller] {self.label}({', '.join(options)}): {exc}") from None
        for method in ("reset", "step"):
            if not callable(getattr(self.user, method, None)):
                raise SceneError(f"[controller] {self.label} has no method {method}(); a controller class needs "
                                 "reset(context) and step(t, measurements)")
        self.delay_steps = int(spec.get("delay_steps", 1))
        self.batch = getattr(cls, "batch", False) is True

    def _setup_kernel(self) -> None:
        """None: the user's class computes the voltages, in Python."""

    def start(self, step_size: float, scene_name: str) -> None:
        self.user.reset(ControllerContext(step_size, self.u_limit, self.target, self.delay_steps, scene_name))

    def __call__(self, t, h, alpha, beta, gyro, base_attitude, base_rates, step=None):
        if self.batch:
            return self._call_batch_of_one(t, alpha, beta, gyro, base_attitude, base_rates)
        u = self.user.step(t, Measurements(alpha, beta, gyro, base_attitude, base_rates))
        try:
            u1, u2 = float(u[0]), float(u[1])
        except (TypeError, ValueError, IndexError):
            raise SceneError(f"{self.label}.step(t = {t:.6g}) returned {u!r}; it must return (u_R1, u_R2) in V") from None
        if not (math.isfinite(u1) and math.isfinite(u2)):
            raise SceneError(f"{self.label}.step(t = {t:.6g}) returned ({u1}, {u2}): the voltages must be finite")
        self.reference = getattr(self.user, "reference", (math.nan, math.nan))
        return self.clamp(u1, 0), self.clamp(u2, 1)

    def _call_batch_of_one(self, t, alpha, beta, gyro, base_attitude, base_rates):
        import numpy as np

        m = Measurements(np.array([alpha]), np.array([beta]), np.array([gyro], dtype=float),
                         np.array([base_attitude], dtype=float), np.array([base_rates], dtype=float))
        u1, u2 = batch_voltages(self.label, t, self.user.step(t, m), 1)[0].tolist()
        if not (math.isfinite(u1) and math.isfinite(u2)):
            raise SceneError(f"{self.label}.step(t = {t:.6g}) returned ({u1}, {u2}): the voltages must be finite")
        self.reference = tuple(batch_reference(self.label, self.user, 1)[0].tolist())
        return self.clamp(u1, 0), self.clamp(u2, 1)


def _load_class(spec: dict, base_dir: pathlib.Path | None):
    module_name, class_name = spec.get("module"), spec.get("class")
    if not isinstance(module_name, str) or not isinstance(class_name, str):
        raise SceneError("[controller] type = 'python' needs module = '<file.py or module>' and class = '<name>'")
    candidates = [pathlib.Path(module_name)]
    if base_dir is not None and not candidates[0].is_absolute():
        candidates.insert(0, base_dir / module_name)
    path = next((c for c in candidates if c.suffix == ".py" and c.is_file()), None)
    try:
        if path is not None:
            unique = f"gimbal_user_controller_{abs(hash(str(path.resolve())))}"
            module = sys.modules.get(unique)
            if module is None:
                loader_spec = importlib.util.spec_from_file_location(unique, path)
                module = importlib.util.module_from_spec(loader_spec)
                loader_spec.loader.exec_module(module)
                sys.modules[unique] = module
        elif module_name.endswith(".py"):
            raise SceneError(f"[controller] module file '{module_name}' not found (looked in "
                             f"{', '.join(str(c) for c in candidates)})")
        else:
            module = importlib.import_module(module_name)
    except SceneError:
        raise
    except Exception as exc:  # the user's module failed to import: say where
        raise SceneError(f"[controller] importing '{module_name}' failed: {type(exc).__name__}: {exc}") from None
    cls = getattr(module, class_name, None)
    if not inspect.isclass(cls):
        raise SceneError(f"[controller] '{module_name}' has no class '{class_name}'")
    return cls


CONTROLLER_KEYS = {"type", "delay_steps", "reference", "voltage_V", "K", "ki", "rate_source", "module", "class",
                   "options"} | set(AXES)


def make_controller(spec: dict | None, target, u_limit, base_dir: pathlib.Path | None = None) -> Controller:
    """Builds the controller of a scene's [controller] table; `target` a unit vector in G or None,
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
        check_keys("controller", spec, {"type", "delay_steps", "module", "class", "options"})
        return UserController(spec, target, u_limit, base_dir)
    raise SceneError(f"[controller] type must be 'none', 'pid', 'state_feedback' or 'python', got {kind!r}")
