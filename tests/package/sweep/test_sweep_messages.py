"""What a sweep tells its user and how it ends, run as a user runs it (gimbal2axis sweep in a
subprocess): a misspelt parameter name is refused before any case runs, naming the closest valid
names; failed cases end the sweep with exit status 1 and say where their errors are; a `cases`
limit that drops grid points says so; Ctrl-C and SIGTERM keep the finished cases and print no
traceback; a scheduler that does not answer fails within seconds in one line. And the summary plot:
a heat map for a grid of two gains, no trend line over a seed, tick labels that stay apart."""
import itertools
import os
import pathlib
import signal
import socket
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from gimbal2axis import FMU  # noqa: E402
from gimbal2axis.sweep import SweepError, SweepOptions, load_sweep, prepare, run_sweep  # noqa: E402
from gimbal2axis.sweep import table  # noqa: E402
from gimbal2axis.sweep.runner import SCHEDULER_TIMEOUT_S  # noqa: E402
from gimbal2axis.sweep.table import read_rows  # noqa: E402

pytestmark = pytest.mark.dask_workers

SCENE = REPO / "scenes" / "ship_stabilization.toml"
SWEEP = [sys.executable, "-m", "gimbal2axis", "sweep"]   # the installed package's command

# gimbal2axis sweep and its Dask workers as processes of their own: under the preloaded AddressSanitizer
# runtime they test nothing the release pass does not (scripts/test.sh leaves tests/package/sweep/test_sweep.py out too).
as_a_process = pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                                  reason="sweep processes under AddressSanitizer test nothing more")

TYPO = """
stop_time = 0.04
[grid]
"controller.azimuth.kpp" = [200.0, 400.0]
"""

ONE_BAD = """
stop_time = 0.04
[grid]
"body2.m" = [2.0, -1.0]
"""

LIMITED = """
stop_time = 0.04
cases = 2
[grid]
"controller.azimuth.kp" = [200.0, 800.0]
"controller.azimuth.ki" = [1000.0, 4000.0]
"""

# Enough short cases that the sweep is still running when the signal comes after the first one.
MANY = """
stop_time = 0.2
samples = 300
[random]
"controller.azimuth.kp" = { uniform = [100.0, 1600.0] }
"""


def write(tmp_path, text, name="s"):
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


def cli(fmu_path, out, *args, **kwargs):
    return subprocess.run([*SWEEP, *map(str, args), "--fmu", str(fmu_path), "--out", str(out)],
                          capture_output=True, text=True, cwd=REPO, **kwargs)


@as_a_process
def test_misspelt_controller_key_is_refused_before_any_case_runs(tmp_path, fmu_path):
    run = cli(fmu_path, tmp_path / "out", SCENE, write(tmp_path, TYPO), "--serial", "--quiet", timeout=60)
    assert run.returncode == 2, run.stderr
    assert "'controller.azimuth.kpp'" in run.stderr
    assert "did you mean 'controller.azimuth.kp'" in run.stderr
    assert "none was run" in run.stderr and "Traceback" not in run.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("name, suggested", [
    ("gear1.k_ss", "'gear1.k_s'"),                       # a bare FMU name
    ("parameters.motor1.k_torq", "'parameters.motor1.k_torque'"),
    ("initial.alpah", "'initial.alpha'"),
    ("alpha", "'initial.alpha'"),                        # a state, not a parameter
    ("controler.azimuth.kp", "'controller.azimuth.kp'"),  # the section misspelt
    ("sensors.gyro_noise", "'sensors.gyro_noise_deg_s'"),
    ("base_motion.rol.significant_amplitude_deg", "'base_motion.roll.significant_amplitude_deg'"),
])
def test_misspelt_names_get_the_closest_valid_names(tmp_path, fmu_path, name, suggested):
    path = write(tmp_path, f'stop_time = 0.04\n[grid]\n"{name}" = [1.0, 2.0]\n')
    with FMU(fmu_path) as fmu, pytest.raises(SweepError) as refused:
        prepare(SCENE, path, fmu)
    assert f"'{name}'" in str(refused.value) and suggested in str(refused.value)


def test_a_name_valid_in_some_cases_only_runs_and_reports_the_others(tmp_path, fmu_path):
    # one good value is enough to show the name is right: the bad value is that case's failure
    path = write(tmp_path, 'stop_time = 0.04\n[grid]\n"controller.azimuth.kp" = [200.0, "fast"]\n')
    with FMU(fmu_path) as fmu:
        _, _, cases = prepare(SCENE, path, fmu)
    assert cases[0].scene is not None and "controller.azimuth.kp" in cases[1].error


@as_a_process
def test_failed_cases_end_the_sweep_with_exit_status_1_and_say_where_the_errors_are(tmp_path, fmu_path):
    run = cli(fmu_path, tmp_path / "out", SCENE, write(tmp_path, ONE_BAD, "one_bad"), "--serial", "--quiet",
              timeout=60)
    assert run.returncode == 1, run.stderr
    csv = tmp_path / "out" / "one_bad__ship_stabilization.csv"
    assert "1 of 2 cases failed" in run.stderr and str(csv) in run.stderr
    assert "'message'" in run.stderr and "'fmu_log'" in run.stderr
    assert "body2.m = -1 is invalid" in run.stdout                 # the first failures, shown
    assert [r["status"] for r in read_rows(csv.with_suffix(".parquet"))] == ["ok", "failed"]


@as_a_process
def test_cases_limit_below_the_grid_says_which_points_are_dropped(tmp_path, fmu_path):
    run = cli(fmu_path, tmp_path / "out", SCENE, write(tmp_path, LIMITED, "limited"), "--serial", "--quiet",
              timeout=60)
    assert run.returncode == 0, run.stderr                        # every case that ran is ok
    assert "warning" in run.stderr
    assert "runs 2 of the 2 x 2 = 4 grid points" in run.stderr
    assert "never run: controller.azimuth.kp = 800" in run.stderr
    assert "Raise 'cases' to 4" in run.stderr
    assert len(read_rows(tmp_path / "out" / "limited__ship_stabilization.parquet")) == 2


def test_limit_warning_counts_grid_points_and_samples(tmp_path):
    text = LIMITED.replace("cases = 2", "cases = 5\nsamples = 2") + '[random]\n"body2.m" = { uniform = [1.5, 3.0] }\n'
    warning = load_sweep(write(tmp_path, text)).limit_warning()
    assert "runs 5 of the 8 cases (2 x 2 = 4 grid points x 2 samples)" in warning
    assert "the first 2 grid points with all 2 samples and grid point 3 with 1 of its 2 samples" in warning
    assert "drops the last 1 grid point" in warning
    assert load_sweep(write(tmp_path, LIMITED.replace("cases = 2", "cases = 4"))).limit_warning() is None
    assert load_sweep(REPO / "sweeps" / "gains_1000.toml").limit_warning() is None


def test_a_sweep_over_a_motors_drive_warns_that_the_gains_change_their_unit(tmp_path):
    for name in ("motor1.drive", "fidelity.motor2.drive"):
        text = f'stop_time = 0.04\n[grid]\n"{name}" = [0, 1]\n'
        warning = load_sweep(write(tmp_path, text)).drive_warning()
        assert f"{name} is swept" in warning and "amperes per unit where it is current-driven" in warning
    assert load_sweep(write(tmp_path, LIMITED)).drive_warning() is None


def _start_then_signal(fmu_path, out, sweep, sig, whole_group):
    """Starts a sweep on a local cluster of 2 worker processes and, once a case is finished, sends
    `sig` to it (or, as a terminal's Ctrl-C does, to its whole process group)."""
    proc = subprocess.Popen([*SWEEP, str(SCENE), str(sweep), "--fmu", str(fmu_path),
                             "--out", str(out), "--workers", "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, cwd=REPO, start_new_session=True,
                            # a shell running us in the background may have SIGINT ignored
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    seen = []
    try:
        for line in proc.stderr:   # progress: a line at the first finished case
            seen.append(line)
            if line.startswith("[") and " ok " in line:
                break
        if whole_group:
            os.killpg(proc.pid, sig)
        else:
            proc.send_signal(sig)
        out_text, err_text = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    return proc.returncode, out_text, "".join(seen) + err_text


@as_a_process
@pytest.mark.parametrize("sig, whole_group, status, said", [
    (signal.SIGTERM, False, 143, "terminated (SIGTERM)"),
    (signal.SIGINT, True, 130, "interrupted"),
])
def test_ctrl_c_and_sigterm_keep_the_finished_cases_without_a_traceback(tmp_path, fmu_path, sig, whole_group,
                                                                       status, said):
    out = tmp_path / "out"
    code, _, stderr = _start_then_signal(fmu_path, out, write(tmp_path, MANY, "many"), sig, whole_group)
    assert code == status, stderr
    assert said in stderr and "kept in" in stderr
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr
    assert " ERROR " not in stderr        # e.g. workers dying of Ctrl-C, losing the FMU scattered to them
    rows = read_rows(out / "many__ship_stabilization.parquet")
    assert 1 <= len(rows) < 300 and all(r["status"] == "ok" for r in rows)


@as_a_process
def test_scheduler_that_does_not_answer_fails_within_seconds_in_one_line(tmp_path, fmu_path):
    with socket.socket() as s:   # a port where nothing listens
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    # No timing assertion (shared machines are noisy): the CLI asks Dask to give up after
    # SCHEDULER_TIMEOUT_S, not its default 30 s, and says so; the subprocess timeout only guards a hang.
    run = cli(fmu_path, tmp_path / "out", SCENE, write(tmp_path, LIMITED), "--scheduler", f"tcp://127.0.0.1:{port}",
              "--quiet", timeout=120)
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert [line for line in lines if "warning" not in line] == [lines[-1]], run.stderr
    assert lines[-1].startswith(f"gimbal2axis sweep: error: no Dask scheduler answered at tcp://127.0.0.1:{port} "
                                f"within {SCHEDULER_TIMEOUT_S:g} s")
    assert SCHEDULER_TIMEOUT_S <= 10


def _rows(names, values, metric=lambda point: 1.0, failed=()):
    rows = []
    for i, point in enumerate(values):
        row = dict(zip(names, point), case=i, status="failed" if i in failed else "ok")
        if i not in failed:
            row.update(los_rms_mrad=metric(point), los_peak_mrad=2.0 * metric(point), i_peak_A=0.53308 + 1e-5 * i,
                       events=10 + i % 7, wall_time_s=0.1 + 0.01 * i)
        rows.append(row)
    return rows


def test_two_swept_gains_give_a_heat_map_with_labelled_axes_and_a_colour_bar(tmp_path, fmu_path, monkeypatch):
    figures = []
    summary = table.summary_figure
    monkeypatch.setattr(table, "summary_figure", lambda *a, **k: figures.append(summary(*a, **k)) or figures[-1])
    path = write(tmp_path, LIMITED.replace("cases = 2\n", ""), "gains")
    run_sweep(SCENE, path, fmu_path, tmp_path / "out", SweepOptions(serial=True, progress=False))
    fig, = figures
    heat = fig.axes[0]
    assert heat.images, "no heat map"
    assert heat.get_xlabel() == "controller.azimuth.kp" and heat.get_ylabel() == "controller.azimuth.ki"
    assert [t.get_text() for t in heat.get_xticklabels()] == ["200", "800"]
    assert [t.get_text() for t in heat.get_yticklabels()] == ["1000", "4000"]
    bars = [ax for ax in fig.axes if ax.get_ylabel().startswith("LOS RMS [mrad]")]
    assert bars and bars[0] is not heat                            # the colour bar, labelled with the metric
    image = heat.images[0].get_array()
    assert image.shape == (2, 2) and image.count() == 4              # every grid point has its value


def test_heat_map_marks_failed_grid_points():
    values = list(itertools.product([100.0, 400.0, 1600.0], [1e3, 4e3]))
    fig = table.summary_figure(_rows(["kp", "ki"], values, failed={1}), ["kp", "ki"], grid=["kp", "ki"])
    heat = fig.axes[0]
    assert heat.images[0].get_array().mask[1, 0]                     # ki = 4000, kp = 100: no value ...
    assert any(t.get_text() == "1 failed" for t in heat.texts)        # ... but a note


def test_no_trend_line_over_a_seed_and_tick_labels_stay_apart():
    names = ["controller.azimuth.kp", "base_motion.seed", "body2.m"]
    values = [(kp, seed, 0.53308 + 1.6e-4 * ((7 * i) % 10) / 10)
              for i, (kp, seed) in enumerate(itertools.product([200.0, 400.0, 800.0], [31337, 4242, 77777]))]
    fig = table.summary_figure(_rows(names, values, metric=lambda p: 1000.0 / p[0]), names,
                               grid=["controller.azimuth.kp", "base_motion.seed"])
    assert not any(ax.images for ax in fig.axes)                     # a seed and a gain: no heat map
    columns = {name: [ax for ax in fig.axes if ax.get_subplotspec().colspan.start == j]
               for j, name in enumerate(names)}
    medians = {name: sum(line.get_label() == "median" for ax in axes for line in ax.lines)
               for name, axes in columns.items()}
    assert medians["controller.azimuth.kp"] > 0 and medians["base_motion.seed"] == 0
    fig.canvas.draw()
    texts = []
    for ax in fig.axes:
        lo, hi = sorted(ax.get_xlim())
        ticks = [t for t, v in zip(ax.get_xticklabels(), ax.get_xticks()) if lo <= v <= hi]
        for text in ticks + [ax.xaxis.label, ax.yaxis.label, ax.xaxis.get_offset_text()]:
            if text.get_visible() and text.get_text():
                texts.append((text.get_text(), text.get_window_extent()))
    touching = [(a, b) for (a, box_a), (b, box_b) in itertools.combinations(texts, 2) if box_a.overlaps(box_b)]
    assert not touching
    width, height = fig.bbox.width, fig.bbox.height
    assert all(box.x0 >= 0 and box.x1 <= width and box.y0 >= 0 and box.y1 <= height for _, box in texts)


def test_a_serial_sweep_leaves_no_temporary_folder(fmu_path, tmp_path):
    """The FMU a serial sweep extracts for itself goes away with the process (it left a 2.2 MB
    gimbal_sweep_* folder in /tmp at every run)."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    sweep = write(tmp_path, LIMITED, "limited")
    done = subprocess.run(SWEEP + [str(SCENE), str(sweep), "--fmu", str(fmu_path), "--out", str(tmp_path / "out"),
                                   "--serial", "--quiet"], capture_output=True, text=True, timeout=120,
                          env={**os.environ, "TMPDIR": str(scratch)})
    assert done.returncode == 0, done.stderr
    assert list(scratch.iterdir()) == []


def test_the_summary_says_why_requirements_met_is_empty_in_every_case():
    """The README's sweep runs 0.5 s per case on a scene whose requirements window starts at 1 s: the
    column requirements_met is empty in every row, and the summary says why (cli.sweep.requirements_note)."""
    from gimbal2axis.cli.sweep import requirements_note

    scene = REPO / "scenes" / "ship_stabilization.toml"
    unjudged = [{"scene": "ship_stabilization", "status": "ok", "requirements_met": None, "stop_time": 0.5}] * 3
    note = requirements_note(scene, unjudged)
    assert note == ("requirements_met is empty in every case: the scene's requirements window starts at 1 s "
                    "(requirements.from_s), at or after the cases' stop time 0.5 s"), note
    judged = unjudged + [{"scene": "ship_stabilization", "status": "ok", "requirements_met": True, "stop_time": 3.0}]
    assert requirements_note(scene, judged) is None
    no_requirements = REPO / "scenes" / "free_swing.toml"
    assert "no [requirements]" in requirements_note(no_requirements, [{**row, "scene": "free_swing"} for row in unjudged])
