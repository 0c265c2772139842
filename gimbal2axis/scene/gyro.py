"""A rate gyro from its datasheet ([sensors.gyro] of a scene): what each figure means, its unit, its
check, and the numbers the C kernel's gyro (c_kernel/include/gimbal_kernel/gyro.h) runs on: the axes matrix,
the discrete bandwidth filter and the table of stochastic errors of a whole run.

Stochastic terms (IEEE Std 952 conventions; the Allan deviation sigma(tau) of a gyro at rest):
  angle random walk N [deg/sqrt(h)]     white rate noise: sigma(tau) = N / sqrt(tau); per sample of
                                        length h its standard deviation is N / sqrt(h)
  bias instability B [deg/h]            flicker (1/f) rate noise, whose Allan deviation is flat at
                                        sqrt(2 ln 2 / pi) B = 0.664 B; made of first-order
                                        Gauss-Markov processes with correlation times spaced
                                        sqrt(10) apart from bias_correlation_time_s down to 10
                                        samples, each of variance ln(sqrt(10)) B^2 / pi: their
                                        summed spectrum is B^2 / (2 pi f) inside that band
  rate random walk K [deg/h/sqrt(h)]    integrated white noise: sigma(tau) = K sqrt(tau / 3)
  bias [deg/h]                          a constant offset (the turn-on bias of this run)
Deterministic terms: scale factor error [ppm] and misalignment [mrad] (the axes matrix
I + diag(scale) + off-diagonal misalignment), the bandwidth (a second-order low-pass of natural
frequency bandwidth_hz and damping), quantization [deg/s, one least significant bit] and a delay of
whole samples. Every figure defaults to 0 (none), the damping to 0.7.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError, check_keys, number, shown

GYRO_KEYS = {"angle_random_walk_deg_rt_h", "bias_instability_deg_h", "bias_correlation_time_s",
             "rate_random_walk_deg_h_rt_h", "bias_deg_h", "scale_factor_error_ppm", "misalignment_mrad",
             "bandwidth_hz", "damping", "quantization_deg_s", "delay_samples"}
MAX_DELAY = 16                 # c_kernel/include/gimbal_kernel/gyro.h GIMBAL_GYRO_MAX_DELAY
FLICKER_SPACING = math.sqrt(10.0)
DEFAULT_BIAS_CORRELATION_TIME = 1000.0   # s: the Allan deviation stays flat up to a few hundred s
FLICKER_SHORTEST_SAMPLES = 10            # shorter correlation times are white noise at this rate
DEG_PER_HOUR = math.pi / 180.0 / 3600.0  # rad/s
SQRT_HOUR = 60.0                         # sqrt(s) per sqrt(h)


def _non_negative(where: str, value) -> float:
    value = number(where, value)
    if value < 0:
        raise SceneError(f"{where} must be >= 0, got {value!r}")
    return value


def _per_axis(where: str, value, count: int = 3) -> np.ndarray:
    """A number for every axis or a list of `count`."""
    if isinstance(value, list):
        if len(value) != count:
            raise SceneError(f"{where} must be a number or a list of {count} numbers, got {len(value)}")
        return np.array([number(f"{where}[{i}]", v) for i, v in enumerate(value)])
    return np.full(count, number(where, value))


class GyroModel:
    """The datasheet of [sensors.gyro] (`where` names the table in messages), checked."""

    def __init__(self, spec: dict, where: str = "sensors.gyro"):
        check_keys(where, spec, GYRO_KEYS)
        key = lambda name: f"{where}.{name}"
        self.angle_random_walk = _non_negative(key("angle_random_walk_deg_rt_h"),
                                               spec.get("angle_random_walk_deg_rt_h", 0.0))
        self.bias_instability = _non_negative(key("bias_instability_deg_h"), spec.get("bias_instability_deg_h", 0.0))
        self.bias_correlation_time = number(key("bias_correlation_time_s"),
                                            spec.get("bias_correlation_time_s", DEFAULT_BIAS_CORRELATION_TIME))
        if not self.bias_correlation_time > 0:
            raise SceneError(f"{key('bias_correlation_time_s')} must be positive, got {self.bias_correlation_time!r}")
        self.rate_random_walk = _non_negative(key("rate_random_walk_deg_h_rt_h"),
                                              spec.get("rate_random_walk_deg_h_rt_h", 0.0))
        self.bias = _per_axis(key("bias_deg_h"), spec.get("bias_deg_h", 0.0))
        self.scale_factor_error = _per_axis(key("scale_factor_error_ppm"), spec.get("scale_factor_error_ppm", 0.0))
        misalignment = spec.get("misalignment_mrad", [0.0] * 6)
        if not isinstance(misalignment, list):
            raise SceneError(f"{key('misalignment_mrad')} must be a list of 6 numbers [xy, xz, yx, yz, zx, zy] "
                             f"(mrad: how much of the rate about the second axis the first axis reads)")
        self.misalignment = _per_axis(key("misalignment_mrad"), misalignment, 6)
        self.bandwidth = _non_negative(key("bandwidth_hz"), spec.get("bandwidth_hz", 0.0))
        self.damping = number(key("damping"), spec.get("damping", 0.7))
        if not self.damping > 0:
            raise SceneError(f"{key('damping')} must be positive, got {self.damping!r}")
        self.quantum = math.radians(_non_negative(key("quantization_deg_s"), spec.get("quantization_deg_s", 0.0)))
        delay = spec.get("delay_samples", 0)
        if isinstance(delay, bool) or not isinstance(delay, int) or not 0 <= delay <= MAX_DELAY:
            raise SceneError(f"{key('delay_samples')} must be an integer in [0, {MAX_DELAY}], got {shown(delay)}")
        self.delay = delay

    def axes(self) -> np.ndarray:
        """I + scale factor errors on the diagonal + misalignments off it (row i: what axis i reads)."""
        matrix = np.diag(1.0 + self.scale_factor_error * 1e-6)
        for (row, column), value in zip([(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)], self.misalignment):
            matrix[row, column] = value * 1e-3
        return matrix

    def filter(self, h: float):
        """(A, B, C, D, settled) of the bandwidth's low-pass w_n^2 / (s^2 + 2 zeta w_n s + w_n^2)
        discretized with a first-order hold at step h; settled: the state of a unit constant input."""
        from scipy import signal   # here, not at the top: 0.5 s to import, for a gyro with a bandwidth only

        w_n = 2.0 * math.pi * self.bandwidth
        continuous = (np.array([[0.0, 1.0], [-w_n ** 2, -2.0 * self.damping * w_n]]), np.array([[0.0], [w_n ** 2]]),
                      np.array([[1.0, 0.0]]), np.array([[0.0]]))
        a, b, c, d, _ = signal.cont2discrete(continuous, h, method="foh")
        settled = np.linalg.solve(np.eye(2) - a, b[:, 0])
        return a, b[:, 0], c[0], float(d[0, 0]), settled

    def flicker_processes(self, h: float) -> list[tuple[float, float]]:
        """(correlation time, standard deviation) of the Gauss-Markov processes of the bias instability."""
        if self.bias_instability == 0:
            return []
        variance = math.log(FLICKER_SPACING) * (self.bias_instability * DEG_PER_HOUR) ** 2 / math.pi
        times, time = [], self.bias_correlation_time
        while not times or time >= FLICKER_SHORTEST_SAMPLES * h:
            times.append(time)
            time /= FLICKER_SPACING
        return [(time, math.sqrt(variance)) for time in times]

    def error_table(self, h: float, count: int, rng: np.random.Generator) -> np.ndarray | None:
        """The stochastic errors and the bias of `count` samples (count x 3, rad/s), or None."""
        from scipy import signal   # here, not at the top: 0.5 s to import, for a noisy gyro only

        table = np.zeros((count, 3))
        drawn = False
        if self.angle_random_walk > 0:
            per_sample = self.angle_random_walk * math.radians(1.0) / SQRT_HOUR / math.sqrt(h)
            table += rng.normal(0.0, per_sample, (count, 3))
            drawn = True
        for correlation_time, deviation in self.flicker_processes(h):
            # x_k = phi x_{k-1} + sqrt(1 - phi^2) sigma w_k, started from its stationary distribution
            phi = math.exp(-h / correlation_time)
            start = rng.normal(0.0, deviation, (1, 3))
            driving = rng.normal(0.0, 1.0, (count, 3))
            table += signal.lfilter([math.sqrt(1.0 - phi * phi) * deviation], [1.0, -phi], driving, axis=0,
                                    zi=phi * start)[0]
            drawn = True
        if self.rate_random_walk > 0:
            per_sample = self.rate_random_walk * DEG_PER_HOUR / SQRT_HOUR * math.sqrt(h)
            table += np.cumsum(rng.normal(0.0, per_sample, (count, 3)), axis=0)
            drawn = True
        if np.any(self.bias != 0):
            table += self.bias * DEG_PER_HOUR
            drawn = True
        return table if drawn else None

    def configure(self, state, h: float, count: int, rng: np.random.Generator):
        """Fills the kernel's GimbalGyro `state` for a run of `count` samples of step h; returns the
        error table it points into (keep it alive for the run)."""
        self.configure_deterministic(state, h)
        errors = self.error_table(h, count, rng)
        state.error = None if errors is None else errors.ctypes.data
        return errors

    def configure_deterministic(self, state, h: float) -> None:
        """configure without the error table (state.error None): axes, filter, quantization, delay."""
        state.enabled = 1
        state.axes[:] = self.axes().ravel().tolist()
        state.filtered = int(self.bandwidth > 0)
        if self.bandwidth > 0:
            a, b, c, d, settled = self.filter(h)
            state.filter_a[:], state.filter_b[:] = a.ravel().tolist(), b.tolist()
            state.filter_c[:], state.filter_d, state.filter_settled[:] = c.tolist(), d, settled.tolist()
        state.error = None
        state.quantum, state.delay = self.quantum, self.delay


class GyroErrorStream:
    """error_table made a chunk of rows at a time, for a run too long to hold it whole
    (master/streaming.py): `rows(count)` gives the next `count` rows, the same bits as the rows of
    error_table(h, total, rng). `generator(draw)` is a numpy Generator positioned where error_table's
    draw number `draw` starts (draws: error_draws)."""

    def __init__(self, gyro: GyroModel, h: float, generator):
        self.gyro, self.h = gyro, h
        self.flicker = []   # per process: [generator, b, a, zi]
        draw = 0
        if gyro.angle_random_walk > 0:
            self.arw = (generator(draw), gyro.angle_random_walk * math.radians(1.0) / SQRT_HOUR / math.sqrt(h))
            draw += 1
        for correlation_time, deviation in gyro.flicker_processes(h):
            phi = math.exp(-h / correlation_time)
            start = generator(draw).normal(0.0, deviation, (1, 3))
            self.flicker.append([generator(draw + 1), [math.sqrt(1.0 - phi * phi) * deviation], [1.0, -phi],
                                 phi * start])
            draw += 2
        if gyro.rate_random_walk > 0:
            self.rrw = (generator(draw), gyro.rate_random_walk * DEG_PER_HOUR / SQRT_HOUR * math.sqrt(h))
            self.walk = None   # the last row of the cumulative sum so far
        self.drawn = draw > 0 or bool(np.any(gyro.bias != 0))

    def rows(self, count: int) -> np.ndarray | None:
        if not self.drawn:
            return None
        table = np.zeros((count, 3))
        if self.gyro.angle_random_walk > 0:
            table += self.arw[0].normal(0.0, self.arw[1], (count, 3))
        for process in self.flicker:
            from scipy import signal   # here, not at the top: 0.5 s to import, for a gyro with bias instability only

            driving = process[0].normal(0.0, 1.0, (count, 3))
            filtered, process[3] = signal.lfilter(process[1], process[2], driving, axis=0, zi=process[3])
            table += filtered
        if self.gyro.rate_random_walk > 0:
            steps = self.rrw[0].normal(0.0, self.rrw[1], (count, 3))
            # the sum carried on from the chunk before, in the same order of additions as one cumsum
            walk = np.cumsum(steps, axis=0) if self.walk is None else \
                np.cumsum(np.concatenate([self.walk, steps]), axis=0)[1:]
            self.walk = walk[-1:].copy()
            table += walk
        if np.any(self.gyro.bias != 0):
            table += self.gyro.bias * DEG_PER_HOUR
        return table


def error_draws(gyro: GyroModel, h: float, count: int) -> list[tuple[int, float]]:
    """The normal draws error_table makes from its generator, in order: (rows of 3, standard deviation)."""
    draws = []
    if gyro.angle_random_walk > 0:
        draws.append((count, gyro.angle_random_walk * math.radians(1.0) / SQRT_HOUR / math.sqrt(h)))
    for _, deviation in gyro.flicker_processes(h):
        draws += [(1, deviation), (count, 1.0)]
    if gyro.rate_random_walk > 0:
        draws.append((count, gyro.rate_random_walk * DEG_PER_HOUR / SQRT_HOUR * math.sqrt(h)))
    return draws
