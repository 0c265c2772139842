"""Sweeps on Dask (gimbal2axis sweep, gimbal2axis/sweep/): expansion of sweep files, a local cluster
of 2 workers against serial runs case by case, failed cases reported with the FMU's log, reruns
that skip the cases already done."""
import math
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from gimbal2axis import FMU, run  # noqa: E402
from gimbal2axis.sweep import SweepError, SweepOptions, load_sweep, prepare, run_sweep  # noqa: E402
from gimbal2axis.sweep.table import read_rows  # noqa: E402
from gimbal2axis.sweep.worker import metrics  # noqa: E402

pytestmark = pytest.mark.dask_workers

SCENE = REPO / "scenes" / "ship_stabilization.toml"
METRICS = ["los_rms_mrad", "los_peak_mrad", "los_final_mrad", "i_peak_R1_A", "i_peak_R2_A", "i_peak_A", "events",
           "requirements_met"]

# 8 short cases: structural switch (rigid / compliant gear), a controller gain, and per sample a
# random sea state and payload mass: the reused instance must forget everything between them.
SMALL = """
name = "small"
seed = 5
samples = 2
stop_time = 0.06
metrics_from_s = 0.02
[grid]
"gear1.model" = [2, 0]
"controller.azimuth.kp" = [200.0, 800.0]
[random]
"base_motion.seed" = { integers = [0, 9999] }
"body2.m" = { uniform = [1.5, 3.0] }
"""

INVALID = """
name = "invalid"
stop_time = 0.04
[grid]
"body2.m" = [2.0, -1.0, 2.5]
"""


def write(tmp_path, text, name):
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def fmu_path(fmu_path, tmp_path_factory):
    """A copy of the FMU: the serial and the Dask runs use the same bytes even if the build replaces it."""
    import shutil

    copy = tmp_path_factory.mktemp("fmu") / "Gimbal2Axis.fmu"
    shutil.copyfile(fmu_path, copy)
    return copy


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def serial_reference(scene_path, sweep_path, fmu_path):
    """The same cases without Dask and without the sweep's worker code: a fresh instance per case."""
    with FMU(fmu_path) as fmu:
        _, sweep, cases = prepare(scene_path, sweep_path, fmu)
        rows = {}
        for case in cases:
            result = run(case.scene, fmu)
            rows[case.case_id] = metrics(result, sweep.metrics_from_s)
    return rows


def test_sweep_file_expansion(tmp_path):
    sweep = load_sweep(write(tmp_path, SMALL, "small"))
    cases = sweep.expand()
    assert len(cases) == 8
    assert [c["gear1.model"] for c in cases[:4]] == [2, 2, 2, 2]   # the grid varies slowest
    # common random numbers: sample j is the same at every grid point; the draws are reproducible
    assert cases[0]["base_motion.seed"] == cases[2]["base_motion.seed"] != cases[1]["base_motion.seed"]
    assert cases == load_sweep(write(tmp_path, SMALL, "again")).expand()
    # more samples leave the first draws alone (so the cases already run stay done)
    more = load_sweep(write(tmp_path, SMALL.replace("samples = 2", "samples = 3"), "more")).expand()
    assert [c for c in more if c in cases] == cases
    limited = load_sweep(write(tmp_path, "cases = 3\n" + SMALL, "limited")).expand()
    assert limited == cases[:3]
    with pytest.raises(SweepError, match="distribution|uniform"):
        load_sweep(write(tmp_path, '[random]\n"gear1.k_s" = { uniformly = [1, 2] }\n', "bad"))


def test_unknown_parameter_is_refused_before_anything_runs(tmp_path, fmu_path):
    path = write(tmp_path, 'stop_time = 0.01\n[grid]\n"gear1.stiffness" = [1.0, 2.0]\n', "unknown")
    with FMU(fmu_path) as fmu, pytest.raises(SweepError, match="gear1.stiffness"):
        prepare(SCENE, path, fmu)


def test_local_cluster_of_two_workers_equals_serial_runs_case_by_case(tmp_path, fmu_path, client):
    sweep_path = write(tmp_path, SMALL, "small")
    outcome = run_sweep(SCENE, sweep_path, fmu_path, tmp_path / "out",
                        SweepOptions(client=client, progress=False, plot=False))
    assert outcome.ran == 8 and outcome.failed == 0
    rows = {r["case_id"]: r for r in read_rows(outcome.parquet)}
    assert len(rows) == 8 and all(r["status"] == "ok" for r in rows.values())
    # both workers took part, and each reused its one FMU instance (fmi2Reset) for several cases
    assert len({r["worker"] for r in rows.values()}) == 2
    assert max(r["instance_use"] for r in rows.values()) >= 2
    reference = serial_reference(SCENE, sweep_path, fmu_path)
    assert set(reference) == set(rows)
    for case_id, expected in reference.items():
        for key in METRICS:   # bitwise: the same arithmetic on the same inputs
            assert _same(rows[case_id][key], expected[key]), (case_id, key, rows[case_id][key], expected[key])
    # the cases differ from each other (the parameters really reached the FMU and the controller)
    assert len({r["los_rms_mrad"] for r in rows.values()}) == 8
    # the serial mode of the sweep runner (one process, one reused instance) agrees too
    serial = run_sweep(SCENE, sweep_path, fmu_path, tmp_path / "serial",
                       SweepOptions(serial=True, progress=False, plot=False))
    for r in read_rows(serial.parquet):
        assert all(_same(r[k], rows[r["case_id"]][k]) for k in METRICS)


def test_invalid_case_is_reported_with_the_fmu_message_and_the_others_complete(tmp_path, fmu_path, client):
    outcome = run_sweep(SCENE, write(tmp_path, INVALID, "invalid"), fmu_path, tmp_path,
                        SweepOptions(client=client, progress=False))
    rows = read_rows(outcome.parquet)
    assert [r["body2.m"] for r in rows] == [2.0, -1.0, 2.5] and outcome.failed == 1
    bad = rows[1]
    assert bad["status"] == "failed"
    assert "body2.m = -1 is invalid" in bad["fmu_log"]            # the FMU's own log message
    assert "body2.m" in bad["message"] and bad["los_rms_mrad"] is None
    for good in (rows[0], rows[2]):                                  # the other cases ran to the end
        assert good["status"] == "ok" and math.isfinite(good["los_rms_mrad"]) and good["fmu_log"] == ""
    assert "body2.m = -1 is invalid" in outcome.csv.read_text()     # in the CSV too
    assert outcome.png.read_bytes()[:4] == b"\x89PNG"


def test_rerun_skips_the_cases_already_done(tmp_path, fmu_path, client):
    sweep_path = write(tmp_path, SMALL.replace("samples = 2", "samples = 1"), "small")
    first = run_sweep(SCENE, sweep_path, fmu_path, tmp_path, SweepOptions(client=client, progress=False, plot=False))
    assert first.ran == 4
    before = read_rows(first.parquet)
    again = run_sweep(SCENE, sweep_path, fmu_path, tmp_path, SweepOptions(client=client, progress=False, plot=False))
    assert again.ran == 0 and again.skipped == 4
    after = read_rows(again.parquet)
    assert len(after) == len(before) and all(all(_same(a[k], b[k]) for k in a) for a, b in zip(before, after))
    # more samples: only the new cases run, the table grows by them
    sweep_path.write_text(SMALL)
    more = run_sweep(SCENE, sweep_path, fmu_path, tmp_path, SweepOptions(client=client, progress=False, plot=False))
    assert more.ran == 4 and more.skipped == 4 and len(read_rows(more.parquet)) == 8


USER_GAINS = """
name = "user_gains"
stop_time = 0.1
metrics_from_s = 0.02
[grid]
"controller.options.kp" = [100.0, 400.0]
"controller.options.k_gyro" = [2.0, 8.0]
"""


def test_a_user_controller_sweeps_on_the_workers_like_a_built_in_one(tmp_path, fmu_path, client):
    # examples/user_controller.toml names examples/gyro_stabilizer.py; its options are swept
    scene = REPO / "examples" / "user_controller.toml"
    sweep_path = write(tmp_path, USER_GAINS, "user_gains")
    outcome = run_sweep(scene, sweep_path, fmu_path, tmp_path / "out", SweepOptions(client=client, progress=False,
                                                                                      plot=False))
    rows = {r["case_id"]: r for r in read_rows(outcome.parquet)}
    assert outcome.failed == 0 and len(rows) == 4
    assert len({r["los_rms_mrad"] for r in rows.values()}) == 4   # each case got its own options
    reference = serial_reference(scene, sweep_path, fmu_path)
    for case_id, expected in reference.items():
        for key in METRICS:
            assert _same(rows[case_id][key], expected[key]), (case_id, key)
