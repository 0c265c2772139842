"""Jitter in the frequency domain through the scene runner: the [analysis] table's refusals, the
per-axis line-of-sight errors and the carrier's rate in the payload frame against the FMU's own
outputs, the PSD and isolation files, the band RMS in the summary line and in a sweep table."""
import csv
import math
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from gimbal2axis import FMU, SceneError, load_scene, run
from gimbal2axis.master import run_scene_file
from gimbal2axis.sweep import SweepOptions, run_sweep

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[3]
SHIP = REPO / "scenes" / "ship_stabilization.toml"
JITTER = REPO / "examples" / "ship_jitter.toml"


def scene_with(tmp_path, analysis: str, stop_time: float = 3.0, requirements: str = "los_rms_max_mrad = 0.3\nfrom_s = 1.0"):
    """The ship scene, shortened, with the given [analysis] text in place of its requirements' end."""
    text = SHIP.read_text()
    text = text.replace("stop_time = 60.0", f"stop_time = {stop_time}")
    text = text.replace("los_rms_max_mrad = 0.3\nfrom_s = 1.0", requirements)
    path = tmp_path / "scene.toml"
    path.write_text(text + "\n" + analysis)
    return path


@pytest.mark.parametrize("analysis, message", [
    ("[analysis]\nresolution = 0.5", "[analysis]: unknown key(s) ['resolution']"),
    ("[analysis]\npsd_resolution_hz = -1.0", "analysis.psd_resolution_hz must be positive, got -1.0"),
    ("[analysis]\npsd_resolution_hz = 'fine'", "analysis.psd_resolution_hz must be a finite number, got 'fine'"),
    ("[analysis]\npsd_resolution_hz = 600.0", "is not below the Nyquist frequency 500 Hz"),
    ("[analysis]\npsd_resolution_hz = 0.1", "analysis.psd_resolution_hz = 0.1 Hz needs a window of 10 s"),
    ("[analysis.bands]\nlow = [2.0, 1.0]", "analysis.bands.low = [2, 1]: f_lo must be below f_hi"),
    ("[analysis.bands]\nlow = [1.0, 1.0]", "analysis.bands.low = [1, 1]: f_lo must be below f_hi"),
    ("[analysis.bands]\nlow = [-1.0, 1.0]", "f_lo must be >= 0 Hz"),
    ("[analysis.bands]\nhigh = [10.0, 600.0]", "f_hi is above the Nyquist frequency 500 Hz"),
    ("[analysis.bands]\nlow = [0.0]", "analysis.bands.low must be [f_lo, f_hi] in Hz, got [0.0]"),
    ("[analysis.bands]\nlow = [0.0, 'x']", "analysis.bands.low[1] must be a finite number, got 'x'"),
    ("[analysis]\nbands = [1, 2]", "analysis.bands must be a table"),
])
def test_a_wrong_analysis_table_is_refused_with_one_line_naming_the_key(tmp_path, analysis, message):
    with pytest.raises(SceneError) as caught:
        load_scene(scene_with(tmp_path, analysis))
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_bands_need_a_target(tmp_path):
    path = tmp_path / "free.toml"
    path.write_text((REPO / "scenes" / "free_swing.toml").read_text() + "\n[analysis.bands]\nlow = [0.0, 1.0]\n")
    with pytest.raises(SceneError, match=r"\[analysis.bands\] of the line-of-sight error need a \[target\]"):
        load_scene(path)


def test_the_command_refuses_a_bad_band_with_one_line_and_status_2(tmp_path):
    done = subprocess.run([sys.executable, "-m", "gimbal2axis", "run", str(scene_with(tmp_path, "[analysis.bands]\nx = [3.0, 1.0]")),
                           "--out", str(tmp_path / "out"), "--quiet"], capture_output=True, text=True)
    assert done.returncode == 2 and "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert "analysis.bands.x = [3, 1]: f_lo must be below f_hi" in done.stderr


@pytest.fixture(scope="module")
def ship_run(fmu_path):
    with FMU(fmu_path) as fmu:
        return run(load_scene(SHIP).with_changes(stop_time=3.0), fmu)


def test_per_axis_errors_make_up_the_los_error(ship_run):
    d, s = ship_run.derived, ship_run.signals
    assert np.max(np.abs(np.hypot(d["los_error_xel"], d["los_error_el"]) - s["los_error"])) < 1e-3 * np.max(s["los_error"])
    assert np.std(d["los_error_xel"]) > 0 and np.std(d["los_error_el"]) > 0


def test_the_carrier_rate_in_the_payload_frame_is_the_gyro_minus_the_joint_rates(ship_run):
    # los.omega = 2T1 1T0 omega_0 + [beta', alpha' sin(beta), alpha' cos(beta)] (docs/physics.md 3.1):
    # a wrong rotation order, sign or Euler-rate formula leaves a residual of the carrier's rate (~1e-2 rad/s)
    s, d = ship_run.signals, ship_run.derived
    joints = {1: s["beta_dot"], 2: s["alpha_dot"] * np.sin(s["beta"]), 3: s["alpha_dot"] * np.cos(s["beta"])}
    for i in (1, 2, 3):
        carrier = d[f"base.omega2[{i}]"]
        assert np.max(np.abs(carrier)) > 1e-3
        assert np.max(np.abs(s[f"los.omega[{i}]"] - joints[i] - carrier)) < 1e-6


def test_a_scene_without_analysis_keeps_its_summary_and_signals(ship_run):
    assert "band" not in ship_run.summary()
    assert not set(ship_run.derived) & set(ship_run.signals)


def test_a_scene_file_run_writes_its_spectrum_and_isolation(tmp_path, fmu_path):
    path = scene_with(tmp_path, "[analysis]\nisolation_resolution_hz = 0.5\n[analysis.bands]\n"
                                "low = [0.0, 1.0]\nmid = [1.0, 10.0]\nhigh = [10.0, 500.0]", stop_time=21.0)
    result, csv_path, _ = run_scene_file(path, fmu_path, tmp_path / "out")
    out = tmp_path / "out"
    assert (out / "scene_spectrum.png").stat().st_size > 0
    header = csv_path.read_text().splitlines()[0].split(",")
    assert {"los_error_xel [rad]", "los_error_el [rad]", "base.omega2[1] [rad/s]", "base.omega2[3] [rad/s]"} <= set(header)
    psd = np.genfromtxt(out / "scene_psd.csv", delimiter=",", names=True, skip_header=1)
    assert psd["frequency_hz"][1] == pytest.approx(0.5) and psd["frequency_hz"][-1] == pytest.approx(500.0)
    # the cumulative RMS of both axes at the top is the error's spread (the mean is reported apart); 20 s
    # of window (39 segments): on a few segments the Hann-weighted ends make Welch miss a transient by %
    spread = math.hypot(psd["cumulative_rms_xel_rad"][-1], psd["cumulative_rms_el_rad"][-1])
    window = result.signals["time"] >= 1.0 - 1e-12
    xel, el = result.derived["los_error_xel"][window], result.derived["los_error_el"][window]
    assert spread == pytest.approx(math.hypot(np.std(xel), np.std(el)), rel=0.02)
    iso = np.genfromtxt(out / "scene_isolation.csv", delimiter=",", names=True, skip_header=1)
    assert np.all((iso["elevation_coherence"] >= 0) & (iso["elevation_coherence"] <= 1))
    bands = result.band_rms()
    assert list(bands) == ["low", "mid", "high"]
    total = math.sqrt(sum(v * v for v in bands.values()))
    assert total == pytest.approx(spread, rel=1e-9)   # the bands tile [0, Nyquist]
    summary = result.summary()
    for name, (lo, hi) in (("low", (0, 1)), ("mid", (1, 10)), ("high", (10, 500))):
        assert f"{name} [{lo}, {hi}) Hz {bands[name] * 1e3:.4g} mrad" in summary


def test_a_still_base_writes_no_isolation_and_no_target_no_spectrum(tmp_path, fmu_path):
    run_scene_file(REPO / "scenes" / "free_swing.toml", fmu_path, tmp_path, stop_time=0.2)
    assert not list(tmp_path.glob("free_swing_psd.csv")) and not list(tmp_path.glob("free_swing_isolation.csv"))
    assert not list(tmp_path.glob("free_swing_spectrum.png"))


def test_the_example_scene_loads_with_its_bands():
    settings = load_scene(JITTER).analysis
    assert settings.bands == {"sea": (0.0, 1.0), "loop": (1.0, 10.0), "gears": (10.0, 500.0)}


def test_a_sweep_of_a_scene_with_bands_has_a_column_per_band(tmp_path, fmu_path):
    import pyarrow.parquet as pq

    scene = scene_with(tmp_path, "[analysis.bands]\nlow = [0.0, 20.0]\nhigh = [20.0, 500.0]")
    sweep = tmp_path / "bands.toml"
    sweep.write_text('name = "bands"\nstop_time = 0.3\nmetrics_from_s = 0.1\n[grid]\n"controller.azimuth.kp" = [200.0, 800.0]\n')
    outcome = run_sweep(scene, sweep, fmu_path, tmp_path / "out", SweepOptions(serial=True, progress=False, plot=True))
    table = pq.read_table(outcome.parquet)
    names = table.column_names
    assert names[names.index("los_from_s") + 1:names.index("los_from_s") + 3] == ["los_band_low_rms_mrad",
                                                                                   "los_band_high_rms_mrad"]
    for row in table.to_pylist():
        assert row["status"] == "ok"
        combined = math.hypot(row["los_band_low_rms_mrad"], row["los_band_high_rms_mrad"])
        assert 0 < combined <= row["los_rms_mrad"] * 1.05   # the spread, without the mean
    with open(outcome.csv) as f:
        assert "los_band_low_rms_mrad" in next(csv.reader(f))


def test_the_sea_estimate_is_put_on_the_dwell_scale_by_the_pointing_geometry(tmp_path, ship_run):
    from gimbal2axis.analysis.frequency_response import read_sea_estimate
    from gimbal2axis.analysis.carrier_projection import dwell_scale

    # on the ship's target (azimuth 30 deg, elevation 5 deg) a roll about y0 lies sin 30 deg along the
    # elevation axis and cos 30 deg sin 5 deg along the cross-elevation one
    scale = dwell_scale(load_scene(SHIP), "roll")
    assert scale["elevation"] == pytest.approx(0.5) and scale["cross_elevation"] == pytest.approx(
        math.cos(math.radians(30)) * math.sin(math.radians(5)))
    path = tmp_path / "iso.csv"
    assert ship_run.write_isolation_csv(path)
    plain = read_sea_estimate(path, 0.01, 100.0)
    scaled = read_sea_estimate(path, 0.01, 100.0, scale)
    assert [c[0].split(":")[1].split("/")[0].strip() for c in plain] == ["los.omega[1]", "los.omega[3]"]
    assert np.allclose(scaled[0][2], plain[0][2] * 0.5) and plain[0][1].min() > 0
    # 3 s at 0.05 Hz is one segment: no bin's gain is known (coherent = 0); they are drawn dotted
    assert not plain[0][4].any() and "bins of low coherence dotted" in plain[0][0]
    with pytest.raises(ValueError, match="not an isolation CSV"):
        (tmp_path / "other.csv").write_text("# x\na,b\n1,2\n")
        read_sea_estimate(tmp_path / "other.csv", 0.1, 1.0)
