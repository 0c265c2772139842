"""The README's commands run as written: every fenced `sh` block (one command per line) and every
`python` block is extracted from README.md and run from the repository's root, as a newcomer would
after `bash scripts/run.sh`. `bash scripts/test.sh` is the command that runs this test, so it is not
run again here; `bash scripts/run.sh` is (it finds everything installed and built, and runs the
default scene). Outputs go where the README says (results/, which git ignores).

A block the README shows as output (no language tag) is compared with what its command printed, up to
the figures that change from run to run (wall time and real-time factor)."""
import os
import pathlib
import re
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
README = REPO / "README.md"
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.M | re.S)
NOT_HERE = {"bash scripts/test.sh"}   # the command that runs this test

pytestmark = [pytest.mark.python_bound,
              pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                                 reason="documentation commands: the release pass runs them")]


def blocks():
    return [(language, body) for language, body in FENCE.findall(README.read_text(encoding="utf-8"))]


def shell_commands():
    commands = []
    for language, body in blocks():
        if language == "sh":
            commands += [line.strip() for line in body.splitlines() if line.strip() and not line.startswith("#")]
    return commands


def test_the_readme_has_the_two_commands_and_a_tour():
    commands = shell_commands()
    assert commands[:2] == ["bash scripts/run.sh", "bash scripts/test.sh"], commands[:2]
    tour = [c.split()[1] for c in commands if c.startswith(".venv/bin/gimbal2axis ")]
    assert sorted(set(tour)) == ["bench", "freqresp", "linearize", "report", "run", "sweep", "system", "tune"], tour
    words = len(README.read_text(encoding="utf-8").split())
    assert words <= 1800, f"the README has {words} words; a newcomer reads about 1,500 in five minutes"


def environment():
    env = dict(os.environ)
    env.pop("LD_PRELOAD", None)
    env["MPLBACKEND"] = "Agg"
    return env


@pytest.mark.parametrize("command", [c for c in shell_commands() if c not in NOT_HERE])
def test_each_readme_command_runs_as_written(command):
    done = subprocess.run(command, shell=True, cwd=REPO, capture_output=True, text=True, env=environment(),
                          timeout=600)
    assert done.returncode == 0, f"{command}\nexit {done.returncode}\n{done.stderr[-3000:]}"


def normalized(line: str) -> str:
    """A summary line without what depends on the machine: the wall time and the real-time factor."""
    return re.sub(r"in [\d.]+ s wall \([\d.]+x real time\)", "in T s wall (Rx real time)", line.strip())


def test_the_output_the_readme_shows_is_what_the_command_prints():
    shown = [body for language, body in blocks() if language == ""]
    assert shown, "the README shows no output"
    for body in shown:
        line = body.strip().splitlines()[0]
        scene = line.split(":", 1)[0]
        command = next(c for c in shell_commands() if c.startswith(".venv/bin/gimbal2axis run ") and scene in c)
        done = subprocess.run(command, shell=True, cwd=REPO, capture_output=True, text=True, env=environment(),
                              timeout=600)
        assert done.returncode == 0, done.stderr
        printed = [normalized(out) for out in done.stdout.splitlines()]
        assert normalized(line) in printed, (line, done.stdout)


@pytest.mark.parametrize("index", range(sum(1 for language, _ in blocks() if language == "python")))
def test_each_readme_python_example_runs(index):
    code = [body for language, body in blocks() if language == "python"][index]
    done = subprocess.run([str(REPO / ".venv" / "bin" / "python"), "-c", code], cwd=REPO, capture_output=True,
                          text=True, env=environment(), timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip(), "the example prints nothing"


def test_the_readme_frequency_response_is_one_where_the_linear_curve_is_measured():
    """The README's freqresp example balances the payload: the linear fidelity's points are all a
    frequency response and nothing is warned about (issue 34: it measured the payload falling over,
    silently). The full model's are marked, as the README says: backlash and friction."""
    command = next(c for c in shell_commands() if c.startswith(".venv/bin/gimbal2axis freqresp "))
    done = subprocess.run(command.replace(" --serial", " --serial --out results/readme_freqresp_check"), shell=True,
                          cwd=REPO, capture_output=True, text=True, env=environment(), timeout=600)
    assert done.returncode == 0, done.stderr
    assert "warning" not in done.stderr, done.stderr
    points = re.search(r"full model (\d+) of (\d+).*no backlash, no dry friction (\d+) of (\d+)", done.stdout)
    assert points, done.stdout
    full_marked, full_total, linear_marked, linear_total = map(int, points.groups())
    assert linear_marked == 0 and linear_total > 0
    assert full_marked == full_total, "the README says the full model's points are all marked"
