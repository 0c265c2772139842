"""The analyses check themselves (issue 34): linearize warns where a requested transfer function is
identically zero because of a held mode and its --help example gives the picture it promises; freqresp
refuses frequencies its step cannot resolve and its coherence is a fraction; both refuse a bad argument
in one line with exit status 2."""
import math
import pathlib
import shlex
import subprocess
import sys

import numpy as np
import pytest

from gimbal2axis.analysis import frequency_response as fr
from gimbal2axis.analysis import linearization
from test_linearization import reflected_inertia_and_damping

REPO = pathlib.Path(__file__).resolve().parents[3]


def gimbal2axis(*args, cwd=REPO):
    return subprocess.run([sys.executable, "-m", "gimbal2axis", *args], capture_output=True, text=True, timeout=300,
                          cwd=cwd)


def help_example(command: str) -> list[str]:
    """The arguments of the first example in `gimbal2axis linearize --help` that starts with `command`
    (its continuation lines joined), as printed to the user."""
    from gimbal2axis.cli import linearize as linearize_command

    lines = linearize_command.__doc__.splitlines()
    start = next(k for k, line in enumerate(lines) if line.strip().startswith(command))
    text = ""
    for line in lines[start:]:
        text += line.strip().rstrip("\\") + " "
        if not line.rstrip().endswith("\\"):
            break
    return shlex.split(text)[2:]   # without "gimbal2axis linearize"


def test_help_example_is_the_first_order_azimuth_axis(build_dir, gimbal_fmu, tmp_path):
    """The --help example, run as printed (only --out moved to tmp_path): no warning, and u_R1 -> alpha_dot
    has the DC gain and pole of the hand-derived first-order model of a rigid axis with a quasi-static
    motor, G = (N k_t / R) / (J s + c + N^2 k_t k_e / R), J the load's inertia plus N^2 the rotor's
    (docs/linearization.md). The elevation side's products of inertia stay at their defaults here and
    couple the axes at second order: measured 1e-9 in gain and 3e-6 in the pole; the bar is 1e-3."""
    args = help_example("gimbal2axis linearize --set gear1.model=0")
    assert "dry_friction=false" in args and "base.fixed=true" in args and "u_R1:alpha_dot" in args
    out_index = args.index("--out") + 1
    args[out_index] = str(tmp_path / pathlib.Path(args[out_index]).name)
    out = gimbal2axis("linearize", "--build-dir", str(build_dir), *args)
    assert out.returncode == 0, out.stderr
    assert "warning" not in out.stderr, out.stderr
    model = linearization.LinearModel.load(args[out_index])
    values = {name: model.point[name] for name in ("gear1.model", "motor1.model", "dry_friction", "base.fixed")}
    J, c, N, R, kt, ke = reflected_inertia_and_damping(gimbal_fmu, values)
    dc_gain, pole = (N * kt / R) / (c + N ** 2 * kt * ke / R), -(c + N ** 2 * kt * ke / R) / J
    assert dc_gain == pytest.approx(0.2063, rel=1e-3) and pole / (2 * math.pi) == pytest.approx(-4.175, rel=1e-3)
    # the rate's DC gain, read well below the pole (the angle itself is a free integrator: A is singular)
    G = model.frequency_response([1e-3], "u_R1", "alpha_dot")[0]
    assert abs(G) == pytest.approx(dc_gain, rel=1e-3)
    assert np.min(np.abs(model.poles() - pole)) < 1e-3 * abs(pole)
    bode = (tmp_path / "azimuth_bode.csv").read_text().splitlines()[1:]
    gains_db = [float(row.split(",")[4]) for row in bode]
    assert gains_db[0] == pytest.approx(20 * math.log10(dc_gain), abs=0.01) and min(gains_db) > -200


def test_readme_example_without_dry_friction_off_warns_that_the_axis_is_stuck(build_dir, tmp_path):
    """The README's old example: every body's friction stuck, u_R1 -> alpha_dot identically zero (the
    -6000 dB line): one warning line on stderr naming the mode and the settings that free it; exit 0."""
    out = gimbal2axis("linearize", "--build-dir", str(build_dir), "--set", "gear1.model=0", "--set", "motor1.model=0",
                      "--out", str(tmp_path / "azimuth.npz"), "--bode", "u_R1:alpha_dot")
    assert out.returncode == 0, out.stderr
    lines = out.stderr.splitlines()
    assert len(lines) == 1, out.stderr
    assert lines[0].startswith("gimbal2axis linearize: warning: u_R1 -> alpha_dot is identically zero")
    assert "body1.friction = stuck" in lines[0] and "--set dry_friction=false" in lines[0]
    assert "--set alpha_dot=" in lines[0]
    assert (tmp_path / "azimuth_bode.png").is_file()


@pytest.mark.parametrize("values, mode, freed_by", [
    ({"gear1.model": 0, "motor1.model": 0}, "body1.friction = stuck", "--set dry_friction=false"),
    ({"dry_friction": False}, "gear1.contact = 0", "--set gear1.model=1"),
    ({"gear1.model": 0, "motor1.model": 0, "dry_friction": False, "u_R1": 20.0, "motor1.i_L": 1.0},
     "motor1.limited = 1", "motor1.i_L"),
    ({"gear1.model": 0, "dry_friction": False, "u_R1": 30.0}, "motor1.voltage_clamped = 1", "motor1.U_L"),
])
def test_each_held_mode_is_named_with_the_setting_that_frees_it(build_dir, values, mode, freed_by):
    model = linearization.linearize(values, build_dir)
    warning = model.zero_path_warning("u_R1", "alpha_dot")
    assert warning is not None and mode in warning and freed_by in warning, warning
    # and the setting named frees it: the same point with it applied has a path
    freed = {"body1.friction = stuck": {"dry_friction": False}, "gear1.contact = 0": {"gear1.model": 1},
             "motor1.limited = 1": {"motor1.i_L": 20.0}, "motor1.voltage_clamped = 1": {"u_R1": 1.0}}[mode]
    assert linearization.linearize({**values, **freed}, build_dir).zero_path_warning("u_R1", "alpha_dot") is None


def test_a_weak_physical_path_is_not_called_zero(build_dir):
    """u_R1 -> beta_dot exists only through the elevation side's products of inertia (a few 1e-3 of the
    azimuth's own gain): it is not identically zero, and nothing is said."""
    model = linearization.linearize({"gear1.model": 0, "motor1.model": 0, "dry_friction": False, "base.fixed": True},
                                    build_dir)
    weak = abs(model.frequency_response([1.0], "u_R1", "beta_dot")[0])
    assert 0 < weak < 0.1 * abs(model.frequency_response([1.0], "u_R1", "alpha_dot")[0])
    assert model.zero_path_warning("u_R1", "beta_dot") is None
    assert "base.fixed = true" in model.zero_path_warning("base.gamma_dot", "alpha_dot")


@pytest.mark.parametrize("command, args, message", [
    ("linearize", ["--set", "motor1.RR=3"], "'motor1.RR' is not a variable of the gimbal model (did you mean 'motor1.R'"),
    ("linearize", ["--fmax", "x"], "--fmax"),
    ("freqresp", ["open-loop", "--set", "motor1.RR=3"], "(did you mean 'motor1.R'"),
    ("freqresp", ["open-loop", "--fmax", "474"], "--fmax 474 Hz is beyond"),
    ("freqresp", ["isolation", "--fmax", "900"], "would run at 1000 Hz"),
    ("freqresp", ["open-loop", "--points", "x"], "--points"),
])
def test_a_bad_argument_is_refused_in_one_line_with_exit_status_2(build_dir, fmu_path, tmp_path, command, args,
                                                                   message):
    where = ["--build-dir", str(build_dir)] if command == "linearize" else ["--fmu", str(fmu_path), "--serial"]
    out = gimbal2axis(command, *args, *where, "--out", str(tmp_path / ("m.npz" if command == "linearize" else "fr")))
    assert out.returncode == 2, out.stderr
    assert out.stderr.startswith(f"gimbal2axis {command}: error: ") and len(out.stderr.splitlines()) == 1, out.stderr
    assert message in out.stderr, out.stderr
    assert "older than the scene" not in out.stderr   # a --set typo is the command line's, not the scene's
    assert not any(tmp_path.iterdir()), "nothing runs or is written before the refusal"


def test_the_highest_frequency_keeps_four_steps_per_period():
    h = 1e-3
    dwell = fr.Dwell(5.0, 1.0, 4)
    assert fr.highest_frequency(h, dwell) == 250.0
    fr.check_resolvable([250.0], h, dwell)
    f, _, n_measure = fr.snapped_grid(250.0, h, dwell)
    assert f == 250.0 and n_measure == 16
    for requested, snapped in ((260.0, "266.667"), (474.0, "500"), (900.0, "1000")):
        with pytest.raises(fr.SceneError, match=f"would run at {snapped} Hz"):
            fr.snapped_grid(requested, h, dwell)


def test_coherence_is_a_fraction_whatever_the_signal_and_frequency():
    """power_fraction is a projection, so in [0, 1] even where the single-bin DFT is not (at the
    Nyquist frequency |X|^2 / 2 / var is 2 for an alternating sequence, at the sampling frequency it is
    the squared mean over the variance, without bound); on whole periods below Nyquist it is the DFT's."""
    rng = np.random.default_rng(34)
    h = 1e-3
    t = np.arange(8) * h
    alternating = np.cos(math.pi * t / h)
    X = fr.fundamental(alternating, t, 500.0)
    assert abs(X) ** 2 / 2 / np.var(alternating) == pytest.approx(2.0)
    assert fr.power_fraction(alternating, t, 500.0) == pytest.approx(1.0)
    offset_drift = 5.0 + 1e-3 * np.arange(8)
    assert abs(fr.fundamental(offset_drift, t, 1000.0)) ** 2 / 2 / np.var(offset_drift) > 1e6
    assert fr.power_fraction(offset_drift, t, 1000.0) == pytest.approx(0.0, abs=1e-12)
    for _ in range(200):
        n = int(rng.integers(3, 200))
        t = np.arange(n) * h
        f = float(rng.uniform(0.1, 1.2 / h))
        x = rng.normal(size=n) * rng.uniform(0, 3) + rng.uniform(-2, 2) * np.sin(2 * math.pi * f * t + rng.uniform(0, 7))
        assert 0.0 <= fr.power_fraction(x, t, f) <= 1.0
    t = np.arange(40) * h   # 4 periods of 100 Hz: the DFT's fraction, a harmonic taking the rest
    x = 2 * np.sin(2 * math.pi * 100 * t + 0.3) + 0.5 * np.sin(2 * math.pi * 200 * t) + 0.7
    X = fr.fundamental(x, t, 100.0)
    assert fr.power_fraction(x, t, 100.0) == pytest.approx(abs(X) ** 2 / 2 / np.var(x), rel=1e-12)
    assert fr.power_fraction(x, t, 100.0) == pytest.approx(4 / (4 + 0.25), rel=1e-12)


def test_linearize_set_takes_angles_by_the_scene_formats_rule():
    """--set follows docs/scenes.md's rule for angles: NAME_deg is degrees, a bare angle radians, a start
    alpha or beta beyond half a turn refused as the degrees it most likely is (issue 34)."""
    import math

    from gimbal2axis.cli.linearize import parse_assignments
    from gimbal2axis.errors import SceneError

    assert parse_assignments(["beta_deg=30", "alpha=0.25", "gear1.model=0"]) == {
        "beta": math.radians(30.0), "alpha": 0.25, "gear1.model": 0.0}
    for refused, said in ((["beta=30"], "did you mean beta_deg = 30"), (["beta=0.1", "beta_deg=3"], "give one"),
                          (["alpha_deg=270"], "beyond ±180 deg")):
        with pytest.raises(SceneError, match=said):
            parse_assignments(refused)


def test_linearize_refuses_a_degree_sized_radian_angle_in_one_line(tmp_path):
    done = subprocess.run([sys.executable, "-m", "gimbal2axis", "linearize", "--set", "beta=30",
                           "--out", str(tmp_path / "l.npz")], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert "beta = 30 rad (1719 deg)" in done.stderr and not (tmp_path / "l.npz").exists()
