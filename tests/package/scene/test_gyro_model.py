"""The datasheet gyro and the indirect stabilization scheme (gimbal2axis/scene/gyro.py, sensors.py,
c_kernel/src/gyro.c, sensors.c): each term against what it must be by definition, checked by
means the model does not use (allantools' Allan deviation, scipy's continuous-time simulation, the
FMU's own los.omega)."""
import math
import pathlib

import allantools
import numpy as np
import pytest
from scipy import signal

from gimbal2axis import FMU, SceneError, load_scene, run
from gimbal2axis import native
from gimbal2axis.scene.gyro import GyroModel
from gimbal2axis.scene.sensors import Sensors, carrier_rate

pytestmark = pytest.mark.python_bound

DEG_H = math.radians(1.0) / 3600.0


def gyro_output(spec: dict, h: float, rates: np.ndarray, seed: int = 1) -> np.ndarray:
    """The kernel gyro's readings of `rates` (n x 3) sampled at step h."""
    model = GyroModel(spec)
    state = native.struct("GimbalGyro")()
    kept = model.configure(state, h, len(rates), np.random.default_rng(seed))
    out = np.ascontiguousarray(rates, dtype=float).copy()
    native.kernel().gimbal_gyro_series(__import__("ctypes").addressof(state), len(out), out.ctypes.data,
                                       out.ctypes.data)
    del kept
    return out


def fit_allan(tau: np.ndarray, adev: np.ndarray) -> tuple[float, float]:
    """(N [rad/sqrt(s)], B [rad/s]) of sigma^2 = N^2 / tau + (0.664 B)^2, least squares relative to
    each point (IEEE Std 952's white and flicker terms)."""
    design = np.column_stack([1.0 / tau, np.ones_like(tau)]) / adev[:, None] ** 2
    n2, b2 = np.linalg.lstsq(design, np.ones_like(tau), rcond=None)[0]
    return math.sqrt(n2), math.sqrt(b2) / math.sqrt(2.0 * math.log(2.0) / math.pi)


@pytest.mark.parametrize("arw, bias_instability", [(0.15, 5.0), (0.02, 0.5)])
def test_the_allan_deviation_at_rest_gives_back_the_angle_random_walk_and_the_bias_instability(arw, bias_instability):
    h, hours = 0.01, 6.0
    count = int(hours * 3600 / h)
    spec = {"angle_random_walk_deg_rt_h": arw, "bias_instability_deg_h": bias_instability,
            "bias_correlation_time_s": 3000.0}
    readings = gyro_output(spec, h, np.zeros((count, 3)))
    taus = np.logspace(-1, math.log10(600.0), 30)
    estimates = []
    for axis in range(3):
        tau, adev, _, _ = allantools.oadev(readings[:, axis], rate=1.0 / h, data_type="freq", taus=taus)
        estimates.append(fit_allan(tau, adev))
    arw_fit = np.mean([e[0] for e in estimates]) / math.radians(1.0) * 60.0       # deg/sqrt(h)
    bias_fit = np.mean([e[1] for e in estimates]) / DEG_H                         # deg/h
    assert arw_fit == pytest.approx(arw, rel=0.10)
    assert bias_fit == pytest.approx(bias_instability, rel=0.10)
    # and the reading at tau = 1 s is the angle random walk (the flicker floor is far below it)
    tau, adev, _, _ = allantools.oadev(readings[:, 0], rate=1.0 / h, data_type="freq", taus=[1.0])
    assert adev[0] / math.radians(1.0) * 60.0 == pytest.approx(arw, rel=0.10)


def test_the_rate_random_walk_grows_the_allan_deviation_as_sqrt_tau_over_3():
    h, count, k = 0.05, 400_000, 40.0   # deg/h/sqrt(h)
    readings = gyro_output({"rate_random_walk_deg_h_rt_h": k}, h, np.zeros((count, 3)))
    taus = np.array([200.0, 500.0, 1000.0])
    for axis in range(3):
        tau, adev, _, _ = allantools.oadev(readings[:, axis], rate=1.0 / h, data_type="freq", taus=taus)
        expected = k * DEG_H / 60.0 * np.sqrt(tau / 3.0)
        assert np.mean(adev / expected) == pytest.approx(1.0, rel=0.15)


def test_the_bandwidth_filter_is_the_continuous_second_order_low_pass_for_piecewise_linear_rates():
    h, f_n, zeta = 1e-3, 80.0, 0.5
    t = np.arange(0, 0.2, h)
    rate = np.interp(t, [0.0, 0.02, 0.05, 0.2], [0.0, 1.0, -0.5, 0.3])   # linear between samples
    readings = gyro_output({"bandwidth_hz": f_n, "damping": zeta}, h, np.column_stack([rate] * 3))
    w_n = 2 * math.pi * f_n
    _, continuous, _ = signal.lsim(([w_n ** 2], [1.0, 2 * zeta * w_n, w_n ** 2]), rate, t, interp=True)
    # the kernel's filter starts settled on the first sample (0 here, as the continuous one)
    assert np.max(np.abs(readings[:, 1] - continuous)) < 1e-9
    constant = gyro_output({"bandwidth_hz": f_n, "damping": zeta}, h, np.full((50, 3), 0.7))
    assert np.max(np.abs(constant - 0.7)) < 1e-12   # settled from the start, unit gain


def test_scale_factor_misalignment_bias_quantization_and_delay_by_hand():
    spec = {"scale_factor_error_ppm": [1000.0, 0.0, -2000.0], "misalignment_mrad": [1.0, 0.0, 0.0, 0.0, 0.0, -3.0],
            "bias_deg_h": [36.0, 0.0, 0.0], "delay_samples": 3}
    rates = np.array([[1.0, 2.0, 3.0]] + [[0.0, 0.0, 0.0]] * 5)
    readings = gyro_output(spec, 1e-3, rates)
    first = np.array([1.001 * 1.0 + 1e-3 * 2.0 + 36 * DEG_H, 2.0, 0.998 * 3.0 - 3e-3 * 2.0])
    assert np.allclose(readings[:4], first, rtol=0, atol=1e-15)       # delayed 3 samples, the line full of the first
    assert np.allclose(readings[4:], [36 * DEG_H, 0.0, 0.0], rtol=0, atol=1e-15)
    quantized = gyro_output({"quantization_deg_s": 0.01}, 1e-3, np.array([[math.radians(0.0149), 0.0, 0.0]]))
    assert quantized[0, 0] == pytest.approx(math.radians(0.01), abs=1e-18)


def test_the_same_seed_draws_the_same_errors_and_another_seed_others():
    spec = {"angle_random_walk_deg_rt_h": 0.1, "bias_instability_deg_h": 1.0, "rate_random_walk_deg_h_rt_h": 2.0}
    a, b = (gyro_output(spec, 1e-3, np.zeros((1000, 3)), seed=5) for _ in range(2))
    assert np.array_equal(a, b)
    assert not np.array_equal(a, gyro_output(spec, 1e-3, np.zeros((1000, 3)), seed=6))


@pytest.mark.parametrize("spec, message", [
    ({"gyro": {"angle_random_walk": 0.1}}, "unknown key"),
    ({"gyro": {"angle_random_walk_deg_rt_h": -0.1}}, "angle_random_walk_deg_rt_h must be >= 0"),
    ({"gyro": {"bias_correlation_time_s": 0.0}}, "bias_correlation_time_s must be positive"),
    ({"gyro": {"delay_samples": 1.5}}, "delay_samples must be an integer in [0, 16]"),
    ({"gyro": {"delay_samples": 17}}, "delay_samples must be an integer in [0, 16]"),
    ({"gyro": {"misalignment_mrad": 1.0}}, "misalignment_mrad must be a list of 6 numbers"),
    ({"gyro": {"scale_factor_error_ppm": [1.0, 2.0]}}, "scale_factor_error_ppm must be a number or a list of 3"),
    ({"gyro": {"damping": 0.0}}, "damping must be positive"),
    ({"gyro": 3}, "must be a table"),
    ({"stabilization": "inertial"}, "sensors.stabilization must be one of 'direct', 'indirect'"),
    ({"joint_rate": "resolver"}, "sensors.joint_rate must be one of 'tachometer', 'encoder_difference'"),
    ({"encoder_offset_deg": [0.1, 0.2, 0.3]}, "encoder_offset_deg must be a number or [alpha, beta]"),
])
def test_a_wrong_sensor_setting_is_refused_by_name(spec, message):
    with pytest.raises(SceneError, match=None) as refused:
        Sensors(spec)
    assert message in str(refused.value)


@pytest.fixture(scope="module")
def fmu(gimbal_fmu):
    return gimbal_fmu


@pytest.fixture(scope="module")
def ship():
    return load_scene(pathlib.Path(__file__).resolve().parents[3] / "scenes" / "ship_stabilization.toml")


def test_the_carrier_rate_is_the_fmus_kinematics(ship, fmu):
    # The payload rate the FMU reports, rebuilt from the carrier rate the carrier gyro reads (the
    # carrier as the FMU moved it over each step) and the joint angles and rates, by hand.
    result = run(ship.with_changes(sensors_spec={}), fmu, stop_time=2.0)
    s = result.signals
    base = np.column_stack([s[f"base.{name}"] for name in ("delta", "psi", "gamma", "delta_dot", "psi_dot",
                                                           "gamma_dot", "delta_ddot", "psi_ddot", "gamma_ddot")])
    w0 = carrier_rate(base, ship.step_size)
    a, b, a_dot, b_dot = s["alpha"], s["beta"], s["alpha_dot"], s["beta_dot"]
    w1 = np.column_stack([np.cos(a) * w0[:, 0] + np.sin(a) * w0[:, 1], -np.sin(a) * w0[:, 0] + np.cos(a) * w0[:, 1],
                          w0[:, 2] + a_dot])
    w2 = np.column_stack([w1[:, 0] + b_dot, np.cos(b) * w1[:, 1] + np.sin(b) * w1[:, 2],
                          -np.sin(b) * w1[:, 1] + np.cos(b) * w1[:, 2]])
    for j in range(3):
        assert np.max(np.abs(w2[:, j] - s[f"los.omega[{j + 1}]"])) < 1e-12


@pytest.mark.parametrize("fidelity", [{"gear1.model": 0, "gear2.model": 0}, {}], ids=["rigid", "compliant_backlash"])
def test_indirect_stabilization_with_ideal_sensors_is_direct_stabilization(ship, fmu, fidelity):
    scene = ship.with_changes(fidelity={**ship.fidelity, **fidelity})
    direct = run(scene.with_changes(sensors_spec={}), fmu, stop_time=3.0)
    indirect = run(scene.with_changes(sensors_spec={"stabilization": "indirect"}), fmu, stop_time=3.0)
    # the rate fed back differs by the kinematics' rounding (1e-16 rad/s); the loop carries it on
    for name in ("alpha", "beta", "los_error"):
        assert np.max(np.abs(direct.signals[name] - indirect.signals[name])) < 1e-9, name
    assert np.max(np.abs(direct.signals["u_R1"] - indirect.signals["u_R1"])) < 1e-6


def test_every_new_sensor_term_off_gives_todays_bits(ship, fmu):
    ideal = run(ship.with_changes(sensors_spec={}), fmu, stop_time=1.0)
    spelled_out = run(ship.with_changes(sensors_spec={"stabilization": "direct", "encoder_offset_deg": [0.0, 0.0],
                                                      "joint_rate": "tachometer", "gyro": {}}), fmu, stop_time=1.0)
    for name, values in ideal.signals.items():
        assert np.array_equal(values, spelled_out.signals[name], equal_nan=True), name
