"""Results streamed, memory bounded (issue 33): `gimbal2axis run` makes its run a chunk of steps at a
time (gimbal2axis/master/streaming.py) and writes it as it goes. The chunks must give the bits of the
whole run held in memory (master.run: the golden digests' path), for both loops and every input that
is prepared ahead (base motion, sensor noise and datasheet gyro, direct and indirect, set points,
delays, user controllers); the summary's metrics and the spectra computed chunk by chunk must agree
with the in-memory ones; the plots' decimation must keep every extreme."""
import pathlib
import sys

import numpy as np
import pyarrow.parquet as pq
import pytest

from gimbal2axis import FMU, SceneError, load_scene, run
from gimbal2axis.master import streaming

REPO = pathlib.Path(__file__).resolve().parents[3]
sys.path.insert(0, str(REPO / "tests" / "c_kernel"))
from test_compiled_loop import variant  # noqa: E402

pytestmark = pytest.mark.python_bound

# Chunks far shorter than the runs (and not a multiple of the sum of sines' 128-row blocks), so that
# every prepared input crosses many chunk boundaries.
SMALL_CHUNK = 173


@pytest.fixture(scope="module")
def fmu(fmu_path):
    with FMU(fmu_path) as loaded:
        yield loaded


def streamed_and_whole(fmu, scene, stop_time, compiled, tmp_path, chunk_rows=SMALL_CHUNK):
    whole = run(scene, fmu, stop_time=stop_time, compiled=compiled)
    streamed = streaming.run_streamed(scene, fmu, tmp_path, stop_time=stop_time, compiled=compiled,
                                      chunk_rows=chunk_rows)
    return whole, streamed


@pytest.mark.parametrize("name", ["ship_stabilization.toml", "ship_with_every_sensor_term", "ship_undelayed",
                                  "ship_indirect_with_every_sensor_term_and_encoder_differences",
                                  "pid_with_every_term_saturating"])
@pytest.mark.parametrize("compiled", [True, False])
def test_a_streamed_run_has_the_bits_of_the_whole_run(fmu, tmp_path, name, compiled):
    scene, stop_time = variant(name)
    stop_time = min(stop_time, 0.6)
    whole, streamed = streamed_and_whole(fmu, scene, stop_time, compiled, tmp_path)
    assert streamed.loop == whole.loop == ("compiled" if compiled else "python")
    table = pq.read_table(streamed.parquet_path)
    assert table.column_names == whole.csv_columns()
    for name_ in whole.csv_columns():
        assert np.array_equal(table.column(name_).to_numpy(), np.asarray(whole.signal(name_), dtype=float),
                              equal_nan=True), name_
    whole.write_csv(tmp_path / "whole.csv")
    assert streamed.csv_path.read_bytes() == (tmp_path / "whole.csv").read_bytes()


def test_a_user_controller_streamed_has_the_bits_of_the_whole_run(fmu, tmp_path):
    scene = load_scene(REPO / "examples" / "user_controller.toml")
    whole, streamed = streamed_and_whole(fmu, scene, 0.4, None, tmp_path)
    assert streamed.loop == "python"
    table = pq.read_table(streamed.parquet_path)
    for name in whole.csv_columns():
        assert np.array_equal(table.column(name).to_numpy(), np.asarray(whole.signal(name), dtype=float),
                              equal_nan=True), name


def test_the_streamed_summary_and_spectra_agree_with_the_whole_run(fmu, tmp_path):
    scene = load_scene(REPO / "scenes" / "ship_jitter_20min.toml")
    whole, streamed = streamed_and_whole(fmu, scene, 12.0, True, tmp_path, chunk_rows=1000)
    expected, found = whole.los_metrics(), streamed.los_metrics()
    for key in ("final", "rms", "max", "rms_all", "from_s"):
        assert found[key] == pytest.approx(expected[key], rel=1e-12), key
    for axis, spectrum in whole.los_spectra().items():
        other = streamed.los_spectra()[axis]
        assert other.segments == spectrum.segments and other.resolution == spectrum.resolution
        assert np.allclose(other.psd, spectrum.psd, rtol=1e-9, atol=1e-12 * spectrum.psd.max())
        assert other.mean == pytest.approx(spectrum.mean, rel=1e-12)
    for i, estimate in whole.isolation_estimates().items():
        other = streamed.isolation_estimates()[i]
        carrier = whole.carrier_spectrum(i)
        assert np.allclose(streamed.carrier_spectrum(i), carrier, rtol=1e-9, atol=1e-12 * carrier.max())
        # where the carrier moves (elsewhere H1 divides round-off by round-off)
        moving = carrier > 1e-6 * carrier.max()
        assert moving.sum() >= 5
        assert np.allclose(other.response[moving], estimate.response[moving], rtol=1e-9)
    assert streamed.band_rms() == pytest.approx(whole.band_rms(), rel=1e-9)
    # the summary line is the same but for the wall time
    cut = lambda line: line.split(" wall ")[1].split(";", 1)[1]   # noqa: E731
    assert cut(streamed.summary()) == cut(whole.summary())


def test_the_plots_decimation_keeps_every_extreme(fmu, tmp_path):
    scene = load_scene(REPO / "scenes" / "ship_stabilization.toml")
    stop_time = 6.0   # 6001 points: more than two per pixel column, so decimated
    streamed = streaming.run_streamed(scene, fmu, tmp_path, stop_time=stop_time, chunk_rows=977)
    table = pq.read_table(streamed.parquet_path)
    assert len(streamed.signals["time"]) <= 2 * streaming.PLOT_COLUMNS < table.num_rows
    for name, values in streamed.signals.items():
        column = table.column(name).to_numpy()
        assert np.nanmin(values) == np.nanmin(column) and np.nanmax(values) == np.nanmax(column), name
    t = streamed.signals["time"]
    assert t[0] == 0.0 and t[-1] == stop_time and np.all(np.diff(t) >= 0)


def test_a_streamed_run_too_long_for_the_disk_is_refused_before_it_starts(fmu, tmp_path):
    scene = load_scene(REPO / "scenes" / "ship_stabilization.toml")
    with pytest.raises(SceneError, match=r"needs up to .* on disk, .* free"):
        streaming.run_streamed(scene, fmu, tmp_path, stop_time=1e7)
    assert list(tmp_path.iterdir()) == []


def test_a_run_held_in_memory_that_cannot_fit_is_refused_before_it_starts(fmu):
    scene = load_scene(REPO / "scenes" / "ship_stabilization.toml")
    with pytest.raises(SceneError, match=r"held in memory needs .* is available; .*gimbal2axis run"):
        run(scene, fmu, stop_time=1e7)


def test_the_streamed_window_is_the_whole_runs(fmu, tmp_path):
    scene = load_scene(REPO / "scenes" / "ship_stabilization.toml")
    whole, streamed = streamed_and_whole(fmu, scene, 6.0, True, tmp_path, chunk_rows=700)
    assert streamed.window_bounds() == whole.window_bounds()
