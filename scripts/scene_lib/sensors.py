"""What the controller sees: encoder angles (optionally quantized), the payload gyro los.omega
(optionally with white noise) and the base attitude and rates an IMU on the carrier gives (exact
values of the prescribed base motion, optionally with white noise on the attitude)."""
from __future__ import annotations

import numpy as np

from .errors import check_keys, number

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

    def measure(self, alpha: float, beta: float, gyro: list, base_attitude: list, base_rates: list):
        """(alpha, beta, [w1, w2, w3], [delta, psi, gamma], [their rates]) as measured."""
        if self.ideal:
            return alpha, beta, gyro, base_attitude, base_rates
        if self.resolution > 0:
            alpha = self.resolution * round(alpha / self.resolution)
            beta = self.resolution * round(beta / self.resolution)
        if self.gyro_noise > 0:
            gyro = [w + n for w, n in zip(gyro, self.rng.normal(0.0, self.gyro_noise, 3))]
        if self.imu_noise > 0:
            base_attitude = [a + n for a, n in zip(base_attitude, self.rng.normal(0.0, self.imu_noise, 3))]
        return alpha, beta, gyro, base_attitude, base_rates
