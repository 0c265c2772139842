"""What the controller sees ([sensors] of a scene; default ideal):

  encoder_resolution_deg, encoder_offset_deg   the encoder angles: plus the offset ([alpha, beta] or
                                               one number), quantized to the resolution
  stabilization = "direct" | "indirect"        where the rate the loop feeds back comes from: a gyro
                                               on the payload reading los.omega (direct, the
                                               default), or a gyro on the carrier whose reading the
                                               gimbal's kinematics carry to the payload with the
                                               encoder angles and joint rates (indirect)
  joint_rate = "tachometer" | "encoder_difference"   indirect: the joint rates alpha_dot, beta_dot as
                                               a tachometer gives them (exact), or the encoders'
                                               backward differences over one step
  [sensors.gyro]                               the gyro's datasheet (gyro.py), payload or carrier
  gyro_noise_deg_s                             white noise added to the rate fed back (std per sample)
  imu_attitude_noise_deg                       white noise on the base attitude the ship's IMU gives
                                               the set points
  seed                                         every random number of a run comes from it

The noise of a whole run is drawn before it (`prepare`), in a fixed order (the older white gyro
noise, the IMU's, then the datasheet gyro's terms), so that the controller's set points can be
computed up front and the compiled loop reads the same numbers as the Python one. The sensors
themselves are the C kernel's (gimbal2axis/native/sensors.c, gyro.c), for both loops."""
from __future__ import annotations

import ctypes
import math

import numpy as np

from .. import native
from . import geometry
from ..errors import SceneError, check_keys, number
from .gyro import GyroModel

KEYS = {"encoder_resolution_deg", "encoder_offset_deg", "gyro_noise_deg_s", "imu_attitude_noise_deg", "seed",
        "stabilization", "joint_rate", "gyro"}
SCHEMES = ("direct", "indirect")
JOINT_RATES = ("tachometer", "encoder_difference")


def _choice(where: str, value, allowed: tuple) -> str:
    if value not in allowed:
        raise SceneError(f"{where} must be one of {', '.join(repr(a) for a in allowed)}, got {value!r}")
    return value


def carrier_rate(base: np.ndarray, h: float | None = None) -> np.ndarray:
    """The carrier's inertial angular velocity in frame 0 (n x 3, rad/s; geometry.carrier_rate) from
    the base motion's columns (delta, psi, gamma, their rates, their accelerations, ...).

    With the step h: at communication point k >= 1 the rate of the carrier as the FMU moved it over
    the step before, i.e. the attitude and rates set at t_(k-1) carried to t_k with their constant
    acceleration (how the FMU holds its base inputs over a step, docs/physics.md section 2), so
    that a gyro on the carrier and one on the payload see the same carrier. Without h: at the
    samples themselves."""
    angles, rates = base[:, 0:3].copy(), base[:, 3:6].copy()
    if h is not None and len(base) > 1:
        accelerations = base[:-1, 6:9]
        angles[1:] = base[:-1, 0:3] + base[:-1, 3:6] * h + accelerations * (0.5 * h * h)
        rates[1:] = base[:-1, 3:6] + accelerations * h
    return np.column_stack(geometry.carrier_rate(angles[:, 1], angles[:, 2], rates[:, 0], rates[:, 1], rates[:, 2]))


class Sensors:
    def __init__(self, spec: dict | None):
        spec = spec or {}
        check_keys("sensors", spec, KEYS)
        self.resolution = np.radians(number("sensors.encoder_resolution_deg", spec.get("encoder_resolution_deg", 0.0)))
        offset = spec.get("encoder_offset_deg", 0.0)
        if isinstance(offset, list) and len(offset) != 2:
            raise SceneError(f"sensors.encoder_offset_deg must be a number or [alpha, beta], got {len(offset)} numbers")
        offsets = offset if isinstance(offset, list) else [offset, offset]
        self.encoder_offset = [math.radians(number(f"sensors.encoder_offset_deg[{i}]", v)) for i, v in enumerate(offsets)]
        self.gyro_noise = np.radians(number("sensors.gyro_noise_deg_s", spec.get("gyro_noise_deg_s", 0.0)))
        self.imu_noise = np.radians(number("sensors.imu_attitude_noise_deg", spec.get("imu_attitude_noise_deg", 0.0)))
        self.scheme = _choice("sensors.stabilization", spec.get("stabilization", "direct"), SCHEMES)
        self.joint_rate = _choice("sensors.joint_rate", spec.get("joint_rate", "tachometer"), JOINT_RATES)
        gyro_spec = spec.get("gyro")
        if gyro_spec is not None and not isinstance(gyro_spec, dict):
            raise SceneError("[sensors] gyro must be a table ([sensors.gyro])")
        self.gyro = None if gyro_spec is None else GyroModel(gyro_spec)
        self.seed = int(spec.get("seed", 0))
        self.rng = np.random.default_rng(self.seed)
        self.ideal = (self.resolution == 0 and self.gyro_noise == 0 and self.imu_noise == 0 and self.gyro is None
                      and self.scheme == "direct" and not any(self.encoder_offset))
        self.gyro_noise_table = None   # (n + 1) x 3, once prepared
        self.carrier_rates = None      # indirect: what the carrier gyro reads, (n + 1) x 3, once prepared
        self._kept = []                # arrays the kernel's struct points into
        self.state = native.struct("GimbalSensors")()
        self.state.encoder_resolution = float(self.resolution)
        self.state.encoder_offset[:] = self.encoder_offset
        self.state.indirect = int(self.scheme == "indirect")
        self.state.joint_rate_from_encoders = int(self.joint_rate == "encoder_difference")
        self._measured = (ctypes.c_double * 7)()

    def prepare(self, base: np.ndarray, h: float = 0.0) -> np.ndarray:
        """Draws the noise of a run with len(base) communication points of step h (base: the base
        motion's columns, at least the attitude) and returns the attitude the IMU measures at each."""
        count, attitude = len(base), base[:, :3]
        self.rng = np.random.default_rng(self.seed)   # a run is the same whenever it is prepared
        self.gyro_noise_table = self.rng.normal(0.0, self.gyro_noise, (count, 3)) if self.gyro_noise > 0 else None
        self.state.gyro_noise = None if self.gyro_noise_table is None else self.gyro_noise_table.ctypes.data
        measured_attitude = attitude + self.rng.normal(0.0, self.imu_noise, (count, 3)) if self.imu_noise > 0 \
            else attitude
        self._kept = []
        self.state.h = h
        gyro_state = self.state.gyro
        if self.gyro is not None:
            if not h > 0:
                raise SceneError("sensors: the gyro model needs the communication step")
            self._kept.append(self.gyro.configure(gyro_state, h, count, self.rng))
        if self.scheme == "indirect":
            if base.shape[1] < 9:
                raise SceneError("sensors: indirect stabilization needs the base attitude, rates and accelerations")
            readings = np.ascontiguousarray(carrier_rate(base, h))
            if self.gyro is not None:   # the carrier gyro: the same datasheet, its own run of the kernel's gyro
                native.kernel().gimbal_gyro_series(ctypes.addressof(gyro_state), count, readings.ctypes.data,
                                                   readings.ctypes.data)
            self.carrier_rates = readings
            self.state.carrier_rate = readings.ctypes.data
            gyro_state.enabled = 0      # no payload gyro
        return measured_attitude

    def measure(self, step: int, alpha: float, beta: float, gyro: list, alpha_dot: float = 0.0,
                beta_dot: float = 0.0):
        """(alpha, beta, [w1, w2, w3]) as measured at communication point `step` (after prepare) from
        the FMU's alpha, beta, los.omega and, for indirect stabilization, alpha_dot and beta_dot."""
        measured = self._measured
        measured[0], measured[1], measured[2:5], measured[5], measured[6] = alpha, beta, gyro, alpha_dot, beta_dot
        native.kernel().gimbal_sensors_measure(ctypes.addressof(self.state), step, measured)
        return measured[0], measured[1], measured[2:5]
