"""The linear prediction of a PID scene's isolation (stabilization) ratio: the line of sight's inertial
rate per carrier rate, against frequency, for a sinusoidal roll, pitch or yaw of the carrier. It is
what the sine dwell of frequency_response.py measures with Excitation("base", axis, ...) when the
motion is small enough for the loop to stay linear (no backlash, no dry friction, no saturation).

Method: the steady-state response of the *sampled-data* closed loop at z = exp(j w h), evaluated per
frequency. It is not the continuous plant G(j w) with hold corrections: the plant is discretized
exactly over one communication step with the inputs the FMU really sees inside a step, so the
prediction holds for the samples at t_k the dwell analyses, up to the linearization itself. (A
continuous-time approximation, aliasing neglected, would be off near the Nyquist frequency by the
hold's aliases; this form has no such neglect.)

  - Plant: linearization.linearize at the scene's operating point, all 17 inputs: where its loop holds
    the gimbal on a level carrier at rest (operating_point: the start_on_target angles, and the steady
    voltages, currents and gear deflections of the gravity torque, from a short run), with the
    fidelity override.
  - Inside a step [t_k, t_k+1] the FMU holds the voltages and extrapolates the carrier from its values
    at t_k with constant acceleration: angle q_k + qd_k s + qdd_k s^2/2, rate qd_k + qdd_k s,
    acceleration qdd_k. So x_k+1 = Phi x_k + M0 B u0 + M1 B u1 + M2 B u2, M_n = int_0^h exp(A (h - s))
    s^n / n! ds (one matrix exponential of a block matrix). The outputs published at t_k are those at
    the end of the previous step, computed with that step's extrapolated inputs (the D term).
  - Carrier angle phasor G on one axis: samples q_k = G z^k, qd_k = j w G z^k, qdd_k = -w^2 G z^k
    (the base motion's exact values at the step starts).
  - Controller: AxisPID's exact transfer functions at z: kp + ki h / (1 - 1/z) (rectangular integral)
    + kd a (1 - 1/z) / h / (1 - (1 - a)/z), a = h / (tau + h) (filtered backward difference); the gyro
    term -k_gyro w with gyro_axis_rates linearized at the operating beta (w_az = w3 / cos(beta0): its
    derivative in beta multiplies w3 = 0 at rest); feed-forward k_ff on the set point's rate. Set
    points from the target ("target"): the Jacobian of geometry.gimbal_angles_for in the carrier
    angles (central differences) times the angle phasor, their rates the same Jacobian times the rate
    phasor (setpoints.py differentiates along the measured rates). Other references do not depend on
    the carrier and contribute nothing at its frequency. Saturation and anti-windup are not modelled.
  - Voltages: u computed at t_k is applied over [t_k+d, t_k+d+1] (d = delay_steps): a factor z^-d.
  - Ideal sensors (no quantization, no noise).

Gains are referred to the carrier RATE sample phasor (j w G), as measure_point does (output
fundamental / fundamental of the sampled base.<axis>_dot); "los" is sqrt(|G1|^2 + |G3|^2), no phase.

The same loop broken at one motor's computed voltage gives the loop gain a voltage injection measures
(Excitation("injection", ...)): loop_gain, injection_sensitivity, injection_response, loop_gain_rows /
loop_gain_lines, and the classical margins of a sampled L (stability_margins, predicted_margins), with the
lower gain margin of a conditionally stable loop.
"""
from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np

from ..errors import SceneError
from .frequency_response import BASE_AXES, LINEAR_CURVE, LOS_OUTPUTS

CARRIER_ANGLE_INDEX = {"pitch": 0, "yaw": 1, "roll": 2}   # delta, psi, gamma
LOOP_OUTPUTS = ["alpha", "beta", "los.omega[1]", "los.omega[3]"]
VOLTAGES = ["u_R1", "u_R2"]
# The motors' commands as the record of a run and the linear model name them: a voltage, or in current drive
# (motor<j>.drive = current, scene/drives.py) the current command.
MOTOR_COMMANDS = VOLTAGES + ["i_R1_cmd", "i_R2_cmd"]


def motor_command_columns(inputs: list[str]) -> list[int]:
    """The columns of the two motors' commands among a linear model's inputs: u_R<j>, or i_R<j>_cmd for a
    motor in current drive."""
    return [inputs.index(f"u_R{j}") if f"u_R{j}" in inputs else inputs.index(f"i_R{j}_cmd") for j in (1, 2)]
JACOBIAN_STEP_RAD = 1e-6
SETTLE_S = 5.0   # s at rest before linearizing: the loop's integrators have taken up the gravity torque
SETTLE_RETRY_FACTOR = 4.0   # a loop not at rest by then gets one run this many times longer


@dataclasses.dataclass(frozen=True)
class AxisGains:
    """The linear part of one AxisPID."""
    kp: float
    ki: float
    kd: float
    k_gyro: float
    k_ff: float
    tau: float

    def error_transfer(self, z: complex, h: float) -> complex:
        """u / e at z: proportional, rectangular integral, filtered backward difference."""
        a = h / (self.tau + h)
        integral = h / (1.0 - 1.0 / z)
        derivative = a * (1.0 - 1.0 / z) / h / (1.0 - (1.0 - a) / z)
        return self.kp + self.ki * integral + self.kd * derivative


@dataclasses.dataclass(frozen=True)
class SampledPlant:
    """The plant over one step: x_k+1 = Phi x_k + sum_n M[n] B u_n (input polynomial coefficients)."""
    Phi: np.ndarray
    MB: tuple          # (M0 B, M1 B, M2 B)
    C: np.ndarray      # rows LOOP_OUTPUTS
    D: np.ndarray
    inputs: list


@dataclasses.dataclass(frozen=True)
class IsolationLoop:
    """Everything the prediction needs, fixed before the frequencies."""
    plant: SampledPlant
    axes: tuple                  # (AxisGains azimuth, AxisGains elevation)
    reference_jacobian: np.ndarray   # 2 x 3: d(alpha_ref, beta_ref) / d(delta, psi, gamma)
    cos_beta: float
    h: float
    delay: int


def pid_gains(scene, fmu) -> tuple:
    """The two AxisPID's gains of the scene's controller; a SceneError for any other controller."""
    from ..scene.controllers import PID
    from ..scene.scene import parameter_value

    u_limit = tuple(float(parameter_value(scene, fmu, f"motor{j}.U_L")) for j in (1, 2))
    controller = scene.controller(u_limit)
    if not isinstance(controller, PID):
        raise SceneError(f"{scene.name}: the isolation prediction models the PID controller only; this scene's "
                         f"controller is '{controller.kind}'")
    axes = tuple(AxisGains(a.kp, a.ki, a.kd, a.k_gyro, a.k_ff, a.tau) for a in controller.axes)
    return axes, controller.refs


def reference_jacobian(target, references, alpha0: float) -> np.ndarray:
    """d(alpha_ref, beta_ref) / d(delta, psi, gamma) at a level carrier; a zero row for an axis whose
    reference does not come from the target."""
    from ..scene.geometry import gimbal_angles_for

    jacobian = np.zeros((2, 3))
    for j in range(3):
        step = np.zeros(3)
        step[j] = JACOBIAN_STEP_RAD
        ahead = np.array(gimbal_angles_for(target, *step, alpha_near=alpha0))
        behind = np.array(gimbal_angles_for(target, *(-step), alpha_near=alpha0))
        jacobian[:, j] = (ahead - behind) / (2 * JACOBIAN_STEP_RAD)
    for axis, reference in enumerate(references):
        if reference != "target":
            jacobian[axis] = 0.0
    return jacobian


def operating_point(scene, fmu, fidelity: dict | None, settle_s: float = SETTLE_S) -> dict:
    """linearize()'s values: where the scene's own loop holds the gimbal on a level carrier at rest, with
    `fidelity` over the scene's. Found by running the loop for `settle_s` from the scene's start values
    (start_on_target angles): the steady state is not the start state, since the elevation holds its
    gravity torque with a steady current and a deflected gear (about 1 V in the ship scene), and the
    linearization at 0 V misses the coupling that torque adds (1 % in los.omega[3] under roll)."""
    from ..master.master import run
    from ..scene.scene import start_values

    merged = dict(scene.fidelity)
    merged.update(fidelity or {})
    # The prediction's assumptions for the settling run too: ideal sensors (noise and quantization keep a
    # loop from ever resting) and set points held at their start (a ramp is never at rest).
    held = scene.with_changes(sensors_spec={}, controller_spec=frozen_references(scene.controller_spec))
    # a slow but stable loop (a low gyro gain) gets a second, longer run before it is refused
    for attempt, duration in enumerate((settle_s, SETTLE_RETRY_FACTOR * settle_s)):
        at_rest = held.with_changes(stop_time=duration, fidelity=merged, base_motion_spec={"type": "fixed"})
        signals = run(at_rest, fmu).signals
        problems = rest_problems(signals)
        if not problems:
            break
        if attempt == 1:
            raise SceneError(f"{scene.name}: its loop does not come to rest on a carrier at rest within {duration:g} s "
                             f"({', '.join(problems)} at the end): there is no steady operating point to linearize "
                             f"(is the loop unstable with these gains?)")
    values = start_values(at_rest, fmu, np.zeros(15))
    values.update(merged)
    values.update({name: float(signals[name][-1]) for name in fmu.states + MOTOR_COMMANDS if name in signals})
    return values


def frozen_references(spec: dict) -> dict:
    """The controller's spec with each set point given as a table (constant, step, ramp, sine) held at its
    value at t = 0: they do not depend on the carrier, so they add nothing at its frequency, but a
    moving one would keep the loop from resting at an operating point."""
    from ..scene.controllers import AXES
    from ..scene.references import Reference

    frozen = copy.deepcopy(spec)
    for axis in AXES:
        reference = frozen.get(axis, {}).get("reference", frozen.get("reference"))
        if isinstance(reference, dict):
            start = Reference(f"controller.{axis}.reference", reference).at(0.0)
            frozen.setdefault(axis, {})["reference"] = {"type": "constant", "value_deg": math.degrees(start)}
    return frozen


REST_RATE_RAD_S = 1e-4   # gimbal rates below this at the end of the settling run: the loop holds still


def rest_problems(signals: dict) -> list[str]:
    """What shows that a run has not come to rest at its end (unstable, limit-cycling, current-limited):
    such a loop has no steady operating point, and an arbitrary moment of its motion is not one."""
    problems = []
    for rate in ("alpha_dot", "beta_dot"):
        if rate in signals and abs(float(signals[rate][-1])) > REST_RATE_RAD_S:
            problems.append(f"{rate} = {float(signals[rate][-1]):.3g} rad/s")
    for flag in ("motor1.limited", "motor2.limited"):
        if flag in signals and float(signals[flag][-1]) != 0:
            problems.append(f"{flag} = {int(signals[flag][-1])}")
    return problems


def sample_plant(model, h: float) -> SampledPlant:
    """Exact discretization over a step with inputs polynomial (degree 2) in the time s into the step."""
    # Not python-control's c2d: its holds (zoh, foh, tustin, ...) do not include the FMU's in-step
    # carrier extrapolation (angle, rate and acceleration from the step start: a degree-2 polynomial),
    # which is what makes this prediction hold up to the Nyquist frequency.
    from scipy.linalg import expm

    n = len(model.states)
    block = np.zeros((4 * n, 4 * n))
    block[:n, :n] = model.A
    for level in range(3):   # x' = A x + w0, w0' = w1, w1' = w2: the top row gives M0, M1, M2
        block[level * n:(level + 1) * n, (level + 1) * n:(level + 2) * n] = np.eye(n)
    transition = expm(block * h)
    Phi = transition[:n, :n]
    MB = tuple(transition[:n, (level + 1) * n:(level + 2) * n] @ model.B for level in range(3))
    rows = [model.outputs.index(name) for name in LOOP_OUTPUTS]
    return SampledPlant(Phi, MB, model.C[rows], model.D[rows], list(model.inputs))


def build_loop(scene, fmu, fidelity: dict | None) -> IsolationLoop:
    from . import linearization

    axes, references = pid_gains(scene, fmu)
    values = operating_point(scene, fmu, fidelity)
    if values.get("base.fixed"):
        raise SceneError(f"{scene.name}: base.fixed = true: the carrier's motion does not reach the gimbal")
    model = linearization.linearize(values)
    held = [f"{name} = {value}" for name, value in model.modes.items()
            if (name.endswith(".limited") or name.endswith(".voltage_clamped")) and value != 0]
    if held:
        raise SceneError(f"{scene.name}: at its operating point {', '.join(held)}: the voltage does not act, "
                         f"a linear loop does not exist there")
    alpha0, beta0 = float(values.get("alpha", 0.0)), float(values.get("beta", 0.0))
    jacobian = reference_jacobian(scene.target, references, alpha0) if scene.target is not None else np.zeros((2, 3))
    loop = IsolationLoop(plant=sample_plant(model, scene.step_size), axes=axes, reference_jacobian=jacobian,
                         cos_beta=max(math.cos(beta0), 0.2), h=scene.step_size, delay=scene.delay_steps)
    radius = float(np.max(np.abs(closed_loop_poles(loop))))
    if radius >= 1.0:
        decoupled = _decoupled_modes(model.modes, values)
        why = (f"; at the operating point {', '.join(decoupled)}: linearize without backlash and dry friction "
               f"(LINEAR_FIDELITY)" if decoupled else "")
        raise SceneError(f"{scene.name}: the linear closed loop is unstable (a pole at |z| = {radius:.6g} >= 1): "
                         f"it has no steady-state response, hence no isolation ratio{why}")
    return loop


def _decoupled_modes(modes: dict, values: dict) -> list[str]:
    """'name = value' of the modes in which the voltage does not reach the load (in the backlash gap of a
    gear with backlash, stuck by friction): each puts a pole at 1."""
    def decoupled(name, value):
        if name.endswith(".contact"):
            return value == 0 and values.get(f"{name.split('.')[0]}.model", 2) == 2
        return name.endswith(".friction") and value != "none" and not str(value).startswith("slipping")

    return [f"{name} = {value}" for name, value in modes.items() if decoupled(name, value)]


def closed_loop_poles(loop: IsolationLoop) -> np.ndarray:
    """Eigenvalues of the sampled closed loop (plant over a step, the two AxisPID's states, the delay
    line), references at rest: inside the unit circle for a stable loop."""
    return np.linalg.eigvals(closed_loop_transition(loop))


def closed_loop_transition(loop: IsolationLoop) -> np.ndarray:
    """The matrix of xi_k -> xi_k+1 for xi_k = [x_k, v_k-1, u_k-1 .. u_k-d, integral_k-1, filtered
    derivative_k-1, e_k-1]: the same sampling, hold and delay as loop_response, in the time domain (one
    step of the loop applied to each unit vector)."""
    plant, h, d = loop.plant, loop.h, loop.delay
    n = plant.Phi.shape[0]
    voltage_columns = motor_command_columns(plant.inputs)
    hold_input, direct = plant.MB[0][:, voltage_columns], plant.D[:, voltage_columns]
    gains = {key: np.array([getattr(axis, key) for axis in loop.axes]) for key in ("kp", "ki", "kd", "k_gyro")}
    smoothing = np.array([h / (axis.tau + h) for axis in loop.axes])
    size = n + 2 + 2 * d + 6

    def step(xi):
        x, applied_before = xi[:n], xi[n:n + 2]
        pending = xi[n + 2:n + 2 + 2 * d].reshape(d, 2)
        integral, derivative, error_before = np.split(xi[n + 2 + 2 * d:], 3)
        y = plant.C @ x + direct @ applied_before              # alpha, beta, los.omega[1], los.omega[3] at t_k
        error = -y[:2]
        gyro = np.array([y[3] / loop.cos_beta, y[2]])
        derivative = derivative + smoothing * ((error - error_before) / h - derivative)
        integral = integral + error * h
        u = gains["kp"] * error + gains["ki"] * integral + gains["kd"] * derivative - gains["k_gyro"] * gyro
        applied = u if d == 0 else pending[d - 1]
        pending = np.vstack([u[None, :], pending[:d - 1]]) if d else pending
        return np.concatenate([plant.Phi @ x + hold_input @ applied, applied, pending.ravel(), integral,
                               derivative, error])

    return np.column_stack([step(column) for column in np.eye(size)])


def carrier_input_polynomial(inputs: list, axis: str, w: float, h: float):
    """Per unit carrier angle phasor: the coefficients (u0, u1, u2) of the base inputs inside a step
    (u(s) = u0 + u1 s + u2 s^2 / 2) and their values at the step's end."""
    index = CARRIER_ANGLE_INDEX[axis]
    names = ["base.delta", "base.psi", "base.gamma"]
    angle = inputs.index(names[index])
    rate = inputs.index(names[index] + "_dot")
    accel = inputs.index(names[index] + "_ddot")
    jw = 1j * w
    u0, u1, u2 = (np.zeros(len(inputs), complex) for _ in range(3))
    u0[[angle, rate, accel]] = 1.0, jw, jw ** 2
    u1[[angle, rate]] = jw, jw ** 2
    u2[angle] = jw ** 2
    return (u0, u1, u2), u0 + u1 * h + u2 * h * h / 2


def loop_response(loop: IsolationLoop, axis: str, frequency_hz: float) -> np.ndarray:
    """Phasors of LOOP_OUTPUTS at t_k per unit phasor of the carrier angle."""
    plant, h = loop.plant, loop.h
    w = 2 * math.pi * frequency_hz
    z = complex(math.cos(w * h), math.sin(w * h))
    n = plant.Phi.shape[0]
    resolvent = np.linalg.inv(z * np.eye(n) - plant.Phi)
    voltage_path = voltage_transfer(loop, z, resolvent)
    (u0, u1, u2), at_end = carrier_input_polynomial(plant.inputs, axis, w, h)
    carrier_path = plant.C @ resolvent @ sum(MB @ u for MB, u in zip(plant.MB, (u0, u1, u2))) + plant.D @ at_end / z
    feedback, feedforward = controller_matrices(loop, axis, z, w)
    closed = np.eye(len(LOOP_OUTPUTS)) - voltage_path @ feedback
    return np.linalg.solve(closed, voltage_path @ feedforward + carrier_path)


def voltage_transfer(loop: IsolationLoop, z: complex, resolvent: np.ndarray | None = None) -> np.ndarray:
    """Computed voltages -> LOOP_OUTPUTS at t_k: held over a step, applied `delay` steps late; D sees the
    previous step's input."""
    plant = loop.plant
    if resolvent is None:
        resolvent = np.linalg.inv(z * np.eye(plant.Phi.shape[0]) - plant.Phi)
    voltage_columns = motor_command_columns(plant.inputs)
    path = plant.C @ resolvent @ plant.MB[0][:, voltage_columns] + plant.D[:, voltage_columns] / z
    return path * z ** -loop.delay


def controller_matrices(loop: IsolationLoop, axis: str, z: complex, w: float):
    """u = feedback @ y + feedforward * G: y the LOOP_OUTPUTS samples, G the carrier angle phasor."""
    azimuth, elevation = loop.axes
    c_az, c_el = azimuth.error_transfer(z, loop.h), elevation.error_transfer(z, loop.h)
    feedback = feedback_matrix(loop, z)
    sensitivity = loop.reference_jacobian[:, CARRIER_ANGLE_INDEX[axis]]
    feedforward = np.array([(c_az + azimuth.k_ff * 1j * w) * sensitivity[0],
                            (c_el + elevation.k_ff * 1j * w) * sensitivity[1]])
    return feedback, feedforward


def feedback_matrix(loop: IsolationLoop, z: complex) -> np.ndarray:
    """K(z), 2 x 4: the controllers' outputs (u_R1, u_R2 computed at t_k) per LOOP_OUTPUTS samples at t_k
    (references at rest). The PID acts on e = reference - angle and on -k_gyro times gyro_axis_rates
    (w3 / cos beta, w1), linearized at the operating beta."""
    azimuth, elevation = loop.axes
    c_az, c_el = azimuth.error_transfer(z, loop.h), elevation.error_transfer(z, loop.h)
    # rows u_R1, u_R2; columns alpha, beta, los.omega[1], los.omega[3]
    return np.array([[-c_az, 0.0, 0.0, -azimuth.k_gyro / loop.cos_beta],
                     [0.0, -c_el, -elevation.k_gyro, 0.0]], complex)


def isolation_gains(loop: IsolationLoop, axis: str, frequencies) -> dict:
    """{output: complex gains per frequency} for los.omega[1], los.omega[3] (per carrier rate) and
    'los' (the combined magnitude, real)."""
    gains = {name: [] for name in LOS_OUTPUTS}
    for f in np.atleast_1d(np.asarray(frequencies, float)):
        response = loop_response(loop, axis, f) / (2j * math.pi * f)
        for name in LOS_OUTPUTS:
            gains[name].append(complex(response[LOOP_OUTPUTS.index(name)]))
    gains = {name: np.array(values) for name, values in gains.items()}
    gains["los"] = np.sqrt(sum(np.abs(gains[name]) ** 2 for name in LOS_OUTPUTS)).astype(complex)
    return gains


def _check_axis(axis: str) -> None:
    if axis not in CARRIER_ANGLE_INDEX:
        raise SceneError(f"carrier axis must be roll, pitch or yaw, got {axis!r}")


def isolation_rows(loop: IsolationLoop, axis: str, frequencies) -> list[dict]:
    """Rows in frequency_response's CSV format (curve LINEAR_CURVE, coherence 1): los.omega[1],
    los.omega[3] and 'los' (phase NaN) at each frequency (frequency_hz = requested_hz = the given one:
    pass the dwell's snapped frequencies to compare point by point). `loop` from build_loop."""
    _check_axis(axis)
    gains = isolation_gains(loop, axis, frequencies)
    rows = []
    for index, f in enumerate(np.atleast_1d(np.asarray(frequencies, float))):
        for name in LOS_OUTPUTS + ["los"]:
            G = complex(gains[name][index])
            rows.append(dict(curve=LINEAR_CURVE, input=BASE_AXES[axis], output=name, requested_hz=float(f),
                             frequency_hz=float(f), gain=abs(G),
                             gain_db=20 * math.log10(abs(G)) if G != 0 else -math.inf,
                             phase_deg=math.nan if name == "los" else math.degrees(math.atan2(G.imag, G.real)),
                             coherence=1.0))
    return rows


def isolation_lines(loop: IsolationLoop, axis: str, f_min: float, f_max: float, points: int = 400) -> list:
    """Dense lines for plot_bode: [(label, frequencies, G, has_phase), ...]. The 'los' line carries the
    real, positive magnitude and no phase (plot_bode draws its gain only)."""
    _check_axis(axis)
    f = np.logspace(math.log10(f_min), math.log10(f_max), points)
    gains = isolation_gains(loop, axis, f)
    return [(f"{LINEAR_CURVE}: {name}", f, gains[name], name != "los") for name in LOS_OUTPUTS + ["los"]]


# -- the loop gain broken at one motor's computed voltage (voltage injection) -------------------------

MOTOR_AXES = ("1", "2")


def _check_motor_axis(axis: str) -> int:
    if axis not in MOTOR_AXES:
        raise SceneError(f"injection axis must be motor '1' or '2', got {axis!r}")
    return int(axis) - 1


def return_matrix(loop: IsolationLoop, z: complex) -> np.ndarray:
    """G(z) = K(z) P(z), 2 x 2: the controllers' outputs U per computed voltages A (both at t_k), with
    P = voltage_transfer (A -> LOOP_OUTPUTS: hold, delay, plant) and K = feedback_matrix. The loop closed
    on both axes is A = U = G A; with an injection D on axis j, A = G A + e_j D."""
    return feedback_matrix(loop, z) @ voltage_transfer(loop, z)


def loop_gain(loop: IsolationLoop, axis: str, z: complex) -> complex:
    """L_j(z): the loop gain broken at motor `axis`'s computed voltage, the other axis's loop closed.

    With G = K P (return_matrix), j the broken axis and i the other: the other loop closed means
    A_i = U_i = G_ii A_i + G_ij A_j, so A_i = G_ij A_j / (1 - G_ii), and the broken axis's controller
    answers A_j with U_j = G_jj A_j + G_ji A_i. Hence
        L_j = -U_j / A_j = -(G_jj + G_ji G_ij / (1 - G_ii)).
    The sign: the loop is U = -L A, a negative feedback loop of gain L, as the textbook's 1 + L = 0.
    The injection closes A_j = U_j + D: A_j / D = 1 / (1 + L_j) = [(I - G)^-1]_jj (the Schur
    complement of the 2 x 2 return difference; injection_sensitivity computes it that way)."""
    j = _check_motor_axis(axis)
    i = 1 - j
    G = return_matrix(loop, z)
    return complex(-(G[j, j] + G[j, i] * G[i, j] / (1.0 - G[i, i])))


def injection_sensitivity(loop: IsolationLoop, axis: str, z: complex) -> complex:
    """A_j / D with both loops closed: [(I - G)^-1]_jj, computed directly (not through loop_gain)."""
    j = _check_motor_axis(axis)
    G = return_matrix(loop, z)
    return complex(np.linalg.solve(np.eye(2) - G, np.eye(2)[:, j])[j])


def injection_response(loop: IsolationLoop, axis: str, z: complex) -> np.ndarray:
    """LOOP_OUTPUTS samples per injected D on motor `axis`, both loops closed: P (I - G)^-1 e_j."""
    j = _check_motor_axis(axis)
    G = return_matrix(loop, z)
    return voltage_transfer(loop, z) @ np.linalg.solve(np.eye(2) - G, np.eye(2)[:, j])


def loop_gain_gains(loop: IsolationLoop, axis: str, frequencies) -> dict:
    """{output: complex gains per frequency}: 'loop_gain' (L_j), 'sensitivity' (A_j / D) and the LOS rate
    that motor moves (los.omega[3] for 1, los.omega[1] for 2) per D: the rows measure_point gives for
    Excitation('injection', axis, ...)."""
    from .frequency_response import INJECTION_OUTPUTS, LOOP_GAIN, SENSITIVITY

    outputs = INJECTION_OUTPUTS[axis]
    gains = {name: [] for name in [LOOP_GAIN, SENSITIVITY] + outputs}
    for f in np.atleast_1d(np.asarray(frequencies, float)):
        z = _unit_circle(f, loop.h)
        gains[LOOP_GAIN].append(loop_gain(loop, axis, z))
        gains[SENSITIVITY].append(injection_sensitivity(loop, axis, z))
        response = injection_response(loop, axis, z)
        for name in outputs:
            gains[name].append(response[LOOP_OUTPUTS.index(name)])
    return {name: np.array(values, complex) for name, values in gains.items()}


def loop_gain_rows(loop: IsolationLoop, axis: str, frequencies) -> list[dict]:
    """Rows in frequency_response's CSV format (curve LINEAR_CURVE, coherence 1), inputs as measure_point's
    for an injection: loop_gain per u_R<axis>_cmd, the others per injection_R<axis>."""
    from .frequency_response import LOOP_GAIN, command_signal, injection_signal

    gains = loop_gain_gains(loop, axis, frequencies)
    drive = "current" if f"i_R{axis}_cmd" in loop.plant.inputs else "voltage"
    rows = []
    for index, f in enumerate(np.atleast_1d(np.asarray(frequencies, float))):
        for name, values in gains.items():
            G = complex(values[index])
            rows.append(dict(curve=LINEAR_CURVE, output=name, requested_hz=float(f), frequency_hz=float(f),
                             input=command_signal(axis, drive) if name == LOOP_GAIN else injection_signal(axis),
                             gain=abs(G), gain_db=20 * math.log10(abs(G)) if G != 0 else -math.inf,
                             phase_deg=math.degrees(math.atan2(G.imag, G.real)), coherence=1.0))
    return rows


def loop_gain_lines(loop: IsolationLoop, axis: str, f_min: float, f_max: float, points: int = 400) -> list:
    """Dense lines for plot_bode: [(label, frequencies, G), ...] of loop_gain_gains."""
    f = np.logspace(math.log10(f_min), math.log10(f_max), points)
    return [(f"{LINEAR_CURVE}: {name}", f, G) for name, G in loop_gain_gains(loop, axis, f).items()]


@dataclasses.dataclass(frozen=True)
class StabilityMargins:
    """Classical margins of a negative-feedback loop gain L (NaN where there is no such crossing).

    A loop whose plant is open-loop unstable (a top-heavy payload's elevation) is conditionally stable: L
    also passes -180 deg where |L| > 1, and there the gain may not DROP by more than the lower gain margin
    (negative dB) before the loop goes unstable. The stable range of a gain factor k on L is
    10^(lower/20) < k < 10^(upper/20)."""
    crossover_hz: float        # |L| = 1
    phase_margin_deg: float    # 180 deg + the phase of L there, in (-180, 180]
    phase_crossover_hz: float  # phase of L = -180 deg with |L| <= 1, of the upper gain margin
    gain_margin_db: float      # -20 log10 |L| there (>= 0): how much more gain makes the loop marginal
    lower_phase_crossover_hz: float = math.nan   # phase of L = -180 deg with |L| > 1, of the lower gain margin
    lower_gain_margin_db: float = math.nan       # -20 log10 |L| there (< 0): how much less gain makes it marginal

    def describe(self) -> str:
        text = (f"crossover {self.crossover_hz:.4g} Hz, phase margin {self.phase_margin_deg:.3g} deg; "
                f"-180 deg at {self.phase_crossover_hz:.4g} Hz, gain margin {self.gain_margin_db:.3g} dB")
        if math.isfinite(self.lower_gain_margin_db):
            text += (f"; -180 deg at {self.lower_phase_crossover_hz:.4g} Hz, "
                     f"lower gain margin {self.lower_gain_margin_db:.3g} dB")
        return text


def stability_margins(frequencies, L) -> StabilityMargins:
    """Margins of the loop gain L sampled on an increasing, dense `frequencies` grid (Hz).

    Crossings are located between grid points by linear interpolation in log frequency (of log |L| for
    the gain crossover, of the phase of -L for the phase crossover; the phase at the gain crossover is
    interpolated on the unwrapped phase). Of several crossings the worst is reported: the gain crossover
    with the smallest |phase margin|; of the phase crossovers with |L| <= 1 the smallest gain margin in
    dB (the upper margin), of those with |L| > 1 the largest, i.e. nearest 0 dB (the lower margin, of a
    conditionally stable loop; a resonance may cross twice). A -180 deg crossing is one where the phase of
    -L passes 0 (L on the negative real axis), not a jump of the wrapped phase at +-180 deg of -L.

    Not python-control's `stability_margins(frd(L, 2 pi f), returnall=True)`, although it finds the
    same crossings (to 1e-5 on the textbook loops of tests/package/analysis/test_loop_gain.py, control 0.10.2): on the
    40,000-point grids used here it took 3.9 s of CPU per call against 2.8 ms for this one (measured
    2026-11-25), and `predicted_margins` calls it per axis and per scene. Without returnall, python-control
    returns one gain margin, the one nearest 0 dB, which for a conditionally stable loop may be the lower."""
    f = np.asarray(frequencies, float)
    L = np.asarray(L, complex)
    if f.ndim != 1 or f.shape != L.shape or len(f) < 2 or np.any(np.diff(f) <= 0) or np.any(f <= 0):
        raise SceneError("stability_margins needs increasing positive frequencies and one L value each")
    x = np.log(f)
    magnitude = np.log(np.maximum(np.abs(L), 1e-300))
    crossover_hz, phase_margin = _gain_crossover(x, magnitude, np.unwrap(np.angle(L)))
    crossings = _phase_crossovers(x, magnitude, L)
    upper = [(gain_db, hz) for hz, gain_db in crossings if gain_db >= 0.0]
    lower = [(gain_db, hz) for hz, gain_db in crossings if gain_db < 0.0]
    gain_margin, phase_crossover_hz = min(upper) if upper else (math.nan, math.nan)
    lower_margin, lower_hz = max(lower) if lower else (math.nan, math.nan)
    return StabilityMargins(float(crossover_hz), float(phase_margin), float(phase_crossover_hz), float(gain_margin),
                            float(lower_hz), float(lower_margin))


def _gain_crossover(x, magnitude, phase) -> tuple:
    """(frequency, phase margin) of the |L| = 1 crossing with the smallest |phase margin|, or NaNs."""
    crossings = []
    for k in np.flatnonzero(np.sign(magnitude[:-1]) * np.sign(magnitude[1:]) <= 0):
        if magnitude[k] == magnitude[k + 1]:
            continue
        s = magnitude[k] / (magnitude[k] - magnitude[k + 1])
        angle = phase[k] + s * (phase[k + 1] - phase[k])
        margin = (math.degrees(angle) + 180.0 + 180.0) % 360.0 - 180.0   # (-180, 180]: wrapped 180 + phase
        crossings.append((abs(margin), math.exp(x[k] + s * (x[k + 1] - x[k])), margin))
    return min(crossings)[1:] if crossings else (math.nan, math.nan)


def _phase_crossovers(x, magnitude, L) -> list:
    """[(frequency, -20 log10 |L| in dB), ...] of every crossing of L over the negative real axis."""
    negative_phase = np.angle(-L)           # 0 where L is on the negative real axis
    crossings = []
    for k in np.flatnonzero(np.sign(negative_phase[:-1]) * np.sign(negative_phase[1:]) <= 0):
        a, b = negative_phase[k], negative_phase[k + 1]
        if abs(a - b) > math.pi or a == b:   # a wrap at +-180 deg of -L: L crossing the positive real axis
            continue
        s = a / (a - b)
        gain_db = -20.0 / math.log(10.0) * (magnitude[k] + s * (magnitude[k + 1] - magnitude[k]))
        crossings.append((math.exp(x[k] + s * (x[k + 1] - x[k])), gain_db))
    return crossings


def predicted_margins(loop: IsolationLoop, axis: str, f_min: float = 0.01, f_max: float | None = None,
                      points: int = 20000) -> StabilityMargins:
    """stability_margins of loop_gain on a dense log grid up to Nyquist (default)."""
    f_max = f_max or 0.5 / loop.h * 0.999
    f = np.logspace(math.log10(f_min), math.log10(f_max), points)
    return stability_margins(f, [loop_gain(loop, axis, _unit_circle(each, loop.h)) for each in f])


def _unit_circle(frequency_hz: float, h: float) -> complex:
    return complex(math.cos(2 * math.pi * frequency_hz * h), math.sin(2 * math.pi * frequency_hz * h))
