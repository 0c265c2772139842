"""One tool: every subcommand refuses a bad argument in one line on stderr with exit status 2, lists
its exit statuses in --help, answers --version, ends with 130 on Ctrl-C without a traceback, and is
quiet under --quiet (nothing on stdout; on stderr only errors and warnings)."""
import pathlib
import re
import signal
import subprocess
import sys

import pytest

from gimbal2axis import __version__
from gimbal2axis.cli import main as cli_main

pytestmark = pytest.mark.python_bound

ROOT = pathlib.Path(__file__).resolve().parents[3]
COMMAND = [sys.executable, "-m", "gimbal2axis"]
SUBCOMMANDS = ["run", "sweep", "linearize", "freqresp", "system", "report", "bench", "tune"]

# Per subcommand, a refusal that only the subcommand's own checks make (argparse accepts the values),
# and what its one line must name.
BAD_VALUES = {
    "run": (["scenes/free_swing.toml", "--stop-time", "1e-300"], ["--stop-time 1e-300", "0.001 s"]),
    "sweep": (["scenes/free_swing.toml", "sweeps/gains_1000.toml", "--workers", "0"], ["--workers"]),
    "linearize": (["--set", "beta"], ["--set 'beta'", "NAME=VALUE"]),
    "freqresp": (["open-loop", "--points", "0"], ["--points 0"]),
    "system": (["no_such_scene.toml"], ["no_such_scene.toml"]),
    "report": (["no_such_comparison.toml"], ["no_such_comparison.toml"]),
    "bench": (["--repeat", "0"], ["--repeat 0"]),
    "tune": (["a.toml", "b.toml", "--workers", "0"], ["--workers"]),
}
# The statuses each --help must list beyond 0, 2 and 130, which all list.
MORE_STATUSES = {"run": [1, 3, 143], "sweep": [1, 143], "bench": [1], "tune": [1, 143]}


def command(*args, timeout=120):
    return subprocess.run([*COMMAND, *args], capture_output=True, text=True, cwd=ROOT, timeout=timeout)


def assert_one_line_refusal(done, subcommand: str, *named: str) -> None:
    assert done.returncode == 2, (done.returncode, done.stderr)
    lines = done.stderr.splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith(f"gimbal2axis {subcommand}: error: "), lines[0]
    for fragment in named:
        assert fragment in lines[0], (fragment, lines[0])
    assert done.stdout == ""


# The positional arguments a subcommand requires (else their absence is what is refused).
REQUIRED = {"sweep": ["a.toml", "b.toml"], "freqresp": ["open-loop"], "system": ["a.toml"], "tune": ["a.toml", "b.toml"]}


@pytest.mark.parametrize("subcommand", SUBCOMMANDS)
def test_an_unknown_option_is_refused_in_one_line(subcommand):
    done = command(subcommand, *REQUIRED.get(subcommand, []), "--no-such-option")
    assert_one_line_refusal(done, subcommand, "--no-such-option", f"see gimbal2axis {subcommand} --help")


@pytest.mark.parametrize("subcommand", SUBCOMMANDS)
def test_a_bad_value_is_refused_in_one_line_naming_it(subcommand):
    arguments, named = BAD_VALUES[subcommand]
    assert_one_line_refusal(command(subcommand, *arguments), subcommand, *named)


def test_a_value_argparse_cannot_read_is_refused_in_one_line():
    assert_one_line_refusal(command("run", "--stop-time", "soon"), "run", "--stop-time", "'soon'")


def test_an_unknown_subcommand_is_refused_in_one_line():
    done = command("runn")
    assert done.returncode == 2 and len(done.stderr.splitlines()) == 1, done.stderr
    assert done.stderr.startswith("gimbal2axis: error: ") and "'runn'" in done.stderr


@pytest.mark.parametrize("stop_time", ["1e-300", "0.0004"])
def test_run_refuses_a_stop_time_shorter_than_one_step(stop_time):
    """0 steps would be a run of nothing that reports success."""
    done = command("run", "scenes/free_swing.toml", "--stop-time", stop_time)
    assert_one_line_refusal(done, "run", f"--stop-time {stop_time}", "shorter than one step", "0.001 s")


def exit_statuses_in_help(text: str) -> dict:
    """{status: meaning} of the 'exit status:' block at the end of a --help."""
    block = text[text.index("exit status:\n"):]
    return {int(m.group(1)): m.group(2) for m in re.finditer(r"^  (\d+)\s+(.+)$", block, re.MULTILINE)}


@pytest.mark.parametrize("subcommand", SUBCOMMANDS)
def test_help_lists_the_exit_statuses(subcommand):
    done = command(subcommand, "--help")
    assert done.returncode == 0 and done.stderr == ""
    statuses = exit_statuses_in_help(done.stdout)
    assert {0, 2, 130} | set(MORE_STATUSES.get(subcommand, [])) <= set(statuses), statuses
    assert "interrupted" in statuses[130]


def test_the_top_level_help_lists_every_exit_status():
    done = command("--help")
    assert done.returncode == 0
    for status in ("0", "1", "2", "3", "130", "143"):
        assert re.search(rf"^  {status}\s+\S", done.stdout, re.MULTILINE), status


@pytest.mark.parametrize("where", [[], ["run"], ["bench"]])
def test_version(where):
    done = command(*where, "--version")
    assert done.returncode == 0 and done.stdout == f"gimbal2axis {__version__}\n" and done.stderr == ""


# Ctrl-C: the first step of each subcommand's work raises KeyboardInterrupt, as a SIGINT there would;
# each must end with 130 and one line, no traceback. (tests/package/master/test_run_partial.py sends real signals to runs.)
INTERRUPTED_AT = {
    "run": ("gimbal2axis.cli.run", "_run", ["run"]),
    "sweep": ("gimbal2axis.cli.sweep", "fmu_path", ["sweep", "a.toml", "b.toml"]),
    "linearize": ("gimbal2axis.cli.linearize", "linearize_and_write", ["linearize"]),
    "freqresp": ("gimbal2axis.cli.freqresp", "measure_and_write", ["freqresp", "open-loop"]),
    "system": ("gimbal2axis.cli.system", "_write", ["system", "a.toml"]),
    "report": ("gimbal2axis.cli.report", "_report", ["report"]),
    "bench": ("gimbal2axis.cli.bench", "scene_file", ["bench"]),
    "tune": ("gimbal2axis.cli.tune", "fmu_path", ["tune", "a.toml", "b.toml"]),
}


@pytest.mark.parametrize("subcommand", SUBCOMMANDS)
def test_ctrl_c_ends_with_130_in_one_line(subcommand, monkeypatch, capsys):
    module_name, function, argv = INTERRUPTED_AT[subcommand]

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(f"{module_name}.{function}", interrupted)
    handlers = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
    try:
        status = cli_main.main(argv)
    finally:   # the subcommands install their own handlers; pytest's are put back
        for signum, handler in handlers.items():
            signal.signal(signum, handler)
    captured = capsys.readouterr()
    assert status == 130, captured.err
    lines = [line for line in captured.err.splitlines() if line.strip()]
    assert len(lines) == 1 and "interrupted" in lines[0] and "Traceback" not in captured.err, captured.err
    assert captured.out == ""


def test_run_quiet_prints_nothing_but_warnings(fmu_path, tmp_path):
    """--quiet: no summary, no list of files (a warning of the scene's own, no controller here, still shows)."""
    arguments = ["run", "scenes/free_swing.toml", "--stop-time", "0.02", "--fmu", str(fmu_path)]
    loud = command(*arguments, "--out", str(tmp_path / "loud"))
    assert loud.returncode == 0 and "wrote" in loud.stdout and "simulated" in loud.stdout
    quiet = command(*arguments, "--out", str(tmp_path / "quiet"), "--quiet")
    assert quiet.returncode == 0, quiet.stderr
    assert quiet.stdout == ""
    assert all(": warning: " in line for line in quiet.stderr.splitlines()), quiet.stderr
    assert (tmp_path / "quiet" / "free_swing.csv").is_file()


def test_run_check_says_why_it_ends_with_1_also_when_quiet(fmu_path, tmp_path):
    """Exit status 1 (ran, a requirement not met) comes with its reason on stderr: under --quiet it is
    the only line."""
    scene = tmp_path / "strict_ship.toml"
    scene.write_text((ROOT / "scenes" / "ship_stabilization.toml").read_text()
                     .replace("los_rms_max_mrad = 0.3", "los_rms_max_mrad = 1e-6"))
    done = command("run", str(scene), "--stop-time", "1.2", "--check", "--quiet", "--fmu", str(fmu_path),
                   "--out", str(tmp_path / "out"))
    assert done.returncode == 1, done.stderr
    assert done.stdout == ""
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("gimbal2axis run: requirements not met: RMS LOS error"), lines
