"""Analyses that check themselves (issue 34): the sine dwell's own measures of linearity (harmonics,
drift) on signals of known content, the marks of points that are not a frequency response (a falling
payload, against a balanced one), the H1 estimate's random error and the coherence below which the
isolation from a run is masked, and the summary's metric labels naming the window they were taken over."""
import csv
import math
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from gimbal2axis.analysis import frequency_response as fr
from gimbal2axis.master import spectra

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[3]
SHIP = REPO / "scenes" / "ship_stabilization.toml"
BALANCED = ["--set", "body2.d_bd[2]=0", "--set", "body2.d_bd[3]=0"]


def window(periods: int, samples: int):
    """`samples` equally spaced phases w t over `periods` whole periods (not a whole number per period)."""
    return 2 * math.pi * periods * np.arange(samples) / samples


# -- the dwell's measures of linearity on known signals -------------------------------------------------

@pytest.mark.parametrize("samples", [63, 634, 4000])   # 15.75, 158.5 and 1000 samples per period
def test_a_steady_sine_has_neither_harmonics_nor_drift(samples):
    phase = window(4, samples)
    harmonic, drift = fr.linearity_measures(0.3 + 2.0 * np.sin(phase + 0.4), 4)
    assert harmonic < 1e-12 and drift < 1e-12


def test_the_harmonic_amplitude_is_the_root_sum_square_of_the_harmonics():
    phase = window(4, 400)
    y = np.sin(phase) + 0.03 * np.cos(2 * phase) + 0.04 * np.sin(3 * phase + 1.0)
    harmonic, drift = fr.linearity_measures(y, 4)
    assert harmonic == pytest.approx(0.05, rel=1e-9)
    assert drift < 1e-12   # harmonics are periodic: no drift


def test_a_growing_amplitude_is_drift_from_the_first_to_the_last_period():
    periods, samples = 4, 634
    phase = window(periods, samples)
    tau = (np.arange(samples) - (samples - 1) / 2) / samples
    y = (1.0 + 0.2 * tau) * np.sin(phase)   # the amplitude grows by 0.2 over the window
    _, drift = fr.linearity_measures(y, periods)
    assert drift == pytest.approx(0.2 * (periods - 1) / periods, rel=1e-9)


def test_a_ramp_of_the_mean_is_drift_by_the_error_it_puts_on_the_single_bin_dft():
    periods, samples = 4, 4000
    phase = window(periods, samples)
    ramp = 0.5 * np.arange(samples) / samples
    _, drift = fr.linearity_measures(np.sin(phase) + ramp, periods)
    assert drift == pytest.approx(0.5 / (math.pi * periods), rel=1e-3)
    # ... which is what the ramp does to the single-bin DFT of the window
    t = np.arange(samples) / samples * periods
    assert abs(fr.fundamental(ramp, t, 1.0)) == pytest.approx(drift, rel=1e-3)


def test_one_measured_period_cannot_tell_drift_from_harmonics():
    harmonic, drift = fr.linearity_measures(np.sin(window(1, 100)), 1)
    assert harmonic < 1e-12 and math.isnan(drift)


def row(gain=1.0, phase_deg=0.0, harmonic=0.0, drift=0.0, amplitude=1.0):
    return dict(curve="no backlash, no dry friction", output="y", frequency_hz=1.0, gain=gain, phase_deg=phase_deg,
                output_amplitude=amplitude, harmonic_amplitude=harmonic, drift_amplitude=drift, output_variance=1.0)


def test_marks_name_each_reason_beyond_the_tolerance_and_none_within_it():
    within = fr.LINEARITY_TOLERANCE * 0.9
    assert fr.linearity_marks(row(1 + within, 0.9, within, within), predicted=1.0) == []
    marks = fr.linearity_marks(row(0.5, 170.0, 0.05, 0.2), predicted=1.0,
                               operating_point_change=-0.5j, operating_point="beta 5 -> -123 deg")
    assert marks == ["harmonics 5 %", "drift 20 %", "vs linear -6.02 dB +170 deg",
                     "operating point beta 5 -> -123 deg: linear there -6.02 dB -90 deg"]
    # the combined 'los' has no phase: judged on its gain alone
    assert fr.linearity_marks(row(1.0, math.nan), predicted=1.0) == []


def test_the_summary_counts_marked_points_per_curve():
    rows = [dict(row(), marks=""), dict(row(), marks="drift 3 %; vs linear -4 dB +180 deg"),
            dict(row(), curve="full model", marks="harmonics 4 %"), dict(curve=fr.LINEAR_CURVE)]
    line = fr.marks_summary(rows)
    assert line.endswith("no backlash, no dry friction 1 of 2 (drift 1, vs linear 1); full model 1 of 1 (harmonics 1)")
    assert fr.marks_summary([dict(row(), marks="")]) is None


# -- the command: a falling payload is marked and warned about, a balanced one is not ------------------

def freqresp(fmu_path, tmp_path, *args):
    out = subprocess.run([sys.executable, "-m", "gimbal2axis", "freqresp", "open-loop", "--axis", "1", "--serial",
                          "--fmu", str(fmu_path), "--out", str(tmp_path), "--name", "dwell", *args],
                         capture_output=True, text=True, cwd=REPO)
    assert out.returncode == 0, out.stderr
    with open(tmp_path / "dwell.csv") as f:
        rows = [r for r in csv.DictReader(f) if r["curve"] != fr.LINEAR_CURVE]
    return out, rows


def test_a_falling_payload_is_marked_and_warned_about(fmu_path, build_dir, tmp_path):
    # the scene's centre of mass is off the elevation axis: with motor 2 at 0 V the payload falls to
    # beta near -120 deg during the settle, which flips los.omega[3] = alpha' cos(beta) and costs 4 to 8 dB
    out, rows = freqresp(fmu_path, tmp_path, "--fmin", "0.1", "--fmax", "1", "--points", "2", "--linear-only")
    # los.omega[3] at both frequencies; alpha_dot hardly depends on beta (within 1 % and 1 deg)
    assert "warning: 2 of 4 points were measured away from the linear prediction's operating point" in out.stderr
    assert "body2.d_bd[2]=0" in out.stderr
    los = [r for r in rows if r["output"] == "los.omega[3]"]
    assert len(los) == 2
    for r in los:
        assert "vs linear" in r["marks"] and "operating point beta 5 -> -1" in r["marks"], r["marks"]
        assert float(r["beta_mean_deg"]) < -100
    assert "no backlash, no dry friction 2 of 4" in out.stdout   # alpha_dot at 1 Hz: the swinging payload
    assert "not a frequency response to 1 % and 1 deg" in out.stdout


def test_the_balanced_payload_without_backlash_and_friction_has_no_mark(fmu_path, build_dir, tmp_path):
    # the documented working example, without the full model, over the whole band
    out, rows = freqresp(fmu_path, tmp_path, "--fmin", "0.1", "--fmax", "100", "--points", "4", "--linear-only",
                         *BALANCED)
    assert len(rows) == 8
    assert all(r["marks"] == "" for r in rows), [r["marks"] for r in rows]
    assert out.stdout.startswith("every point is a frequency response to 1 % and 1 deg"), out.stdout
    assert "warning" not in out.stderr


# -- the isolation from a run: the H1 estimate's random error and its mask --------------------------

def test_overlapping_hann_segments_are_worth_fewer_independent_averages():
    # Welch's overlap correlation of a Hann window at 50 %: rho = 1/6 in the limit of long segments
    assert spectra.independent_segments(1, 1000) == pytest.approx(1.0)
    assert spectra.independent_segments(100, 10000) == pytest.approx(100 / (1 + 2 * 0.99 / 36), rel=1e-3)
    assert spectra.coherence_bound(50.0, 0.1) == pytest.approx(0.5)


def test_the_h1_random_error_at_a_coherence_matches_monte_carlo():
    # y = x + noise with a white x and a white noise of the same power: coherence 0.5 in every bin; the
    # spread of |H1| over many runs is what h1_random_error predicts from the independent averages
    fs, resolution, samples = 100.0, 1.0, 2000
    gains = []
    rng = np.random.default_rng(7)
    for _ in range(300):
        x = rng.normal(size=samples)
        estimate = spectra.transfer_estimate(x, x + rng.normal(size=samples), fs, resolution)
        gains.append(np.abs(estimate.response[5:45]))
    spread = np.std(np.array(gains), axis=0).mean()
    predicted = spectra.h1_random_error(0.5, estimate.averages)
    assert spread == pytest.approx(predicted, rel=0.1)


def test_bins_where_the_input_has_no_energy_are_not_coherent():
    from scipy import signal

    fs = 200.0
    rng = np.random.default_rng(3)
    b, a = signal.butter(6, 5.0, fs=fs)
    x = signal.lfilter(b, a, rng.normal(size=60_000))      # the carrier's energy below 5 Hz
    y = 0.01 * x + 1e-4 * rng.normal(size=x.size)           # the gyro: isolation 0.01 plus its own noise
    estimate = spectra.transfer_estimate(x, y, fs, 0.5)
    f = estimate.frequency
    assert estimate.coherent[(f > 0.5) & (f < 3.0)].all()
    assert not estimate.coherent[(f > 20.0)].any()
    # where known, the gain is within a few random errors of the truth
    known = estimate.coherent & (f > 0)
    assert np.all(np.abs(np.abs(estimate.response[known]) / 0.01 - 1) < 4 * estimate.random_error[known])


@pytest.fixture(scope="module")
def short_ship_run(tmp_path_factory, fmu_path):
    from gimbal2axis.master import run_scene_file

    out = tmp_path_factory.mktemp("short_ship")
    result, _, _ = run_scene_file(SHIP, fmu_path, out, stop_time=0.5)
    return result, out


def test_a_run_shorter_than_the_metrics_window_says_the_window_it_was_measured_over(short_ship_run):
    result, _ = short_ship_run
    summary = result.summary()
    assert "RMS over [0, 0.5] s" in summary, summary
    assert "from 1 s" not in summary
    assert "requirements not judged" in summary


def test_the_isolation_csv_and_panel_mask_the_bins_of_low_coherence(short_ship_run):
    from gimbal2axis.master.plotting import spectrum_figure

    result, out = short_ship_run
    data = np.genfromtxt(out / "ship_stabilization_isolation.csv", delimiter=",", names=True, skip_header=1)
    estimate = result.isolation_estimates()[1]
    # half a second at the 0.05-Hz resolution is one segment, whose coherence is 1 by construction: no bin
    # is known, although every coherence reads 1
    assert estimate.segments == 1 and np.all(data["elevation_coherence"] == 1)
    assert np.all(data["elevation_coherent"] == 0) and not estimate.coherent.any()
    fig = spectrum_figure(result)
    isolation_panel = fig.axes[2]
    drawn = [line for line in isolation_panel.get_lines() if "bins known" in line.get_label()]
    assert len(drawn) == 2
    f = estimate.frequency
    shown = (f > 0) & np.isfinite(np.abs(estimate.response)) & (np.abs(estimate.response) > 0)
    ydata = np.asarray(drawn[0].get_ydata(), float)
    assert np.array_equal(np.isnan(ydata), ~estimate.coherent[shown])


def test_the_bode_plot_draws_marked_points_grey_and_counts_them(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    drawn = {}
    monkeypatch.setattr(Figure, "savefig", lambda fig, *args, **kwargs: drawn.setdefault("figure", fig))
    rows = [dict(row(), frequency_hz=f, gain_db=0.0, coherence=1.0, marks=marks)
            for f, marks in ((1.0, ""), (2.0, "drift 3 %"), (4.0, ""))]
    fr.plot_bode(rows, tmp_path / "bode.png")
    gain_panel = drawn["figure"].axes[0]
    assert any("(1 of 3 not a frequency response: grey)" in line.get_label() for line in gain_panel.get_lines())
    grey = [line for line in gain_panel.get_lines() if line.get_markerfacecolor() == "0.75"]
    assert len(grey) == 1 and list(grey[0].get_xdata()) == [2.0]
