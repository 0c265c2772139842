"""An example of a controller of your own for the scene runner and the sweeps.

A scene names it in its [controller] table (see user_controller.toml next to this file):

    [controller]
    type = "python"
    file = "gyro_stabilizer.py"        # relative to the scene file (older scenes say module = ...)
    class = "GyroStabilizer"
    options = { kp = 400.0, ki = 8000.0, k_gyro = 8.0 }

The runner loads this file (it is code that runs with your rights), checks the class, builds it once
with the options as keyword arguments, calls reset(context) before every run and step(t,
measurements) at every communication point; step returns the two motor voltages, two finite numbers
(clamped to the motors' limits by the runner too). The context's and the measurements' attributes,
units and order, and the helpers imported below: docs/controller_api.md. Here: per axis, PI on the error between the set point that points the line of sight at
the target (inverse kinematics for the measured carrier attitude) and the encoder angle, plus
damping on the payload gyro, which rejects the carrier's motion directly.

GyroStabilizerBatch below is the same controller in the batch form (`batch = True`): numpy arrays
with one entry per case, so that a sweep steps the cases of a task together (lockstep). Name it as
`class = "GyroStabilizerBatch"`; it runs single scenes too (arrays of one case).
"""
import math

import numpy as np

from gimbal2axis.scene.controllers import gyro_axis_rates
from gimbal2axis.scene.geometry import gimbal_angles_for
from gimbal2axis.scene.setpoints import target_angles


class GyroStabilizer:
    def __init__(self, kp: float = 400.0, ki: float = 8000.0, k_gyro: float = 8.0):
        self.kp, self.ki, self.k_gyro = kp, ki, k_gyro

    def reset(self, context):
        """context: step_size [s], u_limit (U_L1, U_L2) [V], target (unit vector in G, or None),
        delay_steps, scene_name, cases (docs/controller_api.md)."""
        if context.target is None:
            raise ValueError("GyroStabilizer points at a target: the scene needs a [target] table")
        self.h, self.u_limit, self.target = context.step_size, context.u_limit, context.target
        self.integral = [0.0, 0.0]
        self.reference = (math.nan, math.nan)

    def step(self, t, m):
        """m: alpha, beta [rad], gyro (w1, w2, w3) [rad/s], base_attitude (delta, psi, gamma: pitch, yaw,
        roll) [rad], base_rates [rad/s] -> (u_R1, u_R2) [V]."""
        references = gimbal_angles_for(self.target, *m.base_attitude, alpha_near=m.alpha)
        self.reference = references
        rates = gyro_axis_rates(m.gyro, m.beta)
        voltages = []
        for axis, (reference, angle, rate) in enumerate(zip(references, (m.alpha, m.beta), rates)):
            error = reference - angle
            u = self.kp * error + self.ki * self.integral[axis] - self.k_gyro * rate
            limit = self.u_limit[axis]
            if abs(u) < limit:  # anti-windup: integrate only while the output is not saturated
                self.integral[axis] += error * self.h
            voltages.append(min(max(u, -limit), limit))
        return voltages


class GyroStabilizerBatch(GyroStabilizer):
    """GyroStabilizer for N cases at once. The options arrive as numbers (equal in all cases) or as
    arrays of shape (N,) (swept ones); reset() gets context.cases = N and step() arrays: alpha, beta
    (N,), gyro, base_attitude, base_rates (N, 3); it returns the voltages as (u_R1, u_R2), two
    arrays of shape (N,) (an (N, 2) array would do as well). The same arithmetic as the scalar
    form, element by element, but numpy's atan2 and hypot may differ from the math module's in
    the last bit."""
    batch = True

    def reset(self, context):
        if context.target is None:
            raise ValueError("GyroStabilizerBatch points at a target: the scene needs a [target] table")
        self.h, self.target = context.step_size, np.asarray(context.target, dtype=float)
        zeros = np.zeros(context.cases)
        self.u_limit = [zeros + limit for limit in context.u_limit]   # per axis, (N,)
        self.gains = [zeros + gain for gain in (self.kp, self.ki, self.k_gyro)]
        self.integral = [zeros.copy(), zeros.copy()]
        self.reference = (math.nan, math.nan)

    def step(self, t, m):
        references = gimbal_angles(self.target, m.base_attitude, m.alpha)
        self.reference = references
        gyro = m.gyro
        rates = (gyro[:, 2] / np.maximum(np.cos(m.beta), 0.2), gyro[:, 0])
        kp, ki, k_gyro = self.gains
        voltages = []
        for axis, (reference, angle, rate) in enumerate(zip(references, (m.alpha, m.beta), rates)):
            error = reference - angle
            u = kp * error + ki * self.integral[axis] - k_gyro * rate
            limit = self.u_limit[axis]
            unsaturated = np.abs(u) < limit   # anti-windup, per case
            self.integral[axis] += np.where(unsaturated, error * self.h, 0.0)
            voltages.append(np.minimum(np.maximum(u, -limit), limit))
        return voltages   # (u_R1, u_R2), two arrays of shape (N,)


def gimbal_angles(target, attitude, alpha_near):
    """gimbal2axis.scene.geometry.gimbal_angles_for on arrays: target (3,) or (N, 3), attitude (N, 3)
    [delta, psi, gamma], alpha_near (N,) -> alpha, beta (N,)."""
    alpha, beta = target_angles(target, *np.asarray(attitude).T)
    alpha = alpha + 2.0 * math.pi * np.round((alpha_near - alpha) / (2.0 * math.pi))
    return alpha, beta
