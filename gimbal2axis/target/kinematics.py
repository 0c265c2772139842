"""Line-of-sight kinematics of a moving target on a moving carrier (docs/physics.md, section 9).

Frames as in scene/geometry.py: G with z_G up, the base attitude GT0 = Rx(delta) Rz(psi) Ry(gamma),
the line of sight the y axis of body 2, Rz(alpha) Rx(beta) [0, 1, 0] in frame 0.

A target gives its position relative to the gimbal, p(t) in G [m], with its first two time
derivatives. From them: the unit vector u = p / |p| and its derivatives; in frame 0,
v = 0TG u, and the inverse kinematics alpha = atan2(-v_x, v_y), beta = atan2(v_z, hypot(v_x, v_y))
with their rates and accelerations, exact derivatives along the target's and the carrier's motion.
They are singular where hypot(v_x, v_y) = 0: the target on the azimuth axis (the zenith of a level
carrier), the two-axis gimbal's keyhole, where alpha' = (v_x v_y' - v_x' v_y) / (v_x^2 + v_y^2) is
unbounded.

Everything is vectorised over samples: vectors are (3, n) arrays (first axis = components).
"""
from __future__ import annotations

import numpy as np


# The keyhole's hold [rad]: a target direction nearer the azimuth axis than this (a thousandth of
# the gyros' microradian) has an azimuth of rounding noise, held instead (PointingCommand).
KEYHOLE_HOLD_RAD = 1e-9


def unit_and_derivatives(p, p_dot, p_ddot):
    """u = p/|p|, u' and u'' from p, p' and p'' ((3, n) each), and the range |p| and its rate.
    p = r u gives p' = r' u + r u', p'' = r'' u + 2 r' u' + r u''."""
    r = np.sqrt(np.sum(p * p, axis=0))
    u = p / r
    r_dot = np.sum(u * p_dot, axis=0)
    u_dot = (p_dot - u * r_dot) / r
    r_ddot = np.sum(u_dot * p_dot, axis=0) + np.sum(u * p_ddot, axis=0)
    u_ddot = (p_ddot - u * r_ddot - 2.0 * u_dot * r_dot) / r
    return u, u_dot, u_ddot, r, r_dot


def carrier_rate_and_acceleration(attitude, rates, accelerations):
    """The carrier's inertial angular velocity w0 in frame 0 (docs/physics.md (2.13)) and its time
    derivative, from the Euler angles (delta, psi, gamma), their rates and accelerations ((3, n) each)."""
    _, psi, gamma = attitude
    d1, p1, g1 = rates
    d2, p2, g2 = accelerations
    cp, sp, cg, sg = np.cos(psi), np.sin(psi), np.cos(gamma), np.sin(gamma)
    w = np.array([d1 * cp * cg - p1 * sg, -d1 * sp + g1, d1 * cp * sg + p1 * cg])
    w_dot = np.array([d2 * cp * cg - d1 * p1 * sp * cg - d1 * g1 * cp * sg - p2 * sg - p1 * g1 * cg,
                      -d2 * sp - d1 * p1 * cp + g2,
                      d2 * cp * sg - d1 * p1 * sp * sg + d1 * g1 * cp * cg + p2 * cg - p1 * g1 * sg])
    return w, w_dot


def inertial_to_base(vector, attitude):
    """0TG vector = Ry(-gamma) Rz(-psi) Rx(-delta) vector, (3, n), in the order of the kernel's
    gimbal_target_angles."""
    x, y, z = vector
    delta, psi, gamma = attitude
    c, s = np.cos(delta), np.sin(delta)
    y, z = c * y + s * z, -s * y + c * z
    c, s = np.cos(psi), np.sin(psi)
    x, y = c * x + s * y, -s * x + c * y
    c, s = np.cos(gamma), np.sin(gamma)
    x, z = c * x - s * z, s * x + c * z
    return np.array([x, y, z])


def base_to_inertial(vector, attitude):
    """GT0 vector = Rx(delta) Rz(psi) Ry(gamma) vector, (3, n): a vector of frame 0 in G (the inverse of
    inertial_to_base)."""
    x, y, z = vector
    delta, psi, gamma = attitude
    c, s = np.cos(gamma), np.sin(gamma)
    x, z = c * x + s * z, -s * x + c * z
    c, s = np.cos(psi), np.sin(psi)
    x, y = c * x - s * y, s * x + c * y
    c, s = np.cos(delta), np.sin(delta)
    y, z = c * y - s * z, s * y + c * z
    return np.array([x, y, z])


def _cross(a, b):
    return np.cross(a, b, axis=0)


class PointingCommand:
    """The gimbal angles that point the line of sight along u on the carrier, their rates and
    accelerations (principal alpha in (-pi, pi], |beta| <= pi/2), and the line of sight's inertial
    angular velocity the gyro reads on track, in the payload frame 2: (about the elevation axis x2,
    about the line of sight y2, cross-elevation about z2)."""

    def __init__(self, u, u_dot, u_ddot, attitude, rates, accelerations):
        # On the azimuth axis (the keyhole: rho2 = 0) the rates divide by zero and are inf or NaN, which
        # the keyhole policy of the callers handles; numpy's warnings about it would only be noise.
        with np.errstate(divide="ignore", invalid="ignore"):
            self._solve(u, u_dot, u_ddot, attitude, rates, accelerations)

    def _solve(self, u, u_dot, u_ddot, attitude, rates, accelerations):
        attitude, rates, accelerations = (np.asarray(a, dtype=float) for a in (attitude, rates, accelerations))
        w, w_dot = carrier_rate_and_acceleration(attitude, rates, accelerations)
        # v = C u with C = 0TG and C' = -[w x] C
        v = inertial_to_base(u, attitude)
        c_u_dot = inertial_to_base(u_dot, attitude)
        v_dot = c_u_dot - _cross(w, v)
        v_ddot = inertial_to_base(u_ddot, attitude) - _cross(w_dot, v) - _cross(w, v_dot) - _cross(w, c_u_dot)
        (x, y, z), (x1, y1, z1), (x2, y2, z2) = v, v_dot, v_ddot
        rho2 = x * x + y * y
        rho = np.sqrt(rho2)
        self.alpha = np.arctan2(-x, y)
        self.beta = np.arctan2(z, rho)
        n = x * y1 - x1 * y
        rho2_dot = 2.0 * (x * x1 + y * y1)
        self.alpha_dot = n / rho2
        self.alpha_ddot = (x * y2 - x2 * y) / rho2 - n * rho2_dot / (rho2 * rho2)
        rho_dot = (x * x1 + y * y1) / rho
        rho_ddot = (x1 * x1 + y1 * y1 + x * x2 + y * y2 - rho_dot * rho_dot) / rho
        s2 = rho2 + z * z
        s2_dot = rho2_dot + 2.0 * z * z1
        m = rho * z1 - z * rho_dot
        self.beta_dot = m / s2
        self.beta_ddot = (rho * z2 - z * rho_ddot) / s2 - m * s2_dot / (s2 * s2)
        # the line of sight's inertial rate u x u' (in G), in frame 2 = Rx(beta)^T Rz(alpha)^T 0TG
        rate_0 = inertial_to_base(_cross(u, u_dot), attitude)
        ca, sa, cb, sb = np.cos(self.alpha), np.sin(self.alpha), np.cos(self.beta), np.sin(self.beta)
        r1 = np.array([ca * rate_0[0] + sa * rate_0[1], -sa * rate_0[0] + ca * rate_0[1], rate_0[2]])
        self.los_rate = np.array([r1[0], cb * r1[1] + sb * r1[2], -sb * r1[1] + cb * r1[2]])
        self.direction_in_base = v
        self._hold_azimuth(~(rho > KEYHOLE_HOLD_RAD))

    def _hold_azimuth(self, on_axis):
        """The keyhole policy where the target is on the azimuth axis (within KEYHOLE_HOLD_RAD): the
        azimuth holds the command of the sample before (of the first sample off the axis, at the
        start; 0 if none), the elevation is the exact +-90 deg, and their rates and accelerations are
        0 (the line of sight's inertial rate stays): there the inverse kinematics divides by zero (docs/physics.md, section 9.3)."""
        if not np.any(on_axis):
            return
        index = np.where(on_axis, -1, np.arange(on_axis.size))
        index = np.maximum.accumulate(index)
        off_axis = np.flatnonzero(~on_axis)
        index[index < 0] = off_axis[0] if off_axis.size else -1
        held = np.where(index >= 0, self.alpha[np.maximum(index, 0)], 0.0)
        self.alpha = np.where(on_axis, held, self.alpha)
        for name in ("alpha_dot", "alpha_ddot", "beta_dot", "beta_ddot"):
            setattr(self, name, np.where(on_axis, 0.0, getattr(self, name)))
        # the line of sight's own rate u x u' stays (what the gyro reads as the target passes), unless not finite
        self.los_rate = np.where(on_axis & ~np.isfinite(self.los_rate), 0.0, self.los_rate)
