"""The built-in controllers' set points for every communication point of a run, computed before the
loop and vectorised over it: by inverse kinematics of the target for the measured base attitude
(reference = "target"), or from the axis references (constant, step, ramp, sine).

Per axis: the set point at t_k and its rate. For a target, the rate is the derivative of the inverse
kinematics along the measured base rates (a difference over 1e-6 s of attitude); for the other
references, the difference quotient over one step. The azimuth to a target is stored as its
principal value: each step takes the 2 pi branch nearest the measured azimuth (the kernel's
controllers.c, for both loops), so a gimbal that has turned a full circle keeps tracking without a
jump.

The target's set points are the C kernel's (c_kernel/src/set_points.c), which the controller
FMU (docs/controller_fmu.md) runs too: libm's sin, cos, atan2 and hypot, where numpy may take SIMD
routines that round differently in the last bit. `target_angles` stays numpy, vectorised over
cases, for user controllers.
"""
from __future__ import annotations

import ctypes

import numpy as np

from .. import native
from ..target import MovingTarget, pointing

RATE_STEP_S = 1e-6   # the attitude difference for the target's rate (set_points.h GIMBAL_SET_POINT_RATE_STEP_S)


def target_angles(target, delta, psi, gamma):
    """Principal (alpha, beta) pointing the line of sight along `target` (a unit vector in G, (3,),
    or one per attitude, (N, 3)) for base attitudes given as arrays: the vectorised form of
    geometry.gimbal_angles_for."""
    x, y, z = (np.broadcast_to(component, np.shape(delta)) for component in np.asarray(target, dtype=float).T)
    c, s = np.cos(delta), np.sin(delta)
    x, y, z = x, c * y + s * z, -s * y + c * z
    c, s = np.cos(psi), np.sin(psi)
    x, y = c * x + s * y, -s * x + c * y
    c, s = np.cos(gamma), np.sin(gamma)
    x, z = c * x - s * z, s * x + c * z
    return np.arctan2(-x, y), np.arctan2(z, np.hypot(x, y))


def target_set_points(target, attitude: np.ndarray, rates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's set points toward `target` (a unit vector in G) for every row of the base
    attitude and its rates ((n + 1) x 3): values (principal alpha, beta) and their rates, (n + 1) x 2."""
    attitude = np.ascontiguousarray(attitude, dtype=float)
    rates = np.ascontiguousarray(rates, dtype=float)
    if attitude.shape != rates.shape or attitude.ndim != 2 or attitude.shape[1] != 3:
        raise ValueError(f"attitude {attitude.shape} and rates {rates.shape} must both be (n, 3)")
    direction = np.ascontiguousarray(target, dtype=float)
    values, value_rates = np.empty((len(attitude), 2)), np.empty((len(attitude), 2))
    native.kernel().gimbal_target_set_points(len(attitude), direction.ctypes.data, attitude.ctypes.data,
                                             rates.ctypes.data, values.ctypes.data, value_rates.ctypes.data)
    return values.T, value_rates.T


def target_direction(azimuth: float, elevation: float) -> tuple:
    """The kernel's unit vector in G of a target at (azimuth, elevation) [rad], as the controller
    FMU computes it from its parameters target.azimuth and target.elevation."""
    direction = (ctypes.c_double * 3)()
    native.kernel().gimbal_target_direction(azimuth, elevation, direction)
    return tuple(direction)


class SetPoints:
    """values[k, axis] and rates[k, axis], (n + 1) x 2 arrays; unwrap[axis]: the value is a
    principal angle to be taken in the branch nearest the measured one. A moving target adds
    accelerations[k, axis] and gyro_rates[k, (x2, z2)], the payload's inertial rate on track (the
    kernel's GimbalSetPoints); None otherwise."""

    def __init__(self, values: np.ndarray, rates: np.ndarray, unwrap: tuple, accelerations=None, gyro_rates=None):
        self.values = np.ascontiguousarray(values, dtype=float)
        self.rates = np.ascontiguousarray(rates, dtype=float)
        self.unwrap = tuple(bool(u) for u in unwrap)
        self.accelerations, self.gyro_rates = (None if a is None else np.ascontiguousarray(a, dtype=float)
                                               for a in (accelerations, gyro_rates))


def plan_set_points(references: list, target, times: np.ndarray, h: float, attitude: np.ndarray,
                    rates: np.ndarray, accelerations: np.ndarray | None = None) -> SetPoints:
    """`references` per axis: "target" or a Reference; `target` a unit vector in G or a moving target
    (gimbal2axis.target.MovingTarget); `accelerations` the base's angular accelerations (the command's
    accelerations toward a moving target; None: zero); `attitude` and `rates` the measured base
    attitude (delta, psi, gamma) and its rates at every time, (n + 1) x 3."""
    count = len(times)
    values, value_rates = np.zeros((count, 2)), np.zeros((count, 2))
    if "target" in references and isinstance(target, MovingTarget):
        # a moving target: the inverse kinematics' exact rates along the target's and the measured
        # carrier's motion (gimbal2axis/target), computed here in numpy for the whole run or chunk
        command = pointing(target, times, attitude, rates, accelerations)
        target_values = np.array([command.alpha, command.beta])
        target_rates = np.array([command.alpha_dot, command.beta_dot])
        target_accelerations = np.array([command.alpha_ddot, command.beta_ddot])
    elif "target" in references:
        target_values, target_rates = target_set_points(target, attitude, rates)
    for axis, reference in enumerate(references):
        if reference == "target":
            values[:, axis], value_rates[:, axis] = target_values[axis], target_rates[axis]
        else:
            now = [reference.at(float(t)) for t in times]
            values[:, axis] = now
            value_rates[:, axis] = [(reference.at(float(t) + h) - r) / h for t, r in zip(times, now)]
    unwrap = tuple(reference == "target" and axis == 0 for axis, reference in enumerate(references))
    if "target" in references and isinstance(target, MovingTarget):
        # per axis the target's acceleration, or the other reference's (zero: its rate is a difference)
        value_accelerations = np.zeros((count, 2))
        for axis, reference in enumerate(references):
            if reference == "target":
                value_accelerations[:, axis] = target_accelerations[axis]
        return SetPoints(values, value_rates, unwrap, value_accelerations, command.los_rate[[0, 2]].T)
    return SetPoints(values, value_rates, unwrap)
