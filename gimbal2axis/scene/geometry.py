"""Line-of-sight geometry.

Frames: G inertial with z_G up; the base attitude is GT0 = Rx(delta) Rz(psi) Ry(gamma) (pitch, yaw,
roll); the line of sight is the y axis of body 2, so in G it points along
GT0 * Rz(alpha) * Rx(beta) * [0, 1, 0].

A target direction is given by azimuth and elevation in G, with the same convention as the gimbal
angles on a level base: azimuth 0 is +y_G, positive azimuth turns about +z_G (towards -x_G),
elevation is positive upwards:  t = [-sin(az) cos(el), cos(az) cos(el), sin(el)].
So on a level base with yaw 0 the gimbal points at (az, el) with alpha = az, beta = el.

The vector functions work element-wise on numpy arrays (whole runs at once) and on floats.
"""
from __future__ import annotations

import math

import numpy as np


def rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def ry(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def base_to_inertial(delta: float, psi: float, gamma: float) -> np.ndarray:
    """GT0 = Rx(delta) Rz(psi) Ry(gamma): maps frame-0 coordinates to G (2.11)."""
    return rx(delta) @ rz(psi) @ ry(gamma)


def _rot_x(a, v):
    c, s = np.cos(a), np.sin(a)
    return (v[0], c * v[1] - s * v[2], s * v[1] + c * v[2])


def _rot_y(a, v):
    c, s = np.cos(a), np.sin(a)
    return (c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2])


def _rot_z(a, v):
    c, s = np.cos(a), np.sin(a)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1], v[2])


def los_in_base(alpha, beta):
    """Line of sight in frame 0: Rz(alpha) Rx(beta) [0, 1, 0]."""
    return (-np.sin(alpha) * np.cos(beta), np.cos(alpha) * np.cos(beta), np.sin(beta))


def los_direction(alpha, beta, delta, psi, gamma) -> np.ndarray:
    """Line of sight in G, shape (3,) or (3, n) for arrays."""
    v = los_in_base(alpha, beta)
    return np.array(_rot_x(delta, _rot_z(psi, _rot_y(gamma, v))))


def target_direction(azimuth, elevation) -> np.ndarray:
    """Unit vector in G of a target at (azimuth, elevation), radians."""
    return np.array([-np.sin(azimuth) * np.cos(elevation), np.cos(azimuth) * np.cos(elevation), np.sin(elevation)])


def angle_between(u: np.ndarray, v: np.ndarray):
    """Angle between vectors (first axis = components), accurate also for tiny angles."""
    cross = np.cross(u, v, axis=0)
    return np.arctan2(np.linalg.norm(cross, axis=0), np.sum(u * v, axis=0))


def los_error(alpha, beta, delta, psi, gamma, azimuth, elevation):
    """Angle [rad] between the line of sight and the target direction."""
    d = los_direction(alpha, beta, delta, psi, gamma)
    t = target_direction(azimuth, elevation)
    if d.ndim == 2:
        t = t[:, None]
    return angle_between(d, t)


def los_azimuth_elevation(alpha, beta, delta, psi, gamma):
    """Azimuth and elevation [rad] of the line of sight in G (the inverse of target_direction)."""
    d = los_direction(alpha, beta, delta, psi, gamma)
    return np.arctan2(-d[0], d[1]), np.arctan2(d[2], np.hypot(d[0], d[1]))


def gimbal_angles_for(target: tuple, delta: float, psi: float, gamma: float, alpha_near: float = 0.0):
    """Inverse kinematics: (alpha, beta) that point the line of sight along `target` (a unit vector
    in G) for the base attitude (delta, psi, gamma). Scalar, pure-math (called every step).

    Of the two solutions the one with |beta| <= 90 deg is returned; alpha is taken in the 2*pi
    branch nearest to `alpha_near`.
    """
    # frame-0 coordinates: 0TG t = Ry(-gamma) Rz(-psi) Rx(-delta) t
    x, y, z = target
    c, s = math.cos(delta), math.sin(delta)
    x, y, z = x, c * y + s * z, -s * y + c * z
    c, s = math.cos(psi), math.sin(psi)
    x, y = c * x + s * y, -s * x + c * y
    c, s = math.cos(gamma), math.sin(gamma)
    x, z = c * x - s * z, s * x + c * z
    beta = math.atan2(z, math.hypot(x, y))
    alpha = math.atan2(-x, y)
    alpha += 2.0 * math.pi * round((alpha_near - alpha) / (2.0 * math.pi))
    return alpha, beta


def wrap_angle(angle):
    """An angle in [-pi, pi)."""
    return (np.asarray(angle) + np.pi) % (2.0 * np.pi) - np.pi


def los_axis_errors(alpha, beta, delta, psi, gamma, azimuth, elevation):
    """Signed pointing errors [rad], line of sight minus target, along the two axes across the line of
    sight: cross-elevation (the azimuth error, wrapped, times cos of the target's elevation: the angle
    the azimuth error makes across the line of sight) and elevation. For small errors
    hypot(cross-elevation, elevation) is los_error."""
    az, el = los_azimuth_elevation(alpha, beta, delta, psi, gamma)
    return wrap_angle(az - azimuth) * np.cos(elevation), el - elevation


def carrier_rate(psi, gamma, delta_dot, psi_dot, gamma_dot):
    """The carrier's inertial angular velocity in frame 0 (docs/physics.md (2.13)) from the Euler
    angles and their rates: GT0 = Rx(delta) Rz(psi) Ry(gamma) gives
    w0 = Ry(gamma)^T Rz(psi)^T [delta', 0, 0] + Ry(gamma)^T [0, 0, psi'] + [0, gamma', 0]."""
    return (delta_dot * np.cos(psi) * np.cos(gamma) - psi_dot * np.sin(gamma),
            -delta_dot * np.sin(psi) + gamma_dot,
            delta_dot * np.cos(psi) * np.sin(gamma) + psi_dot * np.cos(gamma))


def carrier_rate_in_payload(alpha, beta, psi, gamma, delta_dot, psi_dot, gamma_dot):
    """The carrier's inertial angular velocity in the payload's frame 2: 2T1 1T0 omega_0 with
    1T0 = Rz(alpha)^T, 2T1 = Rx(beta)^T. The payload's own rate (los.omega) is this plus the joints'
    rates: [beta', alpha' sin(beta), alpha' cos(beta)]."""
    return _rot_x(-beta, _rot_z(-alpha, carrier_rate(psi, gamma, delta_dot, psi_dot, gamma_dot)))
