"""Issue 44, items 7 and 8: every size an input asks for is bounded before anything is allocated for
it, and every hostile number, nesting or service ends in one line with exit status 2, never a
traceback. One test per attack; each calls the command in-process (gimbal2axis.cli.main.main) under an
address-space limit, so that an attack that allocates ends in a MemoryError instead of taking the
machine's memory."""
import contextlib
import resource
import signal
import socket
import threading

import pytest

from gimbal2axis.cli.main import main
from gimbal2axis.limits import (MAX_ANALYSIS_BANDS, MAX_DELAY_STEPS, MAX_DESCRIPTION_CHARS, MAX_PLOT_PANELS,
                                MAX_PLOT_SIGNALS, MAX_SCENARIOS, MAX_SEA_STATE_COMPONENTS, MAX_STEPS, MAX_SWEEP_CASES,
                                MAX_TOML_BYTES, MAX_TOML_DEPTH, MAX_TUNE_BATCH, MAX_TUNE_PARAMETERS, MAX_TUNE_TRIALS)

pytestmark = pytest.mark.memory_limit

# A sea-state scene with a PID on a fixed target: each attack changes one line of it.
SCENE = """name = "bounds"
stop_time = 0.02
step_size = 1e-3
[fidelity]
"base.fixed" = false
[base_motion]
type = "sea_state"
components = 10
seed = 1
roll = { significant_amplitude_deg = 1.0, peak_period_s = 8.0 }
[target]
azimuth_deg = 10.0
elevation_deg = 5.0
[controller]
type = "pid"
reference = "target"
delay_steps = 1
[controller.azimuth]
kp = 100.0
[controller.elevation]
kp = 100.0
"""
SWEEP = """stop_time = 0.01
cases = 2
[grid]
"controller.azimuth.kp" = [100.0, 200.0]
"""
TUNING = """stop_time = 0.01
[parameters]
"controller.azimuth.kp" = { bounds = [50.0, 500.0], scale = "log" }
[optimizer]
sampler = "random"
trials = 2
batch = 2
"""
# Headroom of address space above what the test process already maps: a run of these scenes needs far
# less, the attacks (7 GiB of sinusoids, 15 TiB of delayed commands, 3 EiB for a handshake) far more.
HEADROOM_BYTES = 3 << 30
# A refusal comes at once; an attack that is not refused (a tuning of 10**9 trials) would run for days.
REFUSAL_WITHIN_S = 60


class TookTooLong(BaseException):
    """Raised by the alarm in the command's place, past REFUSAL_WITHIN_S (no handler of it catches it)."""


@contextlib.contextmanager
def bounded_time():
    def alarm(signum, frame):
        raise TookTooLong(f"no refusal within {REFUSAL_WITHIN_S} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(REFUSAL_WITHIN_S)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


@contextlib.contextmanager
def address_space_limit():
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    with open("/proc/self/status") as status:
        mapped = next(int(line.split()[1]) * 1024 for line in status if line.startswith("VmSize:"))
    limit = mapped + HEADROOM_BYTES
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def refusal(capsys, *argv) -> str:
    """The one error line of the command `argv`, which must end with exit status 2 and no traceback."""
    with address_space_limit(), bounded_time():
        try:
            status = main([str(a) for a in argv])
        except SystemExit as exc:   # argparse's refusal of an argument
            status = exc.code
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    errors = [line for line in err.splitlines() if ": error: " in line]
    assert status == 2 and len(errors) == 1, (status, err[-2000:])
    assert errors[0].startswith(f"gimbal2axis {argv[0]}: error: "), errors[0]
    assert len(errors[0]) < 600, errors[0]
    return errors[0]


def write(folder, name: str, text: str):
    path = folder / name
    path.write_text(text)
    return path


def scene_with(folder, old: str, new: str, name: str = "bounds.toml"):
    assert old in SCENE
    return write(folder, name, SCENE.replace(old, new))


def run_refusal(capsys, tmp_path, scene) -> str:
    return refusal(capsys, "run", scene, "--out", tmp_path / "out", "--quiet")


# --- item 7: sizes ---

@pytest.mark.parametrize("old, new, key", [
    ("components = 10", "components = 1000000000", "base_motion.components = 1000000000"),
    ("peak_period_s = 8.0 }", "peak_period_s = 8.0, components = 1000000000 }", "base_motion.roll.components"),
])
def test_sea_state_components_over_the_limit_are_refused(capsys, tmp_path, old, new, key):
    line = run_refusal(capsys, tmp_path, scene_with(tmp_path, old, new))
    assert key in line and f"{MAX_SEA_STATE_COMPONENTS:,}" in line


PANELS = "".join(f'"panel {i}" = ["alpha"]\n' for i in range(MAX_PLOT_PANELS + 1))
BANDS = "".join(f"b{i} = [0.0, 1.0]\n" for i in range(MAX_ANALYSIS_BANDS + 1))
SINUSOIDS = "[" + ", ".join(["{ amplitude_deg = 0.1, period_s = 5.0 }"] * (MAX_SEA_STATE_COMPONENTS + 1)) + "]"


@pytest.mark.parametrize("added, named", [
    ("[plot]\n" + PANELS, f"[plot]: the number of panels = {MAX_PLOT_PANELS + 1} is over the limit of {MAX_PLOT_PANELS}"),
    ('[plot]\nangles = [' + ", ".join(['"alpha"'] * (MAX_PLOT_SIGNALS + 1)) + "]\n",
     f"[plot] angles: the number of signals = {MAX_PLOT_SIGNALS + 1} is over the limit of {MAX_PLOT_SIGNALS}"),
    ("[analysis.bands]\n" + BANDS, f"the number of bands = {MAX_ANALYSIS_BANDS + 1} is over the limit of {MAX_ANALYSIS_BANDS}"),
])
def test_scene_tables_with_too_many_entries_are_refused(capsys, tmp_path, added, named):
    line = run_refusal(capsys, tmp_path, write(tmp_path, "bounds.toml", SCENE + added))
    assert named in line


def test_a_sum_of_more_sinusoids_than_the_limit_is_refused(capsys, tmp_path):
    scene = scene_with(tmp_path, 'type = "sea_state"\ncomponents = 10\nseed = 1\n'
                       'roll = { significant_amplitude_deg = 1.0, peak_period_s = 8.0 }',
                       f'type = "sinusoids"\nroll = {SINUSOIDS}')
    line = run_refusal(capsys, tmp_path, scene)
    assert f"base_motion.roll: the number of sinusoids = {MAX_SEA_STATE_COMPONENTS + 1:,}" in line or \
        f"base_motion.roll: the number of sinusoids = {MAX_SEA_STATE_COMPONENTS + 1}" in line


def test_a_tuning_of_more_parameters_than_the_limit_is_refused(capsys, tmp_path):
    parameters = "".join(f'"controller.azimuth.p{i}" = {{ bounds = [1.0, 2.0] }}\n' for i in range(MAX_TUNE_PARAMETERS + 1))
    tuning = write(tmp_path, "t.toml", TUNING.replace('[parameters]\n', '[parameters]\n' + parameters))
    line = refusal(capsys, "tune", write(tmp_path, "bounds.toml", SCENE), tuning, "--serial", "--out", tmp_path)
    assert f"the number of tuned parameters = {MAX_TUNE_PARAMETERS + 2} is over the limit of {MAX_TUNE_PARAMETERS:,}" in line


def test_a_delay_of_a_trillion_steps_is_refused(capsys, tmp_path):
    line = run_refusal(capsys, tmp_path, scene_with(tmp_path, "delay_steps = 1", "delay_steps = 1000000000000"))
    assert "delay_steps = 1000000000000" in line and f"{MAX_DELAY_STEPS:,}" in line


def test_a_description_over_the_limit_is_refused(capsys, tmp_path):
    scene = scene_with(tmp_path, 'name = "bounds"', f'name = "bounds"\ndescription = "{"x" * 20_000}"')
    line = run_refusal(capsys, tmp_path, scene)
    assert "'description' is 20,000 characters long" in line and f"{MAX_DESCRIPTION_CHARS:,}" in line


def test_a_plot_title_takes_a_cut_first_line_of_the_description_literally(capsys, tmp_path):
    """A long description is not wrapped whole into the title (minutes for megabytes), and '$' is no
    mathtext: an unknown \\name between two of them made matplotlib raise when saving the figure."""
    description = "cost $\\\\foo$ in dollars " + "word " * 1500 + "\\nsecond line"
    scene = scene_with(tmp_path, 'name = "bounds"', f'name = "bounds"\ndescription = "{description}"')
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--quiet", "--stop-time", "0.005"]) == 0
    assert (out / "bounds.png").stat().st_size > 0
    from gimbal2axis.master.plotting import run_title
    from gimbal2axis.scene import load_scene
    title = run_title(load_scene(scene))
    assert title.startswith("bounds: cost $\\foo$") and len(title) < 300 and "second line" not in title


@pytest.mark.parametrize("kind", ["track", "recorded motion", "scene file"])
def test_dev_zero_as_an_input_file_is_refused_after_a_bounded_read(capsys, tmp_path, kind):
    if kind == "track":
        scene = scene_with(tmp_path, "azimuth_deg = 10.0\nelevation_deg = 5.0",
                           'type = "track"\nfile = "/dev/zero"\n[target.carrier]\nlatitude_deg = 50.0\n'
                           'longitude_deg = 0.0')
    elif kind == "recorded motion":
        scene = scene_with(tmp_path, 'type = "sea_state"\ncomponents = 10\nseed = 1\n'
                           'roll = { significant_amplitude_deg = 1.0, peak_period_s = 8.0 }',
                           'type = "recorded"\nfile = "/dev/zero"')
    else:
        scene = "/dev/zero"
    line = run_refusal(capsys, tmp_path, scene)
    assert "/dev/zero" in line and "limit of" in line


def test_a_toml_file_over_the_limit_is_refused(capsys, tmp_path):
    scene = write(tmp_path, "big.toml", SCENE + "#" * MAX_TOML_BYTES + "\n")
    line = run_refusal(capsys, tmp_path, scene)
    assert f"{MAX_TOML_BYTES:,}" in line


def test_a_sweep_linspace_of_a_billion_values_is_refused_even_with_two_cases(capsys, tmp_path):
    sweep = write(tmp_path, "s.toml", SWEEP.replace('[100.0, 200.0]', '{ linspace = [1.0, 2.0, 1000000000] }'))
    line = refusal(capsys, "sweep", write(tmp_path, "bounds.toml", SCENE), sweep, "--serial", "--out", tmp_path)
    assert "linspace count = 1000000000" in line and f"{MAX_SWEEP_CASES:,}" in line


def test_a_sweep_of_a_billion_samples_is_refused(capsys, tmp_path):
    sweep = write(tmp_path, "s.toml", "stop_time = 0.01\ncases = 2\nsamples = 1000000000\n[random]\n"
                                      '"controller.azimuth.kp" = { uniform = [50.0, 500.0] }\n')
    line = refusal(capsys, "sweep", write(tmp_path, "bounds.toml", SCENE), sweep, "--serial", "--out", tmp_path)
    assert "'samples' = 1000000000" in line and f"{MAX_SWEEP_CASES:,}" in line


def test_a_sweep_grid_of_a_billion_points_runs_only_its_cases(capsys, tmp_path):
    """The cases are taken from the product lazily: `cases = 2` of a 1000 x 1000 x 1000 grid runs 2; without
    the limit the grid is refused by its size."""
    grid = "".join(f'"controller.azimuth.{gain}" = {{ linspace = [1.0, 2.0, 1000] }}\n' for gain in ("kp", "ki", "kd"))
    scene = write(tmp_path, "bounds.toml", SCENE)
    limited = write(tmp_path, "limited.toml", f"stop_time = 0.005\ncases = 2\n[grid]\n{grid}")
    with address_space_limit():
        assert main(["sweep", str(scene), str(limited), "--serial", "--quiet", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    unlimited = write(tmp_path, "unlimited.toml", f"stop_time = 0.005\n[grid]\n{grid}")
    line = refusal(capsys, "sweep", scene, unlimited, "--serial", "--out", tmp_path)
    assert "1,000,000,000 cases is over the limit" in line


@pytest.mark.parametrize("old, new, named", [
    ("trials = 2", "trials = 1000000000", f"[optimizer] trials = 1000000000 is over the limit of {MAX_TUNE_TRIALS:,}"),
    ("batch = 2", "batch = 1000000000", f"[optimizer] batch = 1000000000 is over the limit of {MAX_TUNE_BATCH:,}"),
    ("[optimizer]", '[robustness]\ndraws = 1000000000\n[robustness.draw]\n"body2.m" = { uniform = [1.0, 2.0] }\n'
                    "[optimizer]", f"[robustness] draws = 1000000000 is over the limit of {MAX_SCENARIOS:,}"),
])
def test_tuning_sizes_over_the_limit_are_refused(capsys, tmp_path, old, new, named):
    tuning = write(tmp_path, "t.toml", TUNING.replace(old, new))
    line = refusal(capsys, "tune", write(tmp_path, "bounds.toml", SCENE), tuning, "--serial", "--out", tmp_path)
    assert named in line


# --- item 8: numbers, nesting, services ---

def test_a_stop_time_of_1e308_is_refused_by_run(capsys, tmp_path):
    line = run_refusal(capsys, tmp_path, scene_with(tmp_path, "stop_time = 0.02", "stop_time = 1e308"))
    assert "stop_time = 1e+308 s" in line and f"{MAX_STEPS:,} steps" in line


def test_an_output_interval_of_1e300_is_refused(capsys, tmp_path):
    line = run_refusal(capsys, tmp_path, scene_with(tmp_path, "step_size = 1e-3", "step_size = 1e-3\noutput_interval = 1e300"))
    assert "output_interval = 1e+300 s" in line and f"{MAX_STEPS:,} steps" in line


def test_a_stop_time_of_1e308_is_refused_by_sweep(capsys, tmp_path):
    sweep = write(tmp_path, "s.toml", SWEEP.replace("stop_time = 0.01", "stop_time = 1e308"))
    line = refusal(capsys, "sweep", write(tmp_path, "bounds.toml", SCENE), sweep, "--serial", "--out", tmp_path)
    assert "stop_time = 1e+308 s" in line and f"{MAX_STEPS:,} steps" in line


def test_a_stop_time_of_1e308_is_refused_by_tune(capsys, tmp_path):
    tuning = write(tmp_path, "t.toml", TUNING.replace("stop_time = 0.01", "stop_time = 1e308"))
    line = refusal(capsys, "tune", write(tmp_path, "bounds.toml", SCENE), tuning, "--serial", "--out", tmp_path)
    assert "stop_time = 1e+308 s" in line and f"{MAX_STEPS:,} steps" in line


def test_linearize_at_time_1e308_is_refused(capsys, tmp_path):
    line = refusal(capsys, "linearize", "--scene", write(tmp_path, "bounds.toml", SCENE), "--at-time", "1e308",
                   "--out", tmp_path / "x.npz")
    assert "--at-time = 1e+308 s" in line and f"{MAX_STEPS:,} steps" in line


def test_an_analysis_resolution_of_5e_324_hz_is_refused(capsys, tmp_path):
    scene = write(tmp_path, "bounds.toml", SCENE + "[analysis]\nisolation_resolution_hz = 5e-324\n")
    line = run_refusal(capsys, tmp_path, scene)
    assert "analysis.isolation_resolution_hz" in line and f"{MAX_STEPS:,} steps" in line


NESTINGS = {
    "arrays nested 5,000 deep": "x = " + "[" * 5000 + "]" * 5000 + "\n",
    "a 3,000-part dotted key": "a" + ".a" * 3000 + " = 1\n",
    "an integer of 5,000 digits": "x = 1" + "0" * 5000 + "\n",
    "an integer of 10**20": "x = 100000000000000000000\n",
}


@pytest.mark.parametrize("attack", NESTINGS)
@pytest.mark.parametrize("command", ["run", "sweep", "tune"])
def test_toml_nesting_and_integers_beyond_the_parser_are_refused_in_one_line(capsys, tmp_path, command, attack):
    scene = write(tmp_path, "bounds.toml", SCENE)
    # in a table that the loaders flatten recursively (the FMU's dotted names)
    table = {"run": "[parameters]\n", "sweep": "[grid]\n", "tune": "[parameters]\n"}[command]
    base = {"run": SCENE, "sweep": SWEEP, "tune": TUNING}[command]
    hostile = write(tmp_path, "hostile.toml", base.replace(table, table + NESTINGS[attack], 1) if table in base
                    else base + table + NESTINGS[attack])
    argv = {"run": ["run", hostile, "--out", tmp_path],
            "sweep": ["sweep", scene, hostile, "--serial", "--out", tmp_path],
            "tune": ["tune", scene, hostile, "--serial", "--out", tmp_path]}[command]
    line = refusal(capsys, *argv)
    assert "hostile.toml" in line
    if "deep" in attack or "dotted" in attack:
        assert f"limit is {MAX_TOML_DEPTH} levels" in line or f"over the limit of {MAX_TOML_DEPTH}" in line
    else:
        assert "64-bit" in line


def test_sweep_integers_beyond_64_bits_are_refused(capsys, tmp_path):
    sweep = write(tmp_path, "s.toml", 'stop_time = 0.01\ncases = 2\n[random]\n'
                                      '"base_motion.seed" = { integers = [0, 100000000000000000000] }\n')
    line = refusal(capsys, "sweep", write(tmp_path, "bounds.toml", SCENE), sweep, "--serial", "--out", tmp_path)
    assert "integers[1]" in line and "64-bit" in line


def test_tune_bounds_of_plus_minus_1e308_are_refused(capsys, tmp_path):
    tuning = write(tmp_path, "t.toml", TUNING.replace('bounds = [50.0, 500.0], scale = "log"', "bounds = [-1e308, 1e308]"))
    line = refusal(capsys, "tune", write(tmp_path, "bounds.toml", SCENE), tuning, "--serial", "--out", tmp_path)
    assert "bounds = [-1e+308, 1e+308]" in line and "finite" in line


@contextlib.contextmanager
def web_server():
    """A service on 127.0.0.1 that is not a Dask scheduler: it answers every connection as a web server
    does ("HTTP/1.1", which Dask's comm reads as a message of 3 EiB)."""
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(0.2)
    stop = threading.Event()

    def serve():
        while not stop.is_set():
            try:
                connection, _ = server.accept()
            except (socket.timeout, OSError):
                continue
            with connection:
                connection.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n")

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    finally:
        stop.set()
        thread.join()
        server.close()


def test_a_scheduler_address_of_a_web_server_is_refused(capsys, tmp_path):
    scene, sweep = write(tmp_path, "bounds.toml", SCENE), write(tmp_path, "s.toml", SWEEP)
    with web_server() as address:
        line = refusal(capsys, "sweep", scene, sweep, "--scheduler", address, "--out", tmp_path)
    assert address in line and "not a Dask scheduler" in line and "b'HTTP/1.1'" in line


def test_a_tune_of_a_billion_trials_from_the_command_line_is_refused(capsys, tmp_path):
    tuning = write(tmp_path, "t.toml", TUNING)
    line = refusal(capsys, "tune", write(tmp_path, "bounds.toml", SCENE), tuning, "--trials", "1000000000",
                   "--serial", "--out", tmp_path)
    assert f"--trials 1000000000 is over the limit of {MAX_TUNE_TRIALS:,}" in line


def test_a_local_cluster_of_a_million_workers_is_refused_before_starting_one(monkeypatch):
    """Checked in make_client, which sweep, tune and freqresp share; a stand-in for Dask's LocalCluster
    says whether one would have been started (a million processes)."""
    import distributed

    from gimbal2axis.sweep.runner import MAX_LOCAL_WORKERS, make_client
    from gimbal2axis.sweep.spec import SweepError

    started = []

    def local_cluster(*args, n_workers=None, **kwargs):
        started.append(n_workers)
        raise RuntimeError("no cluster in this test")

    monkeypatch.setattr(distributed, "LocalCluster", local_cluster)
    with pytest.raises(SweepError, match=f"--workers 1000000: a local cluster has 1 to {MAX_LOCAL_WORKERS} workers"):
        make_client(None, workers=1_000_000)
    assert started == []


def test_freqresp_refuses_a_scheduler_that_is_not_dask_in_one_line(capsys, tmp_path):
    with web_server() as address:
        line = refusal(capsys, "freqresp", "open-loop", "--scheduler", address, "--no-linear", "--out", tmp_path)
    assert "not a Dask scheduler" in line
