"""What the controller sees: encoder angles (optionally quantized), the payload gyro los.omega
(optionally with white noise) and the base attitude and rates an IMU on the carrier gives (exact
values of the prescribed base motion, optionally with white noise on the attitude).

The noise of a whole run is drawn before it (`prepare`): the gyro's, then the IMU's, each as one
(n + 1) x 3 table from the scene's seed, so that the controller's set points can be computed up
front and the compiled loop reads the same numbers as the Python one. The sensors themselves
(quantization, noise) are the C kernel's (gimbal2axis/native/sensors.c), for both loops."""
from __future__ import annotations

import ctypes

import numpy as np

from .. import native
from ..errors import check_keys, number

KEYS = {"encoder_resolution_deg", "gyro_noise_deg_s", "imu_attitude_noise_deg", "seed"}


class Sensors:
    def __init__(self, spec: dict | None):
        spec = spec or {}
        check_keys("sensors", spec, KEYS)
        self.resolution = np.radians(number("sensors.encoder_resolution_deg", spec.get("encoder_resolution_deg", 0.0)))
        self.gyro_noise = np.radians(number("sensors.gyro_noise_deg_s", spec.get("gyro_noise_deg_s", 0.0)))
        self.imu_noise = np.radians(number("sensors.imu_attitude_noise_deg", spec.get("imu_attitude_noise_deg", 0.0)))
        self.rng = np.random.default_rng(int(spec.get("seed", 0)))
        self.ideal = self.resolution == 0 and self.gyro_noise == 0 and self.imu_noise == 0
        self.gyro_noise_table = None   # (n + 1) x 3, once prepared
        self.state = native.struct("GimbalSensors")()   # the kernel's view: resolution, noise table
        self.state.encoder_resolution = float(self.resolution)
        self._measured = (ctypes.c_double * 5)()

    def prepare(self, base_attitude: np.ndarray) -> np.ndarray:
        """Draws the noise of a run with len(base_attitude) communication points and returns the
        attitude the IMU measures at each of them."""
        count = len(base_attitude)
        self.gyro_noise_table = self.rng.normal(0.0, self.gyro_noise, (count, 3)) if self.gyro_noise > 0 else None
        self.state.gyro_noise = None if self.gyro_noise_table is None else self.gyro_noise_table.ctypes.data
        if self.imu_noise > 0:
            return base_attitude + self.rng.normal(0.0, self.imu_noise, (count, 3))
        return base_attitude

    def measure(self, step: int, alpha: float, beta: float, gyro: list):
        """(alpha, beta, [w1, w2, w3]) as measured at communication point `step` (after prepare)."""
        measured = self._measured
        measured[0], measured[1], measured[2:5] = alpha, beta, gyro
        native.kernel().gimbal_sensors_measure(ctypes.addressof(self.state), step, measured)
        return measured[0], measured[1], measured[2:5]
