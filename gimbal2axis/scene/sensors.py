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
themselves are the C kernel's (c_kernel/src/sensors.c, gyro.c), for both loops."""
from __future__ import annotations

import ctypes
import math

import numpy as np

from .. import native
from . import geometry
from ..errors import SceneError, check_keys, choice, integer, non_negative, number, shown
from .gyro import GyroErrorStream, GyroModel, error_draws

KEYS = {"encoder_resolution_deg", "encoder_offset_deg", "gyro_noise_deg_s", "imu_attitude_noise_deg", "seed",
        "stabilization", "joint_rate", "gyro"}
SCHEMES = ("direct", "indirect")
JOINT_RATES = ("tachometer", "encoder_difference")


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
        self.resolution = np.radians(non_negative("sensors.encoder_resolution_deg", spec.get("encoder_resolution_deg", 0.0)))
        offset = spec.get("encoder_offset_deg", 0.0)
        if isinstance(offset, list) and len(offset) != 2:
            raise SceneError(f"sensors.encoder_offset_deg must be a number or [alpha, beta], got {len(offset)} numbers")
        offsets = offset if isinstance(offset, list) else [offset, offset]
        self.encoder_offset = [math.radians(number(f"sensors.encoder_offset_deg[{i}]", v)) for i, v in enumerate(offsets)]
        self.gyro_noise = np.radians(non_negative("sensors.gyro_noise_deg_s", spec.get("gyro_noise_deg_s", 0.0)))
        self.imu_noise = np.radians(non_negative("sensors.imu_attitude_noise_deg", spec.get("imu_attitude_noise_deg", 0.0)))
        self.scheme = choice("sensors.stabilization", spec.get("stabilization", "direct"), SCHEMES)
        self.joint_rate = choice("sensors.joint_rate", spec.get("joint_rate", "tachometer"), JOINT_RATES)
        gyro_spec = spec.get("gyro")
        if gyro_spec is not None and not isinstance(gyro_spec, dict):
            raise SceneError(f"[sensors] gyro must be a table ([sensors.gyro]), got {shown(gyro_spec)}")
        self.gyro = None if gyro_spec is None else GyroModel(gyro_spec)
        self.seed = integer("sensors.seed", spec.get("seed", 0), 0)
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

    def stream(self, count: int, h: float) -> "SensorStream":
        """prepare, a chunk at a time: SensorStream.rows(first, base) for consecutive chunks."""
        return SensorStream(self, count, h)

    def measure(self, step: int, alpha: float, beta: float, gyro: list, alpha_dot: float = 0.0,
                beta_dot: float = 0.0):
        """(alpha, beta, [w1, w2, w3]) as measured at communication point `step` (after prepare) from
        the FMU's alpha, beta, los.omega and, for indirect stabilization, alpha_dot and beta_dot."""
        measured = self._measured
        measured[0], measured[1], measured[2:5], measured[5], measured[6] = alpha, beta, gyro, alpha_dot, beta_dot
        native.kernel().gimbal_sensors_measure(ctypes.addressof(self.state), step, measured)
        return measured[0], measured[1], measured[2:5]


# Rows of the generators' draws skipped at a time while positioning a stream (bounds the memory).
SKIP_ROWS = 1 << 16


def _shifted(array: np.ndarray, first: int) -> int:
    """The address row 0 of the run would have if `array` (a chunk's rows, its row 0 the run's row
    `first`) were part of a table of the whole run: the C kernel indexes its tables by the run's step
    k, and this lets it read a chunk's rows at k = first .. first + len - 1 without copies."""
    address = array.ctypes.data - first * array.strides[0]
    if address <= 0:
        raise MemoryError("a chunk's rows cannot be addressed by the run's step")
    return address


class SensorStream:
    """What Sensors.prepare makes for a whole run (the noise tables, the IMU's attitude, the carrier
    gyro's readings), made a chunk at a time for a run streamed to disk (master/streaming.py): the
    same bits, in memory bounded by the chunk. Each random draw of prepare (in its fixed order) gets a
    generator positioned at its start, found by drawing the draws before it and dropping them."""

    def __init__(self, sensors: "Sensors", count: int, h: float):
        self.sensors, self.h, self.count = sensors, h, count
        draws = []   # (rows, standard deviation) of prepare's draws, in order
        if sensors.gyro_noise > 0:
            draws.append((count, sensors.gyro_noise))
        if sensors.imu_noise > 0:
            draws.append((count, sensors.imu_noise))
        gyro_draws = error_draws(sensors.gyro, h, count) if sensors.gyro is not None else []
        draws += gyro_draws
        rng = np.random.default_rng(sensors.seed)
        self.starts = []   # the bit generator's state at the start of each draw
        for rows, deviation in draws:
            self.starts.append(rng.bit_generator.state)
            for first in range(0, rows, SKIP_ROWS):
                rng.normal(0.0, deviation, (min(SKIP_ROWS, rows - first), 3))
        index = 0
        self.gyro_noise = self.imu = None
        if sensors.gyro_noise > 0:
            self.gyro_noise, index = self._generator(index), index + 1
        if sensors.imu_noise > 0:
            self.imu, index = self._generator(index), index + 1
        state = sensors.state
        state.h = h
        self.errors = None
        if sensors.gyro is not None:
            if not h > 0:
                raise SceneError("sensors: the gyro model needs the communication step")
            sensors.gyro.configure_deterministic(state.gyro, h)   # the error table: per chunk
            self.errors = GyroErrorStream(sensors.gyro, h, lambda draw: self._generator(index + draw))
        self.indirect = sensors.scheme == "indirect"
        if self.indirect:
            # the carrier gyro: its own copy of the configured gyro (filter and delay states run on
            # over the chunks); the payload gyro is off
            self.carrier_gyro = type(state.gyro).from_buffer_copy(state.gyro) if sensors.gyro is not None else None
            state.gyro.enabled = 0
        self.previous_base = None   # the last base row of the chunk before (indirect: carrier_rate's h form)
        self._kept = []

    def _generator(self, index: int) -> np.random.Generator:
        bits = np.random.PCG64()
        bits.state = self.starts[index]
        return np.random.Generator(bits)

    def rows(self, first: int, base: np.ndarray) -> np.ndarray:
        """Makes rows first .. first + len(base) - 1 (base: the base motion's rows there) and points the
        sensors' kernel state at them; returns the attitude the IMU measures there."""
        count, state = len(base), self.sensors.state
        kept = []
        if self.gyro_noise is not None:
            noise = self.gyro_noise.normal(0.0, self.sensors.gyro_noise, (count, 3))
            kept.append(noise)
            state.gyro_noise = _shifted(noise, first)
        measured_attitude = base[:, :3] + self.imu.normal(0.0, self.sensors.imu_noise, (count, 3)) \
            if self.imu is not None else base[:, :3]
        errors = self.errors.rows(count) if self.errors is not None else None
        if errors is not None:
            kept.append(errors)
        if self.indirect:
            if base.shape[1] < 9:
                raise SceneError("sensors: indirect stabilization needs the base attitude, rates and accelerations")
            with_previous = base if self.previous_base is None else np.concatenate([self.previous_base, base])
            readings = np.ascontiguousarray(carrier_rate(with_previous, self.h)[len(with_previous) - count:])
            if self.carrier_gyro is not None:
                gyro = self.carrier_gyro
                gyro.error = None if errors is None else _shifted(errors, first)
                measure, row_bytes = native.kernel().gimbal_gyro_measure, readings.strides[0]
                for k in range(count):
                    address = readings.ctypes.data + k * row_bytes
                    measure(ctypes.addressof(gyro), first + k, address, address)
            kept.append(readings)
            state.carrier_rate = _shifted(readings, first)
        elif errors is not None:
            state.gyro.error = _shifted(errors, first)
        self.previous_base = base[-1:].copy()
        self._kept = kept   # the kernel reads these until the next chunk
        return measured_attitude
