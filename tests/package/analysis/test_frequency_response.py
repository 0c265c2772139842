"""Frequency responses by sine dwell (gimbal2axis.analysis.frequency_response) against a known linear case, and the
backlash's describing-function gain drop."""
import cmath
import math
import pathlib
import warnings

import numpy as np
import pytest

from gimbal2axis import load_scene
from gimbal2axis.analysis.frequency_response import Dwell, Excitation, fundamental, measure_point, zoh_fundamental

pytestmark = [pytest.mark.python_bound, pytest.mark.dask_workers]

REPO = pathlib.Path(__file__).resolve().parents[3]

SCENE = """
name = "frequency_response_test"
stop_time = 1.0
step_size = 1e-3

[fidelity]
{models}
dry_friction = false
"base.fixed" = true

[parameters]
"solver.rtol" = 1e-9
"solver.atol" = 1e-11
# the payload's centre of mass on the elevation axis: no gravity torque, the elevation axis stays at rest
"body2.d_bd[2]" = 0.0
"body2.d_bd[3]" = 0.0

[base_motion]
type = "fixed"

[controller]
type = "none"
"""


def scene_file(tmp_path, gear1: int):
    """The test scene (no controller: its SceneWarning is expected and silenced)."""
    path = tmp_path / f"fr_gear{gear1}.toml"
    path.write_text(SCENE.format(models=f'"gear1.model" = {gear1}\n"motor1.model" = 0'))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_scene(path)


def value(fmu, scene, name):
    return float(scene.parameters.get(name, fmu.start(name)))


def test_single_bin_dft_and_zero_order_hold():
    h, f = 1e-3, 12.5
    t = np.arange(400) * h                       # 5 whole periods
    x = 0.3 + 2.0 * np.sin(2 * math.pi * f * t + 0.4) + 0.5 * np.sin(2 * math.pi * 3 * f * t)
    X = fundamental(x, t, f)
    assert abs(X - 2.0 * cmath.exp(1j * (0.4 - math.pi / 2))) < 1e-12
    # a staircase of the samples: its continuous fundamental lags by w h / 2 and shrinks by sinc
    Z = zoh_fundamental(1.0, f, h)
    assert math.isclose(cmath.phase(Z), -math.pi * f * h, rel_tol=1e-12)
    assert math.isclose(abs(Z), math.sin(math.pi * f * h) / (math.pi * f * h), rel_tol=1e-12)


def test_rigid_axis_with_quasi_static_motor_matches_first_order_transfer_function(gimbal_fmu, tmp_path):
    """Azimuth axis with a rigid gear (gear1.model = 0) and a quasi-static motor (motor1.model = 0), no dry
    friction, fixed level base, elevation at rest at beta = 0 (its centre of mass on its axis).

    With q_m = N alpha (docs/physics.md section 6) the rotor's equation, multiplied by N, adds to the load's:
        (J11 + N^2 J_R1) alpha'' = N T_ele - (c_1 + N^2 c_R1) alpha'
    (J12 = 0: rotor 1 turns on the carrier, its stator is not on body 1), and the quasi-static current is
    i = (u - k_emf N alpha') / R, T_ele = k_torque i. So
        G(s) = alpha'(s) / u(s) = (N k_t / R) / (J s + c + N^2 k_t k_e / R)
    with J = J11 + N^2 I_zz,R1 and c = c_1 + N^2 c_R1: the motor constants reflected to the load by N.
    J11 at alpha = beta = 0 about the azimuth axis through b: the z-z inertias of body 1, body 2 and rotor 2
    (all frames aligned at q = 0) plus m (d_x^2 + d_y^2) of their centres of mass (parallel axes). The
    products of inertia couple the elevation axis only to second order in the small amplitude."""
    scene = scene_file(tmp_path, gear1=0)
    fmu = gimbal_fmu
    v = lambda name: value(fmu, scene, name)
    N, R, kt, ke = v("gear1.N"), v("motor1.R"), v("motor1.k_torque"), v("motor1.k_emf")
    J11 = (v("body1.I_zz") + v("body1.m") * (v("body1.d_bc[1]") ** 2 + v("body1.d_bc[2]") ** 2)
           + v("body2.I_zz") + v("body2.m") * (v("body2.d_bd[1]") ** 2 + v("body2.d_bd[2]") ** 2)
           + v("rotor2.I_zz") + v("rotor2.m") * (v("rotor2.d_bf[1]") ** 2 + v("rotor2.d_bf[2]") ** 2))
    J = J11 + N ** 2 * (v("rotor1.I_zz") + v("rotor1.m") * (v("rotor1.d_be[1]") ** 2 + v("rotor1.d_be[2]") ** 2))
    c = v("body1.c_visc") + N ** 2 * v("rotor1.c_visc")
    amplitude = 1.0   # V: |i| <= amplitude / R = 0.5 A, far below i_L; far below U_L
    for f in (0.5, 2.0, 6.0, 25.0):
        rows = measure_point(scene, fmu, f, Excitation("voltage", "1", amplitude),
                             Dwell(settle_periods=2, settle_s=0.25, measure_periods=2), outputs=["alpha_dot"])
        row = rows[0]
        w = 2 * math.pi * row["frequency_hz"]
        G = (N * kt / R) / (J * 1j * w + c + N ** 2 * kt * ke / R)
        assert row["current_limited_fraction"] == 0.0
        assert row["gain"] == pytest.approx(abs(G), rel=0.01), f
        assert abs(row["phase_deg"] - math.degrees(cmath.phase(G))) < 1.0, f
        assert row["coherence"] > 0.999


def play_operator_describing_function(X: float, eta: float) -> complex:
    """The describing function of the ideal backlash (play operator, half-width eta) for an input X sin(w t):
    the output stays where it was left until the input takes up the play, then follows it at -+eta."""
    n = 4000
    t = np.arange(n) / n * 2.0
    x = X * np.sin(2 * math.pi * t)
    y, last = np.zeros(n), 0.0
    for k in range(n):
        last = min(max(last, x[k] - eta), x[k] + eta)
        y[k] = last
    second = slice(n // 2, n)   # the second period: periodic
    return fundamental(y[second], t[second], 1.0) / fundamental(x[second], t[second], 1.0)


def test_backlash_lowers_the_gain_where_the_motion_is_comparable_to_the_play(gimbal_fmu, tmp_path):
    """Describing function: a backlash of half-width eta between the gear output theta_1 = alpha_m / N and the
    load, with a load that stays where the drive leaves it, is the play operator. For an input X sin(w t) its
    describing function has a gain -> 1 and no lag for X >> eta (the play is taken up in a small part of each
    period), and for X of the order of eta the load moves during only part of each half period: the gain of
    the fundamental falls towards 0 as X -> eta, with a growing phase lag (about 0.86 and -15 deg at
    X = 4.4 eta, 0.63 and -30 deg at 2.1 eta, 0 at X <= eta; play_operator_describing_function).

    The test measures u_R1 -> alpha_dot with the compliant gear with backlash (gear1.model = 2) over the
    same gear without it (gear1.model = 1), with a small voltage amplitude, at frequencies where the load
    angle's amplitude X (linear case) is about 9, 2 and 1 eta. The load's viscous friction is raised to
    body1.c_visc = 10 N.m.s/rad (time constant J11 / c_1 = 20 ms) so that the load stops in the gap, as the
    play operator assumes. Expected: the gain ratio below 1, falling with X / eta, with a drop 1 - ratio
    between 0.2 and 1 times the play operator's (smaller than the ideal element's because the motor, unloaded
    in the gap, speeds up and the gear output's amplitude grows), and a phase lag.

    (With the default, lightly damped load, c_1 = 0.05, time constant 4 s, the load coasts across the gap
    instead: the gain hardly drops at X >~ eta, only the lag appears, and for X < eta the load rattles
    between the flanks and its rate's fundamental even exceeds the linear one.)"""
    fmu = gimbal_fmu
    excitation = Excitation("voltage", "1", 0.05)
    dwell = Dwell(settle_periods=3, settle_s=0.5, measure_periods=2)
    eta = float(fmu.start("gear1.eta"))
    scenes = {}
    for model in (1, 2):
        scene = scene_file(tmp_path, model)
        scenes[model] = scene.with_changes(parameters={**scene.parameters, "body1.c_visc": 10.0})
    ratios, amplitudes, lags, expected = [], [], [], []
    for f in (0.5, 2.0, 4.0):
        linear = measure_point(scenes[1], fmu, f, excitation, dwell, outputs=["alpha_dot"])[0]
        play = measure_point(scenes[2], fmu, f, excitation, dwell, outputs=["alpha_dot"])[0]
        assert play["current_limited_fraction"] == 0.0
        ratios.append(play["gain"] / linear["gain"])
        lags.append(play["phase_deg"] - linear["phase_deg"])
        amplitudes.append(linear["output_amplitude"] / (2 * math.pi * linear["frequency_hz"]) / eta)
        expected.append(abs(play_operator_describing_function(amplitudes[-1] * eta, eta)))
    print("X/eta", amplitudes, "gain ratio", ratios, "play operator", expected, "lag", lags)
    assert amplitudes[0] > 6 and 1.5 < amplitudes[1] < 3 and 0.7 < amplitudes[2] < 1.3
    assert 0.95 < ratios[0] <= 1.0
    assert ratios[2] < ratios[1] < ratios[0]
    for ratio, ideal in zip(ratios, expected):
        assert 0.2 * (1 - ideal) < 1 - ratio < 1 - ideal + 0.01
    assert lags[2] < lags[1] < lags[0] < 0
    assert lags[1] < -8.0


def test_sweep_on_dask_equals_the_serial_sweep(client, fmu_path):
    """The frequencies of a closed-loop isolation sweep run as Dask tasks give the serial sweep's rows."""
    from gimbal2axis.analysis.frequency_response import LINEAR_FIDELITY, sweep

    scene = load_scene(REPO / "scenes" / "ship_stabilization.toml")
    excitation = Excitation("base", "pitch", math.radians(1.0))
    dwell = Dwell(settle_periods=2, settle_s=0.2, measure_periods=2)
    frequencies = [20.0, 50.0]
    serial = sweep(scene, fmu_path, frequencies, excitation, dwell, fidelity=LINEAR_FIDELITY, curve="linear")
    parallel = sweep(scene, fmu_path, frequencies, excitation, dwell, fidelity=LINEAR_FIDELITY, client=client,
                     curve="linear")
    assert [(r["output"], r["frequency_hz"]) for r in serial] == [(r["output"], r["frequency_hz"]) for r in parallel]
    assert [r["output"] for r in serial[:3]] == ["los.omega[1]", "los.omega[3]", "los"]
    for a, b in zip(serial, parallel):
        assert a["gain"] == pytest.approx(b["gain"], rel=1e-12)
    los = serial[2]
    assert los["gain"] == pytest.approx(math.hypot(serial[0]["gain"], serial[1]["gain"]))


def test_command_writes_a_csv_row_per_point_and_a_bode_plot(fmu_path, tmp_path):
    import csv
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "gimbal2axis", "freqresp", "isolation", "--axis", "yaw",
                          "--fmin", "30", "--fmax", "60", "--points", "2", "--settle-periods", "2", "--settle-s", "0.1",
                          "--measure-periods", "2", "--serial", "--fmu", str(fmu_path), "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=300, cwd=REPO)
    assert out.returncode == 0, out.stderr
    rows = list(csv.DictReader(open(tmp_path / "frequency_response_isolation_yaw.csv")))
    # (2 variants + the linear prediction) x 2 frequencies x (los.omega[1], los.omega[3], los)
    assert len(rows) == 18
    assert {r["curve"] for r in rows} == {"full model", "no backlash, no dry friction", "linear model"}
    simulated = {r["frequency_hz"] for r in rows if r["curve"] == "full model"}
    assert {r["frequency_hz"] for r in rows if r["curve"] == "linear model"} == simulated
    assert all(r["input"] == "base.psi_dot" for r in rows)
    assert (tmp_path / "frequency_response_isolation_yaw.png").stat().st_size > 10000


@pytest.mark.parametrize("axis", ["1", "2"])
def test_simulated_response_matches_the_linear_model_from_0p1_to_100_hz(gimbal_fmu, tmp_path, axis):
    """Compliant gears without backlash, no dry friction, inductive motors (both gear resonances, 84 and
    122 Hz, and the current poles, 150-260 Hz, inside or near the band), a small voltage (0.5 V): the sine
    dwell of the nonlinear FMU against the linear model's G(j w) = C (j w I - A)^-1 B + D from the core
    (gimbal2axis.analysis.linearization), 1 % in gain and 1 deg in phase, 0.1-100 Hz, u_R<axis> -> the axis rate and
    the line-of-sight rate it moves. (Measured: within 5e-5 and 0.003 deg; against the sampled-data form of
    the same model, held_frequency_response, within 1e-7: what is left is the hold's aliasing.)"""
    from gimbal2axis.analysis import linearization
    from gimbal2axis.analysis.frequency_response import LINEAR_FIDELITY, linear_point, linear_rows

    path = tmp_path / "fr_linear.toml"
    path.write_text(SCENE.format(models='"gear1.model" = 1\n"gear2.model" = 1'))   # inductive motors
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(path)
    excitation = Excitation("voltage", axis, 0.5)
    model = linearization.linearize(linear_point(scene, gimbal_fmu, excitation, LINEAR_FIDELITY))
    assert model.modes["gear1.contact"] == 0 and model.modes["rotor1.friction"] == "none"
    outputs = ["alpha_dot", "los.omega[3]"] if axis == "1" else ["beta_dot", "los.omega[1]"]
    rows = []
    for f in (0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 60.0, 100.0):
        rows += measure_point(scene, gimbal_fmu, f, excitation, Dwell(settle_periods=3, settle_s=1.5, measure_periods=2),
                              outputs=outputs)
    predicted = {(r["output"], r["frequency_hz"]): r for r in linear_rows(model, rows)}
    assert len(predicted) == len(rows)
    for row in rows:
        linear = predicted[(row["output"], row["frequency_hz"])]
        where = f"{row['output']} at {row['frequency_hz']:.3g} Hz"
        assert row["gain"] == pytest.approx(linear["gain"], rel=0.01), where
        assert abs((row["phase_deg"] - linear["phase_deg"] + 180) % 360 - 180) < 1.0, where
        held = model.held_frequency_response([row["frequency_hz"]], row["input"], row["output"], scene.step_size)[0]
        assert abs(row["gain"] * cmath.exp(1j * math.radians(row["phase_deg"])) - held) < 1e-5 * abs(held), where


def test_open_loop_command_adds_the_linear_models_curve(fmu_path, build_dir, tmp_path):
    import csv
    import os
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "gimbal2axis", "freqresp", "open-loop", "--axis", "2",
                          "--fmin", "5", "--fmax", "10", "--points", "2", "--settle-periods", "2", "--settle-s", "0.1",
                          "--measure-periods", "2", "--serial", "--fmu", str(fmu_path), "--out", str(tmp_path),
                          "--set", "body2.d_bd[2]=0", "--set", "body2.d_bd[3]=0"],
                         capture_output=True, text=True, timeout=300, cwd=REPO,
                         env={**os.environ, "GIMBAL2AXIS_PROBE_LIBRARY": str(build_dir / "libgimbal_probe.so")})
    assert out.returncode == 0, out.stderr
    rows = list(csv.DictReader(open(tmp_path / "frequency_response_open_loop_2.csv")))
    # (2 variants + the linear model) x 2 frequencies x (beta_dot, los.omega[1])
    assert len(rows) == 12
    # the summary counts frequencies as frequencies, rows as rows
    assert out.stdout.splitlines()[-1].startswith("2 frequencies x 2 simulated curves (12 CSV rows"), out.stdout
    assert {r["curve"] for r in rows} == {"full model", "no backlash, no dry friction", "linear model"}
    linear = {(r["output"], r["frequency_hz"]): float(r["gain"]) for r in rows if r["curve"] == "linear model"}
    simulated = {(r["output"], r["frequency_hz"]): float(r["gain"]) for r in rows
                 if r["curve"] == "no backlash, no dry friction"}
    assert linear.keys() == simulated.keys()
    for key, gain in simulated.items():
        assert gain == pytest.approx(linear[key], rel=0.01), key


def test_several_amplitudes_give_a_curve_each(fmu_path, tmp_path):
    import csv
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "gimbal2axis", "freqresp", "open-loop", "--axis", "1",
                          "--fmin", "5", "--fmax", "5", "--points", "1", "--settle-periods", "2", "--settle-s", "0.1",
                          "--measure-periods", "2", "--serial", "--fmu", str(fmu_path), "--out", str(tmp_path),
                          "--amplitude", "0.5", "2", "--full-only", "--no-linear"],
                         capture_output=True, text=True, timeout=300, cwd=REPO)
    assert out.returncode == 0, out.stderr
    rows = list(csv.DictReader(open(tmp_path / "frequency_response_open_loop_1.csv")))
    assert {r["curve"] for r in rows} == {"full model, 0.5 V", "full model, 2 V"} and len(rows) == 4
    amplitude = {r["curve"]: float(r["input_amplitude"]) for r in rows}
    # the continuous fundamental of the held sine: the amplitude times the hold's sinc (5 Hz, 1 ms: 0.99959)
    assert amplitude["full model, 2 V"] == pytest.approx(4 * amplitude["full model, 0.5 V"], rel=1e-9)
    assert amplitude["full model, 0.5 V"] == pytest.approx(0.5, rel=1e-3)


@pytest.mark.parametrize("args, message", [
    (["isolation", "--axis", "sideways"], "roll, pitch or yaw"),
    (["open-loop", "--fmin", "0"], "need 0 < fmin <= fmax"),
    (["isolation", "--amplitude", "0"], "need a positive amplitude"),
    (["open-loop", "--fmax", "474"], "resolves, 250 Hz: a dwell needs at least 4 steps per period"),
    (["open-loop", "--set", "body2.d_bd[4]=0"], "--set: 'body2.d_bd[4]' is not a variable"),
])
def test_command_refusals_name_the_culprit_without_a_traceback(fmu_path, tmp_path, args, message):
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "gimbal2axis", "freqresp", *args, "--serial",
                          "--fmu", str(fmu_path), "--out", str(tmp_path)], capture_output=True, text=True, timeout=300,
                         cwd=REPO)
    assert out.returncode == 2
    assert message in out.stderr and "Traceback" not in out.stderr, out.stderr
    assert out.stderr.startswith("gimbal2axis freqresp: error: ") and len(out.stderr.splitlines()) == 1, out.stderr
