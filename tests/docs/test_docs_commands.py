"""Every command the README and docs/*.md show is run as written, from the repository's root as a newcomer
would after `bash scripts/run.sh`, and what it prints is compared with what the pages say of it: each
figure a page quotes from a command's output must be in that output, to the digits the page prints.

The commands are the lines of every fenced `sh` block (a line ending in a backslash goes on; `# ...`
comments are dropped); the same command on two pages runs once. A page's `python` blocks run too. What
a page shows of a command's output is declared in QUOTES: a shown output line, or a figure of a
sentence, with the command it is from; each must be in the page as well as in the output (wall times
and real-time factors, which depend on the machine, are compared as T and R). A page that shows the
output of a command it names in prose (no `sh` block) has that command in PROSE_COMMANDS.

Not run, each with its reason: NOT_RUN; those of them that take minutes (SLOW) run with
GIMBAL_DOCS_SLOW=1. A command that would write into the repository's tracked files
runs with its output folder moved (MOVED_OUT). Outputs go where the pages say (results/, which git
ignores)."""
import os
import pathlib
import re
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.M | re.S)
G2A = ".venv/bin/gimbal2axis"

TUNE = f"{G2A} tune scenes/ship_stabilization.toml tunings/ship_pid.toml --workers 2"
# Run only with GIMBAL_DOCS_SLOW=1, which also compares what they print with QUOTES.
SLOW = {
    TUNE: "96 candidates x 8 runs of 12 s: 95 s measured on 2 cores, 657 s at load average 16 (issue 46); "
          "its first 24 candidates run instead (PROSE_COMMANDS), whose figures docs/tuning.md gives too",
}
NOT_RUN = {
    "bash scripts/test.sh": "the command that runs this test",
    **({} if os.environ.get("GIMBAL_DOCS_SLOW") == "1" else SLOW),
    "cp results/ship_jitter_20min.png results/ship_jitter_20min_spectrum.png docs/figures/":
        "the maintainer's update of the figures in git: the run before it is tested",
    ".venv/bin/python -m fmpy compile Gimbal2Axis.fmu":
        "compiles the core from the FMU's sources (minutes on 2 cores; tests/fmu/test_fmi3.py builds a source FMU)",
    'gcc -c -O2 -fPIC -I. -I"$FMI2_HEADERS" fmi_layer/*.c':
        "inside an extracted FMU's sources/: the source build, as above",
    'g++ -shared -O2 -fPIC -std=c++17 -I. -I"$FMI2_HEADERS" */*.cpp *.o -o ../binaries/linux64/Gimbal2Axis.so':
        "inside an extracted FMU's sources/: the source build, as above",
}
# docs/benchmarks.md: the benchmark suite's own commands (builds, minutes of measurements, callgrind over
# git revisions); the page is their report.
BENCHMARK_PAGE = REPO / "docs" / "benchmarks.md"

MOVED_OUT = {"--out docs/figures": "--out results/docs_commands/figures"}   # docs/figures is in git

# Commands a page names in prose and shows the output of.
FREQRESP_UNBALANCED = f"{G2A} freqresp open-loop --axis 1 --amplitude 1 --fmin 1 --fmax 30 --points 5 --serial"
LINEARIZE_STUCK = (f"{G2A} linearize --set gear1.model=0 --set motor1.model=0 --set base.fixed=true "
                   f"--out results/azimuth_stuck.npz --bode u_R1:alpha_dot")
TUNE_24 = f"{TUNE} --trials 24 --out results/tuning_24"
PROSE_COMMANDS = {
    f"{G2A} run examples/ship_jitter.toml": "docs/jitter.md: `examples/ship_jitter.toml` ... with these bands",
    FREQRESP_UNBALANCED: "docs/frequency_response.md: the README's example with the payload as the scene has it",
    LINEARIZE_STUCK: "docs/linearization.md: the same command without --set dry_friction=false",
    TUNE_24: "README.md and docs/tuning.md: what --trials 24 gives",
}

LINEARIZE = (f"{G2A} linearize --set gear1.model=0 --set motor1.model=0 --set dry_friction=false "
             f"--set base.fixed=true --out results/azimuth.npz --bode u_R1:alpha_dot")
RUN_SHIP = f"{G2A} run scenes/ship_stabilization.toml"
SWEEP = f"{G2A} sweep scenes/ship_stabilization.toml sweeps/gains_1000.toml --workers 2"
LOOP_GAIN = f"{G2A} freqresp loop-gain --axis 1 --amplitude 0.2 --serial --out docs/figures"


def shown_lines(page: str, first: str) -> list[tuple[str, str]]:
    """The lines of the page's output block that starts with `first`, as quotes."""
    for _, body in FENCE.findall((REPO / page).read_text(encoding="utf-8")):
        if body.startswith(first):
            return [(page, line) for line in body.strip().splitlines()]
    raise AssertionError(f"{page}: no block starts with {first!r}")


# {command: [(page, what the page shows of its output)]}
QUOTES = {
    RUN_SHIP: shown_lines("README.md", "ship_stabilization: 60 s simulated"),
    LINEARIZE: [("README.md", "u_R1 -> alpha_dot: DC gain 0.2063 (-13.71 dB), -3 dB at 4.175 Hz"),
                ("docs/linearization.md", "u_R1 -> alpha_dot: DC gain 0.2063 (-13.71 dB), -3 dB at 4.175 Hz"),
                ("docs/linearization.md", "-26.23"), ("docs/frequency_response.md", "0.206"),
                ("docs/frequency_response.md", "-13.7"), ("docs/frequency_response.md", "4.175 Hz")],
    LINEARIZE_STUCK: shown_lines("docs/linearization.md", "gimbal2axis linearize: warning: u_R1 -> alpha_dot"),
    f"{G2A} system scenes/ship_stabilization.toml --out results/systems":
        [("docs/systems.md", "results/systems/ship_stabilization/osp/OspSystemStructure.xml"),
         ("docs/systems.md", "results/systems/ship_stabilization/ship_stabilization.ssp")],
    SWEEP: [("docs/sweeps.md", "requirements_met is empty in every case: the scene's requirements window starts at "
                               "1 s (requirements.from_s), at or after the cases' stop time 0.5 s")],
    TUNE: [(page, quote) for page in ("README.md", "docs/tuning.md")
           for quote in ("objective 0.10029 mrad", "22.8% lower", "best 0.094241 mrad, scene's own 0.11579 mrad")],
    TUNE_24: [("docs/tuning.md", "the best not 1 % lower: the search has not left the start yet; give it more --trials"),
              ("docs/tuning.md", "trial 22"), ("docs/tuning.md", "0.12926 mrad"), ("docs/tuning.md", "0.12304 mrad"),
              ("docs/tuning.md", "objective 0.12983 mrad")],
    f"{G2A} run scenes/ship_jitter_20min.toml": shown_lines("docs/jitter.md", "ship_jitter_20min: 1200 s simulated"),
    f"{G2A} run examples/ship_jitter.toml": shown_lines("docs/jitter.md", "ship_jitter: 300 s simulated"),
    FREQRESP_UNBALANCED: shown_lines("docs/frequency_response.md", "not a frequency response to 1 % and 1 deg "
                                                                   "(CSV column marks, grey in the plot; "
                                                                   "docs/frequency_response.md): full model 10")
                         + shown_lines("docs/frequency_response.md", "gimbal2axis freqresp: warning: 10 of 20"),
    LOOP_GAIN: shown_lines("docs/frequency_response.md", "linear model, loop gain at"),
}


def shell_commands(page: pathlib.Path) -> list[str]:
    commands = []
    for language, body in FENCE.findall(page.read_text(encoding="utf-8")):
        if language != "sh":
            continue
        joined = re.sub(r"\\\n\s*", " ", body)
        for line in joined.splitlines():
            line = re.sub(r"\s+#.*$", "", line).strip()
            if line and not line.startswith("#"):
                commands.append(" ".join(line.split()))
    return commands


def every_command() -> dict:
    """{command: [pages showing it]}, in the order of the pages."""
    found: dict = {}
    for page in PAGES:
        for command in shell_commands(page):
            found.setdefault(command, []).append(page.name)
    return found


def commands_to_run() -> list[str]:
    shown = [c for c, pages in every_command().items()
             if c not in NOT_RUN and pages != [BENCHMARK_PAGE.name]]
    return shown + [c for c in PROSE_COMMANDS if c not in shown]


def normalized(text: str) -> str:
    """Without what depends on the machine (wall time, real-time factor) and with one space for any run
    of white space (a page wraps its sentences)."""
    text = re.sub(r"in [\d.]+ s wall \([\d.]+x real time\)", "in T s wall (Rx real time)", text)
    return " ".join(text.split())


def environment():
    env = dict(os.environ)
    env.pop("LD_PRELOAD", None)
    env["MPLBACKEND"] = "Agg"
    return env


def run(command: str) -> subprocess.CompletedProcess:
    for shown, moved in MOVED_OUT.items():
        command = command.replace(shown, moved)
    return subprocess.run(command, shell=True, cwd=REPO, capture_output=True, text=True, env=environment(),
                          timeout=900)


# Runs the commands the pages show: its time goes to Python and the commands' processes.
pytestmark = [pytest.mark.python_bound,
              pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                                 reason="documentation commands: the release pass runs them")]


def test_every_command_is_run_or_declared_not_run_with_its_reason():
    shown = every_command()
    for command in NOT_RUN:
        assert command in shown, f"NOT_RUN names a command no page shows any more: {command}"
    assert set(QUOTES) <= set(commands_to_run()) | set(SLOW), set(QUOTES) - set(commands_to_run())
    assert {"README.md", "tuning.md", "linearization.md", "frequency_response.md", "jitter.md", "sweeps.md",
            "systems.md", "sensors.md"} <= {page for pages in shown.values() for page in pages}


@pytest.mark.parametrize("command", commands_to_run())
def test_each_command_runs_and_prints_what_the_pages_say(command):
    done = run(command)
    assert done.returncode == 0, f"{command}\nexit {done.returncode}\n{done.stderr[-3000:]}"
    printed = normalized(done.stdout + "\n" + done.stderr)
    for page, quote in QUOTES.get(command, []):
        assert normalized(quote) in normalized((REPO / page).read_text(encoding="utf-8")), \
            f"{page} no longer shows {quote!r}: update QUOTES with the page"
        assert normalized(quote) in printed, f"{page} shows {quote!r}; `{command}` printed:\n{done.stdout}\n{done.stderr}"


def python_blocks() -> list[tuple[str, int, str]]:
    blocks = []
    for page in PAGES[1:]:   # the README's python example: tests/docs/test_readme_commands.py, tests/model_core/model/test_relaxed_start.py
        bodies = [body for language, body in FENCE.findall(page.read_text(encoding="utf-8")) if language == "python"]
        blocks += [(page.name, index, body) for index, body in enumerate(bodies)]
    return blocks


@pytest.mark.parametrize("page, index, code", python_blocks(), ids=[f"{p}-{i}" for p, i, _ in python_blocks()])
def test_each_python_block_of_the_docs_runs(page, index, code):
    if "results/ship_stabilization.parquet" in code and not (REPO / "results" / "ship_stabilization.parquet").exists():
        assert run(RUN_SHIP).returncode == 0   # the file the block reads, as the README's run writes it
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, env=environment(),
                          timeout=300)
    assert done.returncode == 0, f"{page}, python block {index}:\n{done.stderr[-3000:]}"
