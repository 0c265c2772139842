"""The built-in controllers' set points for every communication point of a run, computed before the
loop and vectorised over it: by inverse kinematics of the target for the measured base attitude
(reference = "target"), or from the axis references (constant, step, ramp, sine).

Per axis: the set point at t_k and its rate. For a target, the rate is the derivative of the inverse
kinematics along the measured base rates (a difference over 1e-6 s of attitude); for the other
references, the difference quotient over one step. The azimuth to a target is stored as its
principal value: each step takes the 2 pi branch nearest the measured azimuth (the kernel's
controllers.c, for both loops), so a gimbal that has turned a full circle keeps tracking without a
jump.
"""
from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi
RATE_STEP_S = 1e-6   # the attitude difference for the target's rate


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


class SetPoints:
    """values[k, axis] and rates[k, axis], (n + 1) x 2 arrays; unwrap[axis]: the value is a
    principal angle to be taken in the branch nearest the measured one."""

    def __init__(self, values: np.ndarray, rates: np.ndarray, unwrap: tuple):
        self.values = np.ascontiguousarray(values, dtype=float)
        self.rates = np.ascontiguousarray(rates, dtype=float)
        self.unwrap = tuple(bool(u) for u in unwrap)


def plan_set_points(references: list, target, times: np.ndarray, h: float, attitude: np.ndarray,
                    rates: np.ndarray) -> SetPoints:
    """`references` per axis: "target" or a Reference; `attitude` and `rates` the measured base
    attitude (delta, psi, gamma) and its rates at every time, (n + 1) x 3."""
    count = len(times)
    values, value_rates = np.zeros((count, 2)), np.zeros((count, 2))
    if "target" in references:
        alpha, beta = target_angles(target, attitude[:, 0], attitude[:, 1], attitude[:, 2])
        ahead = attitude + RATE_STEP_S * rates
        alpha_ahead, beta_ahead = target_angles(target, ahead[:, 0], ahead[:, 1], ahead[:, 2])
        turn = alpha_ahead - alpha
        turn -= TWO_PI * np.round(turn / TWO_PI)
        target_values = (alpha, beta)
        target_rates = (turn / RATE_STEP_S, (beta_ahead - beta) / RATE_STEP_S)
    for axis, reference in enumerate(references):
        if reference == "target":
            values[:, axis], value_rates[:, axis] = target_values[axis], target_rates[axis]
        else:
            now = [reference.at(float(t)) for t in times]
            values[:, axis] = now
            value_rates[:, axis] = [(reference.at(float(t) + h) - r) / h for t, r in zip(times, now)]
    return SetPoints(values, value_rates, tuple(reference == "target" and axis == 0
                                               for axis, reference in enumerate(references)))
