"""The C kernel (c_kernel/, imported as gimbal2axis.native) against independent plain-Python references of the same
equations, written out here: the built-in controllers (PID with every term, state feedback with
gyro and encoder rates), the sensors, the prepared set points' 2 pi branch, the sums of sinusoids.
The Python side sets the kernel's structs through the ctypes view it builds from the kernel's
layout table, so a field placed at another offset than C's would change the numbers and fail here.

The references are the arithmetic the Python loop had before the kernel took it over, operation for
operation: the kernel must give their bits (the golden digests were recorded with it)."""
import ctypes
import math

import numpy as np
import pytest

from gimbal2axis import native
from gimbal2axis.scene.controllers import PID, Controller, Replay, StateFeedback
from gimbal2axis.scene.sensors import Sensors


class ReferenceAxisPID:
    def __init__(self, kp, ki, kd, k_gyro, k_ff, tau, i_limit, u_limit):
        self.kp, self.ki, self.kd, self.k_gyro, self.k_ff = kp, ki, kd, k_gyro, k_ff
        self.tau, self.i_limit, self.u_limit = tau, i_limit, u_limit
        self.integral, self.e_prev, self.d, self.saturated = 0.0, None, 0.0, 0

    def __call__(self, e, rate, h, ref_rate):
        if self.e_prev is not None:
            raw = (e - self.e_prev) / h
            self.d += (h / (self.tau + h)) * (raw - self.d)
        self.e_prev = e
        if self.ki != 0.0 and not (self.saturated * e > 0):
            self.integral += e * h
            if abs(self.ki * self.integral) > self.i_limit:
                self.integral = math.copysign(self.i_limit / abs(self.ki), self.integral)
        u = self.kp * e + self.ki * self.integral + self.kd * self.d - self.k_gyro * rate + self.k_ff * ref_rate
        self.saturated = 1 if u > self.u_limit else -1 if u < -self.u_limit else 0
        return min(max(u, -self.u_limit), self.u_limit)


def reference_gyro_rates(gyro, beta):
    return gyro[2] / max(math.cos(beta), 0.2), gyro[0]


class ReferenceStateFeedback:
    def __init__(self, K, ki, u_limit, encoder_rates):
        self.K, self.ki, self.u_limit, self.encoder_rates = K, ki, u_limit, encoder_rates
        self.integral, self.prev = [0.0, 0.0], None

    def __call__(self, h, alpha, beta, gyro, r1, r2):
        if self.encoder_rates:
            w_az, w_el = (0.0, 0.0) if self.prev is None else ((alpha - self.prev[0]) / h, (beta - self.prev[1]) / h)
            self.prev = (alpha, beta)
        else:
            w_az, w_el = reference_gyro_rates(gyro, beta)
        x = (alpha - r1, beta - r2, w_az, w_el)
        u = []
        for i in range(2):
            total = 0.0
            for k, xi in zip(self.K[i], x):
                total = total + k * xi
            v = -total + self.ki[i] * self.integral[i]
            limited = min(max(v, -self.u_limit[i]), self.u_limit[i])
            if self.ki[i] != 0.0 and limited == v:
                self.integral[i] += -x[i] * h
            u.append(limited)
        return tuple(u)


def random_signals(seed, steps):
    """Measurements and set points that move enough to saturate, wind up and reverse."""
    rng = np.random.default_rng(seed)
    alpha = np.cumsum(rng.normal(0.0, 0.01, steps))
    beta = 0.3 * np.sin(np.arange(steps) * 0.05) + rng.normal(0.0, 0.002, steps)
    gyro = rng.normal(0.0, 0.5, (steps, 3))
    set_points = np.column_stack([0.2 * np.sign(np.sin(np.arange(steps) * 0.03)), np.full(steps, -0.1),
                                  rng.normal(0.0, 0.3, steps), rng.normal(0.0, 0.3, steps)])
    return alpha.tolist(), beta.tolist(), gyro.tolist(), set_points.tolist()


PID_SPEC = {"azimuth": {"kp": 300.0, "ki": 3000.0, "kd": 2.0, "d_filter_s": 0.002, "i_limit_V": 3.0, "k_gyro": 4.0,
                        "k_ff": 4.8},
            "elevation": {"kp": 120.0, "ki": 50.0, "kd": 1.0, "k_gyro": 4.0},
            "reference": {"type": "constant", "value_deg": 0.0}}


def test_the_kernels_pid_is_the_reference_pid_to_the_bit():
    h, u_limit = 1e-3, (6.0, 24.0)
    controller = PID(PID_SPEC, None, u_limit)
    axes = [ReferenceAxisPID(a.kp, a.ki, a.kd, a.k_gyro, a.k_ff, a.tau, a.i_limit, a.u_limit) for a in controller.axes]
    saturated = 0
    for k, (alpha, beta, gyro, sp) in enumerate(zip(*random_signals(1, 2000))):
        w_az, w_el = reference_gyro_rates(gyro, beta)
        expected = (axes[0](sp[0] - alpha, w_az, h, sp[2]), axes[1](sp[1] - beta, w_el, h, sp[3]))
        got = controller._step(k, h, alpha, beta, gyro, sp)
        assert got == expected, k
        saturated += abs(got[0]) == u_limit[0]
    assert 0 < saturated < 2000   # the limit and the anti-windup were exercised, not only one side
    assert controller.state.axis[0].integral == axes[0].integral and controller.state.axis[0].derivative == axes[0].d


def test_the_kernels_pid_by_hand():
    """Two steps worked out on paper: kp = 2, ki = 10, kd = 0.5 (no filter), k_gyro = 0.25, k_ff = 1."""
    spec = {"azimuth": {"kp": 2.0, "ki": 10.0, "kd": 0.5, "k_gyro": 0.25, "k_ff": 1.0},
            "elevation": {"kp": 1.0}, "reference": {"type": "constant", "value_deg": 0.0}}
    controller = PID(spec, None, (100.0, 100.0))
    h = 0.5
    # step 0: e = 1, integral 0.5, no derivative yet, w_az = gyro[2] / cos(0) = 2: 2 + 5 - 0.5 + 0.75
    u = controller._step(0, h, 0.0, 0.0, (0.0, 0.0, 2.0), (1.0, 0.0, 0.75, 0.0))
    assert u == (7.25, 0.0)
    # step 1: e = 3, integral 0.5 + 1.5 = 2, derivative (3 - 1) / 0.5 = 4: 6 + 20 + 2 - 0 + 0
    u = controller._step(1, h, 0.0, 0.0, (0.0, 0.0, 0.0), (3.0, 0.0, 0.0, 0.0))
    assert u == (28.0, 0.0)


@pytest.mark.parametrize("encoder_rates", [False, True])
def test_the_kernels_state_feedback_is_the_reference_to_the_bit(encoder_rates):
    h, u_limit = 1e-3, (5.0, 24.0)
    spec = {"type": "state_feedback", "K": [[120.0, 3.0, 2.5, 0.1], [-4.0, 200.0, 0.2, 3.0]], "ki": [400.0, 0.0],
            "rate_source": "encoder" if encoder_rates else "gyro", "reference": {"type": "constant", "value_deg": 0.0}}
    controller = StateFeedback(spec, None, u_limit)
    reference = ReferenceStateFeedback(controller.K, controller.ki, u_limit, encoder_rates)
    saturated = 0
    for k, (alpha, beta, gyro, sp) in enumerate(zip(*random_signals(2, 2000))):
        expected = reference(h, alpha, beta, gyro, sp[0], sp[1])
        assert controller._step(k, h, alpha, beta, gyro, sp) == expected, k
        saturated += abs(expected[0]) == u_limit[0]
    assert 0 < saturated < 2000
    assert list(controller.state.state_integral) == reference.integral


def test_prepared_set_points_take_the_azimuths_branch_nearest_the_measured_angle():
    controller = PID({"reference": "target"}, (0.0, 1.0, 0.0), (24.0, 24.0))
    times = np.arange(3) * 1e-3
    controller.prepare(times, 1e-3, np.zeros((3, 3)), np.zeros((3, 3)))
    assert controller.set_points.unwrap == (True, False)
    principal = controller.set_points.values[1, 0]
    for turns in (-2, 0, 1, 3):
        measured = principal + turns * 2 * math.pi + 0.4   # less than half a turn off: this branch
        controller(0.001, 1e-3, measured, 0.0, (0.0, 0.0, 0.0), None, None, step=1)
        assert controller.reference[0] == principal + 2 * math.pi * turns


def test_none_and_replay_give_their_voltages_and_leave_the_reference_alone():
    constant = Controller((1.5, -0.7))
    assert constant(0.0, 1e-3, 0.1, 0.2, (0.0, 0.0, 0.0), None, None, step=5) == (1.5, -0.7)
    rows = np.array([[0.5, -0.25], [3.0, 4.0]])
    replay = Replay(rows)
    assert replay(0.0, 1e-3, 0.0, 0.0, (0.0, 0.0, 0.0), None, None, step=1) == (3.0, 4.0)
    assert all(math.isnan(r) for r in replay.reference)


def test_the_kernels_sensors_quantize_half_to_even_and_add_the_drawn_noise():
    sensors = Sensors({"encoder_resolution_deg": math.degrees(0.5), "gyro_noise_deg_s": 1.0, "seed": 4})
    sensors.prepare(np.zeros((3, 3)))
    assert sensors.state.encoder_resolution == 0.5
    noise = sensors.gyro_noise_table[2].tolist()
    alpha, beta, gyro = sensors.measure(2, 0.75, 0.25, [1.0, 2.0, 3.0])
    assert (alpha, beta) == (1.0, 0.0)   # 1.5 and 0.5 steps: to the even neighbours 2 and 0
    assert gyro == [1.0 + noise[0], 2.0 + noise[1], 3.0 + noise[2]]
    exact = Sensors({})
    exact.prepare(np.zeros((3, 3)))
    assert exact.measure(1, 0.123, -0.456, [0.1, 0.2, 0.3]) == (0.123, -0.456, [0.1, 0.2, 0.3])


def test_the_kernels_sum_of_sines_in_pieces_is_the_whole_grid_and_the_formula():
    """Rows asked for a few at a time (the benchmark driver's way) give the whole grid's bits; both
    within 1e-13 of the direct formula."""
    kernel = native.kernel()
    pointer, long, double = ctypes.c_void_p, ctypes.c_long, ctypes.c_double
    kernel.gimbal_sum_of_sines_rotation_doubles.argtypes, kernel.gimbal_sum_of_sines_rotation_doubles.restype = [long], long
    kernel.gimbal_sum_of_sines_rotation.argtypes = [double, long, pointer, pointer]
    kernel.gimbal_sum_of_sines_rows.argtypes = [long, long, double, double, long] + [pointer] * 7
    rng = np.random.default_rng(5)
    components, rows, t0, h = 7, 1000, 0.25, 1e-3
    amplitude, omega, phase = rng.uniform(0.1, 1.0, components), rng.uniform(0.3, 6.0, components), \
        rng.uniform(0.0, 2 * math.pi, components)
    weights = np.empty(3 * components)
    kernel.gimbal_sum_of_sines_weights(components, amplitude.ctypes.data, omega.ctypes.data, weights.ctypes.data)
    np.testing.assert_array_equal(weights, np.concatenate([amplitude, amplitude * omega, -amplitude * omega**2]))
    whole = np.empty((3, rows))
    assert kernel.gimbal_sum_of_sines(rows, t0, h, components, omega.ctypes.data, phase.ctypes.data,
                                      weights.ctypes.data, *(whole[i].ctypes.data for i in range(3))) == 0
    rotation = np.empty(kernel.gimbal_sum_of_sines_rotation_doubles(components))
    kernel.gimbal_sum_of_sines_rotation(h, components, omega.ctypes.data, rotation.ctypes.data)
    pieces = np.empty((3, rows))
    for first in range(0, rows, 37):   # pieces across block boundaries
        count = min(37, rows - first)
        kernel.gimbal_sum_of_sines_rows(first, count, t0, h, components, omega.ctypes.data, phase.ctypes.data,
                                        weights.ctypes.data, rotation.ctypes.data,
                                        *(pieces[i, first:].ctypes.data for i in range(3)))
    np.testing.assert_array_equal(pieces, whole)
    arg = np.outer(t0 + np.arange(rows) * h, omega) + phase
    direct = (np.sin(arg) @ amplitude, np.cos(arg) @ (amplitude * omega), np.sin(arg) @ (-amplitude * omega**2))
    for got, expected in zip(whole, direct):
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-13 * np.max(np.abs(expected)) * components)


def test_the_ctypes_view_is_the_kernels_layout():
    """Every field of the kernel's table at its offset in the view, every struct its sizeof."""
    kernel = native.kernel()
    rows = native._layout_rows(kernel)
    assert {"GimbalMasterLoop", "GimbalController", "GimbalAxisPid", "GimbalSensors", "GimbalSetPoints"} <= set(rows)
    for name, fields in rows.items():
        view = native.struct(name)
        assert ctypes.sizeof(view) == kernel.gimbal_layout_size(name.encode())
        for field, offset, kind, count in fields:
            assert getattr(view, field).offset == offset, (name, field)
    assert kernel.gimbal_layout_size(b"NoSuchStruct") == -1
    assert [kernel.gimbal_controller_kind(kind.encode()) for kind in ("none", "pid", "state_feedback", "replay")] \
        == [0, 1, 2, 3]
    assert kernel.gimbal_controller_kind(b"python") == -1
