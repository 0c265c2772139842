"""The isolation panel of <scene>_spectrum.png (master.plotting.spectrum_figure) calls a bin's gain known
only where the estimate can know it: coherent and with the carrier's rate as input. Where the carrier has
no power (above a few Hz in a seaway), some of thousands of bins pass the coherence bound by chance, and
their H1 is a ratio of round-off (1e4 to 1e6): issue 46 found those drawn as known. A tracking scene
draws no isolation at all: its line of sight turns after the target on purpose."""
import pathlib

import numpy as np
import pytest

from gimbal2axis.master import run
from gimbal2axis.master.plotting import CARRIER_RANGE_DB, carrier_has_power, spectrum_figure
from gimbal2axis.scene import load_scene

# Spectra and figures: its time goes to Python.
pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[3]


def test_the_carrier_has_power_within_its_range_of_the_peak_only():
    psd = np.array([0.0, 1e-2, 1.0, 1e-6 * 1.01, 1e-6 * 0.99, np.nan, 1e-20])
    assert CARRIER_RANGE_DB == 60.0
    assert carrier_has_power(psd).tolist() == [False, True, True, True, False, False, False]
    assert not carrier_has_power(np.zeros(4)).any()


@pytest.fixture(scope="module")
def ship_run(gimbal_fmu):
    """21 s of the ship scene in 5-s segments (0.2 Hz): 7 segments, some of thousands of noise bins pass."""
    scene = load_scene(REPO / "scenes" / "ship_stabilization.toml")
    scene = scene.with_changes(stop_time=21.0, analysis_spec={**scene.analysis_spec, "isolation_resolution_hz": 0.2})
    return run(scene, gimbal_fmu)


def test_no_bin_is_known_where_the_carrier_has_no_power(ship_run):
    fig = spectrum_figure(ship_run)
    panel = fig.axes[2]
    drawn = [line for line in panel.get_lines() if "bins known" in line.get_label()]
    assert len(drawn) == 2
    by_chance = 0
    for line, (i, estimate) in zip(drawn, ship_run.isolation_estimates().items()):
        f, gain = estimate.frequency, np.abs(estimate.response)
        shown = (f > 0) & np.isfinite(gain) & (gain > 0)
        known = ~np.isnan(np.asarray(line.get_ydata(), float))
        powered = carrier_has_power(ship_run.carrier_spectrum(i))[shown]
        assert not (known & ~powered).any()
        assert np.array_equal(known, (estimate.coherent[shown] & powered))
        by_chance += int((estimate.coherent[shown] & ~powered).sum())
        assert f[shown][known].max(initial=0.0) < 5.0, "a bin known above the sea's band"
    assert by_chance > 0, "no noise bin passed the coherence bound: the test shows nothing masked"


def test_a_tracking_scene_draws_no_isolation(gimbal_fmu):
    scene = load_scene(REPO / "scenes" / "track_flyby_keyhole.toml").with_changes(stop_time=1.0)
    result = run(scene, gimbal_fmu)
    assert result.base_moves and result.isolation_estimates(), "the flyby's carrier moves: an estimate exists"
    fig = spectrum_figure(result)
    assert len(fig.axes) == 2
    assert not any("isolation" in ax.get_title() for ax in fig.axes)
