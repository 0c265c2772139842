#!/usr/bin/env python3
"""How fast the command answers: `gimbal2axis --help`, every subcommand's `--help`, `--version`, and
`gimbal2axis run` of the 60-s ship scene (scenes/ship_stabilization.toml, --quiet), each as a whole
process as a user starts it, wall and CPU time (the process's and its children's), best and median of
--repeat runs. Targets (on an idle 2-core machine): every --help under 0.3 s, the ship run under 1.5 s.

Then where the time goes: the modules that take longest to import (`python -X importtime`: their own
time, and the top-level imports by total time) for --help and for the run, and the run's phases by
cProfile (imports, FMU extraction, simulation and writing, spectra, plots).

Writes benchmarks/results/cli_latency.json and prints a table.

Usage: .venv/bin/python benchmarks/cli_latency.py [--repeat 5] [--run-repeat 3] [--out ...]
"""
import argparse
import datetime
import json
import os
import pathlib
import platform
import pstats
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parents[1]
SUBCOMMANDS = ["run", "sweep", "linearize", "freqresp", "system", "report", "bench"]
SHIP_SCENE = REPO / "scenes" / "ship_stabilization.toml"
HELP_TARGET_S, RUN_TARGET_S = 0.3, 1.5
IMPORT_LINE = re.compile(r"^import time:\s+(\d+) \|\s+(\d+) \|( *)(\S+)$")
# The run's phases: the functions whose cumulative time cProfile reports (those missing are left out).
PHASES = {
    "FMU extracted and read": ("fmu.py", "__init__"),
    "simulation, CSV and Parquet (run_streamed)": ("streaming.py", "run_streamed"),
    "  of which the spectra read back from the file": ("streaming.py", "spectra_from_file"),
    "time plot": ("plotting.py", "plot"),
    "spectrum plot": ("plotting.py", "plot_spectrum"),
}


def command() -> list[str]:
    """The installed console script next to this Python, else `python -m gimbal2axis`."""
    script = pathlib.Path(sys.executable).parent / "gimbal2axis"
    return [str(script)] if script.is_file() else [sys.executable, "-m", "gimbal2axis"]


def timed(arguments: list[str], repeat: int) -> dict:
    """Wall and CPU seconds (user + system, of the process and what it started) of `repeat` runs."""
    walls, cpus = [], []
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        done = subprocess.run(arguments, capture_output=True, text=True, cwd=REPO)
        walls.append(time.perf_counter() - start)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
        if done.returncode != 0:
            raise SystemExit(f"{' '.join(arguments)}: exit {done.returncode}\n{done.stderr}")
    return {"wall_best_s": round(min(walls), 4), "wall_median_s": round(statistics.median(walls), 4),
            "cpu_best_s": round(min(cpus), 4), "cpu_median_s": round(statistics.median(cpus), 4),
            "wall_all_s": [round(w, 4) for w in walls]}


def import_times(code: str, top: int) -> dict:
    """-X importtime of `code` in a fresh interpreter: the total, the `top` modules by their own time,
    and the top-level imports (those the code itself triggered) by their cumulative time."""
    done = subprocess.run([sys.executable, "-X", "importtime", "-c", code], capture_output=True, text=True, cwd=REPO)
    if done.returncode != 0:
        raise SystemExit(f"-X importtime failed:\n{done.stderr[-2000:]}")
    rows = []
    for line in done.stderr.splitlines():
        match = IMPORT_LINE.match(line)
        if match:
            own, cumulative, indent, name = match.groups()
            rows.append((name, int(own) / 1e6, int(cumulative) / 1e6, len(indent)))
    outermost = min(depth for *_, depth in rows)
    top_level = [(name, cumulative) for name, _, cumulative, depth in rows if depth == outermost]
    return {"total_s": round(sum(cumulative for _, cumulative in top_level), 4),
            "by_own_time": [{"module": name, "own_s": round(own, 4), "cumulative_s": round(cumulative, 4)}
                            for name, own, cumulative, _ in sorted(rows, key=lambda r: -r[1])[:top]],
            "top_level_by_cumulative_time": [{"module": name, "cumulative_s": round(cumulative, 4)}
                                             for name, cumulative in sorted(top_level, key=lambda r: -r[1])[:top]]}


def run_phases(out: pathlib.Path) -> dict:
    """The ship run under cProfile, in a fresh interpreter: seconds per phase (cProfile's overhead
    included: the proportions, not the absolute figures, are the point)."""
    profile, script = out / "run.prof", out / "profiled_run.py"
    script.write_text("from gimbal2axis.cli.main import main\n"
                      f"assert main(['run', {str(SHIP_SCENE)!r}, '--quiet', '--out', {str(out / 'profiled')!r}]) == 0\n")
    subprocess.run([sys.executable, "-m", "cProfile", "-o", str(profile), str(script)], check=True, cwd=REPO,
                   capture_output=True)
    stats = pstats.Stats(str(profile))
    by_function = {}
    for (filename, _, function), (_, _, _, cumulative, _) in stats.stats.items():
        by_function[(pathlib.Path(filename).name, function)] = max(cumulative, by_function.get(
            (pathlib.Path(filename).name, function), 0.0))
    phases = {"whole process (profiled)": round(stats.total_tt, 3)}
    phases["imports"] = round(by_function.get(("<frozen importlib._bootstrap>", "_find_and_load"), 0.0), 3)
    for label, key in PHASES.items():
        if key in by_function:
            phases[label] = round(by_function[key], 3)
    return phases


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs of each --help (default 5)")
    parser.add_argument("--run-repeat", type=int, default=3, help="runs of the ship scene (default 3)")
    parser.add_argument("--top", type=int, default=12, help="import-time offenders listed (default 12)")
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results" / "cli_latency.json"))
    args = parser.parse_args()

    gimbal2axis = command()
    load_before = os.getloadavg()[0]
    answers, run_label, help_imports, run_imports, phases = measure(gimbal2axis, args)
    helps = [label for label in answers if label.endswith("--help")]
    slowest_help = max(answers[label]["wall_median_s"] for label in helps)
    run_wall = answers[run_label]["wall_median_s"]
    result = {
        "benchmark": "cli_latency", "date": datetime.date.today().isoformat(), "cpus": os.cpu_count(),
        "load_average_1min_before": round(load_before, 2), "load_average_1min_after": round(os.getloadavg()[0], 2),
        "python": platform.python_version(), "command": " ".join(gimbal2axis),
        "repeat": {"help": args.repeat, "run": args.run_repeat},
        "targets": {"help_wall_s": HELP_TARGET_S, "run_wall_s": RUN_TARGET_S,
                    "help_met": slowest_help < HELP_TARGET_S, "run_met": run_wall < RUN_TARGET_S},
        "answers": answers,
        "imports_of_help": help_imports, "imports_of_run": run_imports, "run_phases_profiled_s": phases,
        "note": "whole processes as a user starts them; medians are compared with the targets (best and all "
                "runs kept); CPU time is the process's user + system time; the machine's load before and after "
                "shows in load_average_1min_*",
    }
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=2) + "\n")
    report(result, load_before, slowest_help, run_wall)
    print(f"wrote {out}")
    return 0


def measure(gimbal2axis: list[str], args):
    """The timed answers of every command, the run's label among them, the imports of --help and of
    the run, and the run's profiled phases."""
    answers = {"gimbal2axis --help": timed(gimbal2axis + ["--help"], args.repeat),
               "gimbal2axis --version": timed(gimbal2axis + ["--version"], args.repeat)}
    for name in SUBCOMMANDS:
        answers[f"gimbal2axis {name} --help"] = timed(gimbal2axis + [name, "--help"], args.repeat)
    with tempfile.TemporaryDirectory(prefix="gimbal_cli_latency_") as tmp:
        tmp = pathlib.Path(tmp)
        run_label = f"gimbal2axis run {SHIP_SCENE.relative_to(REPO)} --quiet"
        answers[run_label] = timed(gimbal2axis + ["run", str(SHIP_SCENE), "--quiet", "--out", str(tmp / "run")],
                                   args.run_repeat)
        run_imports = import_times("from gimbal2axis.cli.main import main\n"
                                   f"main(['run', {str(SHIP_SCENE)!r}, '--quiet', '--out', {str(tmp / 'imports')!r}])",
                                   args.top)
        phases = run_phases(tmp)
    help_imports = import_times("from gimbal2axis.cli.main import main\ntry:\n    main(['--help'])\n"
                                "except SystemExit:\n    pass", args.top)
    return answers, run_label, help_imports, run_imports, phases


def report(result: dict, load_before: float, slowest_help: float, run_wall: float) -> None:
    answers = result["answers"]
    width = max(len(label) for label in answers)
    print(f"{'command':<{width}}  wall median  wall best  CPU median   ({os.cpu_count()} CPUs, load "
          f"{load_before:.2f} before)")
    for label, figures in answers.items():
        print(f"{label:<{width}}  {figures['wall_median_s']:9.3f} s  {figures['wall_best_s']:7.3f} s  "
              f"{figures['cpu_median_s']:8.3f} s")
    print(f"targets: every --help < {HELP_TARGET_S} s: {'met' if result['targets']['help_met'] else 'NOT met'} "
          f"(slowest {slowest_help:.3f} s); the ship run < {RUN_TARGET_S} s: "
          f"{'met' if result['targets']['run_met'] else 'NOT met'} ({run_wall:.3f} s)")
    for title, found in (("--help", result["imports_of_help"]), ("run", result["imports_of_run"])):
        print(f"imports of {title}: {found['total_s']:.3f} s; top level by total: " + ", ".join(
            f"{row['module']} {row['cumulative_s']:.3f}" for row in found["top_level_by_cumulative_time"][:6]))
        print("  by own time: " + ", ".join(f"{row['module']} {row['own_s']:.3f}" for row in found["by_own_time"][:8]))
    print("the run's phases (cProfile, its overhead included): " + "; ".join(
        f"{label.strip()} {seconds:.2f} s" for label, seconds in result["run_phases_profiled_s"].items()))


if __name__ == "__main__":
    sys.exit(main())
