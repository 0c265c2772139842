"""An example of a controller of your own for the scene runner and the sweeps.

A scene names it in its [controller] table (see user_controller.toml next to this file):

    [controller]
    type = "python"
    module = "gyro_stabilizer.py"      # relative to the scene file, or an importable module name
    class = "GyroStabilizer"
    options = { kp = 400.0, ki = 8000.0, k_gyro = 8.0 }

The runner builds the class once with the options as keyword arguments, calls reset(context) before
every run and step(t, measurements) at every communication point; step returns the two motor
voltages. Here: per axis, PI on the error between the set point that points the line of sight at
the target (inverse kinematics for the measured carrier attitude) and the encoder angle, plus
damping on the payload gyro, which rejects the carrier's motion directly.
"""
import math

from scene_lib.controllers import gyro_axis_rates
from scene_lib.geometry import gimbal_angles_for


class GyroStabilizer:
    def __init__(self, kp: float = 400.0, ki: float = 8000.0, k_gyro: float = 8.0):
        self.kp, self.ki, self.k_gyro = kp, ki, k_gyro

    def reset(self, context):
        """context: step_size [s], u_limit (U_L1, U_L2) [V], target (unit vector in G, or None),
        delay_steps, scene_name."""
        if context.target is None:
            raise ValueError("GyroStabilizer points at a target: the scene needs a [target] table")
        self.h, self.u_limit, self.target = context.step_size, context.u_limit, context.target
        self.integral = [0.0, 0.0]
        self.reference = (math.nan, math.nan)

    def step(self, t, m):
        """m: alpha, beta [rad], gyro (w1, w2, w3) [rad/s], base_attitude, base_rates -> (u_R1, u_R2) [V]."""
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
