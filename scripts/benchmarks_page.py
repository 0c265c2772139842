#!/usr/bin/env python3
"""Writes docs/benchmarks.md: the prose of benchmarks/page_template.md with every figure table
rendered from the results files the benchmarks commit in benchmarks/results/, so that no figure on
the page is typed by hand or older than its file (tests/docs/test_benchmarks_page.py checks that the
committed page is what this writes).

    .venv/bin/python scripts/benchmarks_page.py            # after a benchmark wrote its results file
    .venv/bin/python scripts/benchmarks_page.py --check    # exit status 1 when the page is out of date

A template line `{{name}}` is replaced by TABLES[name](results folder); every name must be known
and every table used.
"""
from __future__ import annotations

import argparse
import json
import math
import pathlib
import re
import sys

REPO = pathlib.Path(__file__).resolve().parents[1]
PAGE = REPO / "docs" / "benchmarks.md"
TEMPLATE = REPO / "benchmarks" / "page_template.md"
RESULTS = REPO / "benchmarks" / "results"
PLACEHOLDER = re.compile(r"^\{\{(\w+)\}\}$", re.M)

METHOD_NAMES = {"0": "0 CVODE BDF", "3": "3 ARKODE explicit RK", "4": "**4 automatic (default)**",
                "5": "5 Dormand-Prince 5(4)", "6": "6 RODAS4", "7": "7 real time (RODAS4, fixed substeps)"}


# --- formatting --------------------------------------------------------------------------------

def sig(value, digits: int = 2) -> str:
    """`value` to `digits` significant digits, thousands separated; '-' for a missing value."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if value == 0:
        return "0"
    magnitude = math.floor(math.log10(abs(value)))
    if magnitude >= digits - 1:
        return f"{round(value, -(magnitude - digits + 1)):,.0f}"
    if magnitude >= -3:
        return f"{value:.{digits - 1 - magnitude}f}"
    return f"{value:.{digits - 1}e}".replace("e-0", "e-")


def count(value) -> str:
    return "-" if value is None else f"{value:,}"


def sci(value) -> str:
    """An error or tolerance: 2 significant digits, exponent form."""
    return "-" if value is None else f"{value:.1e}".replace("e-0", "e-").replace("e+0", "e")


def tol(value) -> str:
    """A tolerance as the scripts set it: 1e-5."""
    return "-" if value is None else f"{value:.0e}".replace("e-0", "e-")


def table(header: list[str], rows: list[list[str]], right_from: int = 1) -> str:
    """A Markdown table whose columns from `right_from` on are right-aligned."""
    align = ["---" if i < right_from else "---:" for i in range(len(header))]
    lines = [header, align, *rows]
    return "\n".join("| " + " | ".join(line) + " |" for line in lines)


def load(name: str, folder: pathlib.Path) -> dict:
    return json.loads((folder / name).read_text())


def measured(when: str | None, where: str | None = None) -> str:
    text = f"Measured {when}" if when else "Measured (the file records no date)"
    return text + (f", {where}." if where else ".")


# --- scripts/benchmark.py: results.json ---------------------------------------------------------

def speed_machine(folder: pathlib.Path) -> str:
    results = load("results.json", folder)
    machine = results["machine"]
    commit = machine["git_commit"][:7] + ("+" if machine["git_dirty"] else "")
    return measured(machine["date"][:10], f"commit {commit}, {machine['cpu']}, {machine['cores']} cores, "
                                          f"{machine['compiler'].split(' (')[0]} {machine['compiler'].rsplit(' ', 1)[-1]}; "
                                          f"{results['settings']['duration_s']:g} s of the scene per run, "
                                          f"the whole benchmark {results['elapsed_s']:.0f} s")


def at_target_error(folder: pathlib.Path) -> str:
    results = load("results.json", folder)
    rows = []
    for best in results["at_target_error"]:
        setting = (f"{best['substeps']} substep{'s' if best['substeps'] > 1 else ''}" if best.get("substeps")
                   else tol(best["rtol"]))
        rows.append([best["fidelity"], METHOD_NAMES.get(str(best["method"]), str(best["method"])), setting,
                     sig(best.get("cpu_us_per_step")), sig(best["rtf"]), sig(best.get("fmu_rtf")),
                     sci(best["err_beta"]), sig(best["target_rtf"], 4)])
    return table(["fidelity", "integrator (`solver.method`)", "rtol", "CPU per doStep [us]", "real-time factor",
                  "the FMU alone", "beta error [rad]", "target"], rows, right_from=3)


def default_settings(folder: pathlib.Path) -> str:
    results = load("results.json", folder)
    rows = []
    for point in results["sweep"]:
        if point["method"] == 4 and point["rtol"] == 1e-6 and not point.get("failure"):
            rows.append([point["fidelity"], sig(point["cpu_us_per_step"]), sig(point["rtf"]), sci(point["err_beta"]),
                         sci(point["err_alpha"]), sci(point["err_omega"]), count(point["solver_steps"]),
                         sig(point["rhs_evaluations"] / point["dostep_calls"], 3), count(point["events"])])
    return table(["fidelity", "CPU per doStep [us]", "real-time factor", "beta error [rad]", "alpha error [rad]",
                  "los.omega error [rad/s]", "steps", "right-hand sides per doStep", "mode changes"], rows)


def reference_spread(folder: pathlib.Path) -> str:
    results = load("results.json", folder)
    rows = [[fidelity, sci(ref["check_difference"]["err_beta"]), sci(ref["check_difference"]["err_alpha"]),
             sci(ref["check_difference"]["err_omega"])] for fidelity, ref in results["references"].items()]
    return table(["fidelity", "beta [rad]", "alpha [rad]", "los.omega [rad/s]"], rows)


def stiff_variants(folder: pathlib.Path) -> str:
    results = load("results.json", folder)
    rows = []
    for case in results["stiff_cases"]:
        if case.get("failure"):
            rows.append([case["case"], "failed: " + case["failure"][:60]] + [""] * 8)
            continue
        own, cvode, spread = case["default"], case["cvode_default"], case.get("reference_spread") or {}
        rows.append([case["case"], sig(own["rtf"]), sig(own["cpu_us_per_step"]), count(own["events"]),
                     sig(own.get("steps_per_event")), count(own["method_switches"]),
                     f"{sci(own['err_beta'])} / {sci(own['err_beta_short'])}",
                     f"{sci(spread.get('err_beta'))} / {sci(spread.get('err_beta_short'))}",
                     sig(cvode["rtf"]), sci(cvode["err_beta_short"])])
    return table(["variant", "default: real-time factor", "us per doStep", "mode changes", "steps per change",
                  "switches", "beta error 2 s / 0.1 s", "references' spread 2 s / 0.1 s",
                  "CVODE BDF at its defaults: real-time factor", "its beta error 0.1 s"], rows)


def cost_vs_duration(folder: pathlib.Path) -> str:
    results = load("results.json", folder)
    rows = [[f"{run['simulated_s']:g} s", sig(run["cpu_s"]), sig(run["cpu_us_per_simulated_ms"]), sig(run["rtf"]),
             count(run["solver_steps"])] for run in results["cost_vs_duration"]["runs"] if not run.get("failure")]
    rtol = results["cost_vs_duration"]["rtol"]
    return (f"The default integrator at rtol {tol(rtol)}, full fidelity.\n\n"
            + table(["simulated", "CPU [s]", "CPU per simulated ms [us]", "real-time factor", "steps"], rows))


def fmi_overhead(folder: pathlib.Path) -> str:
    results = load("results.json", folder)
    overhead, allocations = results["fmi_overhead"], results["allocations_in_dostep"]
    fidelities = list(overhead)
    rows = [["doStep of a model at rest (fixed base, g = 0, 0 V, 1 us steps), CPU per call [ns]",
             *(sig(overhead[f].get("ns_per_dostep")) for f in fidelities)],
            ["instance memory (instantiate + initialization, live heap) [kB]",
             *(sig(overhead[f].get("instance_bytes", 0) / 1e3, 3) for f in fidelities)],
            ["allocations in doStep after the first (2 s of the ship scene)",
             *(f"{count(allocations[f]['dostep_allocations'])} in {count(allocations[f]['dostep_calls'])} doSteps"
               for f in fidelities)],
            ["allocations in doStep after the first (at rest)",
             *(f"{count(overhead[f]['dostep_allocations'])} in {count(overhead[f]['dostep_calls'])} doSteps"
               for f in fidelities)]]
    return table(["", *fidelities], rows)


def single_dosteps(folder: pathlib.Path) -> str:
    results = load("results.json", folder)
    rows = []
    for run in results["single_dosteps"]:
        if run.get("failure"):
            continue
        wall = [sig(1e6 * run[key]) for key in ("dostep_p50_s", "dostep_p99_s", "dostep_p999_s", "dostep_max_s")]
        cpu = [sig(1e6 * run[key]) for key in ("dostep_cpu_p50_s", "dostep_cpu_p999_s", "dostep_cpu_max_s")]
        work = [count(run[key]) for key in ("rhs_per_dostep_median", "rhs_per_dostep_p999", "rhs_per_dostep_max")]
        rows.append([run["label"], *wall, *cpu, *work])
    return table(["", "wall [us]: median", "p99", "p99.9", "max", "thread CPU [us]: median", "p99.9", "max",
                  "right-hand sides: median", "p99.9", "max"], rows)


def met(ok: bool) -> str:
    return "yes" if ok else "**no**"


def speed_targets(folder: pathlib.Path) -> str:
    """The speed work's targets (issue 12) that results.json measures, each against its figure."""
    results = load("results.json", folder)
    rows = []
    for best in results["at_target_error"]:
        if best["method"] == 4 and best["rtf"] is not None:
            rows.append([f"default, {best['fidelity']} fidelity, beta error <= 1e-6 rad: >= {sig(best['target_rtf'], 4)}x "
                         "real time", f"{sig(best['rtf'])}x (rtol {tol(best['rtol'])})",
                         met(best["meets_target"]) + ("" if best["meets_target"] else
                                                      f", {best['target_rtf'] / best['rtf']:.0f}x short")])
    for case in results["stiff_cases"]:
        if not case.get("failure"):
            rtf = case["default"]["rtf"]
            rows.append([f"{case['case']}, default settings: >= 100x real time, no discarded step", f"{sig(rtf)}x",
                         met(rtf >= 100)])
    core = results.get("core_costs", {})
    if "rhs_ns" in core.get("full", {}):
        rows.append(["a right-hand side, full fidelity (`gimbal_bench_core`) <= 150 ns", f"{sig(core['full']['rhs_ns'])} ns",
                     met(core["full"]["rhs_ns"] <= 150)])
    for fidelity, costs in core.items():
        if "event_check_ns" in costs:
            rows.append([f"event checks per step, {fidelity} fidelity <= 50 ns", f"{sig(costs['event_check_ns'])} ns",
                         met(costs["event_check_ns"] <= 50)])
    overhead = max(run["ns_per_dostep"] for run in results["fmi_overhead"].values())
    rows.append(["FMI overhead: doStep at rest <= 100 ns", f"{sig(overhead)} ns", met(overhead <= 100)])
    allocations = sum(run["dostep_allocations"] for run in results["allocations_in_dostep"].values())
    rows.append(["no heap allocation in doStep after the first (the default method)", count(allocations),
                 met(allocations == 0)])
    return table(["target", "measured", "met"], rows, right_from=3)


# --- the other benchmarks' files ------------------------------------------------------------------

def model_exchange(folder: pathlib.Path) -> str:
    results = load("model_exchange.json", folder)
    evaluation = results["evaluation"]
    calls = table(["", "ns per call"], [
        ["core right-hand side, carrier held (the work of one Model Exchange evaluation)", sig(evaluation["core_rhs_held_ns"], 3)],
        ["core right-hand side, carrier moved to a new time (a Co-Simulation stage)", sig(evaluation["core_rhs_moving_ns"], 3)],
        ["`fmi2SetTime` + `fmi2SetContinuousStates` + `fmi2GetDerivatives`, new time and state",
         sig(evaluation["me_derivatives_ns"], 3)],
        ["of which `fmi2SetTime` / `fmi2SetContinuousStates` / `fmi2GetDerivatives` at an evaluated point",
         " / ".join(sig(evaluation[key], 2) for key in ("set_time_ns", "set_states_ns", "cached_derivatives_ns"))],
        ["`fmi2GetEventIndicators` after the derivatives", sig(evaluation["me_event_indicators_ns"], 2)],
        ["a host's evaluation over the core's right-hand side", sig(evaluation["ratio_derivatives_to_core"], 3)]])
    rows = [[run["scene"], "Model Exchange (fmpy CVode)" if run["interface"] == "ModelExchange" else
             "Co-Simulation (own integrator, 1 ms)", tol(run["rtol"]), sig(run["cpu_s"]), sig(run["real_time_factor"]),
             sci(run["max_angle_error_rad"]), f"{run['events']} (reference {run['reference_events']})"]
            for run in results["runs"]]
    scenes = table(["scene", "interface", "rtol", "CPU [s]", "real-time factor", "max angle error [rad]", "events"],
                   rows, right_from=2)
    return measured(results.get("date")) + "\n\n" + calls + "\n\n" + scenes


def scene_runner(folder: pathlib.Path) -> str:
    results = load("scene_runner.json", folder)
    rows = [["the FMU alone (compiled replay)", sig(results["fmu_alone_cpu_s"]), sig(results["fmu_alone_real_time_factor"]),
             f"({sig(results['fmu_us_per_step'])} per step: the FMU)"]]
    for loop in ("compiled", "python"):
        entry = results[loop]
        rows.append([f"{loop} loop ({results['controller']})", sig(entry["loop_cpu_s"]), sig(entry["real_time_factor_cpu"]),
                     sig(entry["master_own_us_per_step"]) if entry["master_own_us_per_step"] > 0 else
                     "below the noise"])
    worst_own = max(results[loop]["master_own_us_per_step"] for loop in ("compiled", "python"))
    slowest = min(results[loop]["real_time_factor_cpu"] for loop in ("compiled", "python"))
    return (measured(results.get("date"), f"{results['stop_time_s']:g} s of `{results['scene']}`, "
                                          f"{count(results['steps'])} steps") + "\n\n"
            + table(["", "loop CPU [s]", "real-time factor", "the master's own per step [us]"], rows)
            + f"\n\nTargets: the master's own cost <= 10 us per step ({met(worst_own <= 10)}); the compiled loop "
              f">= 100x real time ({met(results['compiled']['real_time_factor_cpu'] >= 100)}; the Python loop, which "
              f"only a user's controller needs, {sig(slowest)}x).")


def sweeps(folder: pathlib.Path) -> str:
    rows, dates = [], []
    for name in ("sweep_throughput.json", "sweep_throughput_10s.json"):
        results = load(name, folder)
        dates.append(results.get("date"))
        rows.append([f"{results['cases']} cases of {results['simulated_s_per_case']:g} s", sig(results["serial"]["wall_s"]),
                     sig(results["dask"]["wall_s"]), f"{results['workers']}", sig(results["dask"]["cluster_startup_s"]),
                     sig(results["cases"] * results["simulated_s_per_case"] / results["dask"]["sum_of_case_cpu_s"]),
                     sig(results["load_average_1min"]), "yes" if results["dask_equals_serial"] else "**no**"])
    when = " and ".join(sorted({date for date in dates if date})) or None
    return (measured(when, "best of the file's repetitions, wall times with case expansion and table writing")
            + "\n\n" + table(["", "serial, wall [s]", "Dask, wall [s]", "workers", "cluster start [s]",
                               "simulated s per CPU s of the workers", "load average",
                               "Dask equal to serial, bit for bit"], rows))


def batch_controller(folder: pathlib.Path) -> str:
    results = load("batch_controller.json", folder)
    rows = []
    for size in results["sizes"]:
        rate, master = size["simulated_s_per_cpu_s"], size["master_us_per_case_step"]
        rows.append([count(size["cases"]), f"{sig(rate['one_at_a_time'])} ({sig(master['one_at_a_time'], 3)})",
                     f"{sig(rate['lockstep'])} ({sig(master['lockstep'], 3)})",
                     f"{sig(rate['fmu_alone'], 3)} ({sig(size['fmu_us_per_case_step'])})",
                     sci(size["max_relative_los_rms_difference_batch_vs_scalar"])])
    sweep = results.get("serial_sweep") or {}
    serial = "; ".join(f"`{name}` {sig(entry['cpu_s'])} s CPU for {entry['cases']} cases"
                       for name, entry in sweep.items())
    load_text = ", ".join(sig(x) for x in results["load_average"])
    return (measured(results["date"], f"load average {load_text}; cases of {results['sizes'][0]['stop_time_s']:g} s "
                                      f"of `{results['scene']}`") + "\n\n"
            + table(["N cases", "one at a time, scalar class: simulated s per CPU s (master us per case-step)",
                     "lockstep, batch class: the same", "the FMU alone: simulated s per CPU s (us per step)",
                     "batch against scalar: LOS RMS, relative"], rows)
            + (f"\n\nA whole serial sweep: {serial}." if serial else ""))


def current_drive(folder: pathlib.Path) -> str:
    results = load("current_drive.json", folder)
    rows = []
    for name, variant in results["variants"].items():
        counters = variant["counters"]
        rows.append([name, sig(variant["cpu_s"], 3), sig(variant["cpu_ratio_to_voltage"], 3),
                     count(counters["solver.steps"]), count(counters["solver.rhs_evaluations"]),
                     count(counters["solver.jacobian_evaluations"]), count(counters["events.total"])])
    cost = table(["variant", "CPU [s]", "vs voltage", "steps", "right-hand sides", "Jacobians", "mode changes"], rows)
    errors = [[name, *(sci(e[key]) for key in ("alpha_rad", "beta_rad", "los_omega_rad_s", "i_R1_A", "i_R2_A"))]
              for name, e in results["errors"].items()]
    return (measured(results.get("date"), f"{results['simulated_s']:g} s, median of {results['repeat']}; "
                                          f"{results['scene']}") + "\n\n" + cost + "\n\n"
            + "Largest differences at the 1 ms points:\n\n"
            + table(["compared", "alpha [rad]", "beta [rad]", "los.omega [rad/s]", "i_R1 [A]", "i_R2 [A]"], errors))


def tracking_scenes(folder: pathlib.Path) -> str:
    results = load("tracking_scenes.json", folder)
    voltage = results["rows"]["track_flyby_keyhole"]["cpu_s"]
    rows, errors = [], []
    for name, row in results["rows"].items():
        rows.append([f"`{name}` ({row['simulated_s']:g} s)", sig(row["cpu_s"], 3), sig(row["real_time_factor"], 3),
                     sig(row["cpu_s"] / voltage, 3) if "flyby" in name else "", count(row["solver.steps"]),
                     count(row["solver.rhs_evaluations"]), count(row["events.total"]), sig(row["los_rms_mrad"], 3),
                     sig(row["time_lost_near_keyhole_s"], 3)])
        if "against_reference" in row:
            e = row["against_reference"]
            errors.append([name, *(sci(e[key]) for key in ("alpha_rad", "beta_rad", "los_error_mrad", "i_R1_A"))])
    return (measured(results.get("date"), f"median of {results['repeat']} runs ({results['machine']})") + "\n\n"
            + table(["scene", "CPU [s]", "x real time", "vs voltage flyby", "steps", "right-hand sides", "events",
                     "LOS RMS [mrad]", "lost near the keyhole [s]"], rows)
            + "\n\nLargest differences from the reference (rtol 1e-10) over the run:\n\n"
            + table(["current-drive flyby", "alpha [rad]", "beta [rad]", "los_error [mrad]", "i_R1 [A]"], errors))


def long_runs(folder: pathlib.Path) -> str:
    results = load("long_run_memory.json", folder)
    rows = [[f"{row['simulated_s']:g} s", sig(row["peak_rss_mb"], 3), sig(row["wall_s"], 3), sig(row["parquet_mb"], 3),
             sig(row["csv_mb"], 3)] for row in results["results"]]
    return (measured(results["date"][:10], f"{results['cpus']} cores, Python {results['python']}") + "\n\n"
            + table(["simulated", "peak RSS [MB]", "wall [s]", "Parquet [MB]", "CSV [MB]"], rows))


def record_cost(folder: pathlib.Path) -> str:
    results = load("record_cost.json", folder)
    memory, disk = results["runs"]["memory"], results["runs"]["disk"]
    parts = disk["record_parts_cpu_s"]
    rows = [["in memory (`master.run`)", sig(memory["cpu_s"], 3), sig(memory["peak_rss_mb"], 3), "", "", "", "", ""],
            ["to disk (`run_streamed`, as `gimbal2axis run`)", sig(disk["cpu_s"], 3), sig(disk["peak_rss_mb"], 3),
             *(sig(parts[key]) for key in ("parquet_chunk_files", "csv_rows", "run_json", "merge_and_end")),
             f"{sig(results['record_cpu_s'])} ({100 * results['record_share_of_disk_run']:.0f} %)"]]
    load_text = " and ".join(sig(x) for x in results["load_average_1min"])
    return (measured(results["date"][:10], f"{results['simulated_s']:g} s of `{results['scene']}`, "
                                           f"{results['cpus']} cores, load average {load_text} before and after") + "\n\n"
            + table(["run", "CPU, user + sys [s]", "peak RSS [MB]", "the record's Parquet chunks [s CPU]", "CSV rows",
                     "`_run.json`", "merge and end", "the record in all (of the run)"], rows))


def cli_latency(folder: pathlib.Path) -> str:
    results = load("cli_latency.json", folder)
    rows = []
    for command, answer in results["answers"].items():
        rows.append([f"`{command}`", sig(answer["wall_median_s"]), sig(answer["wall_best_s"]), sig(max(answer["wall_all_s"])),
                     sig(answer["cpu_median_s"])])
    targets = results["targets"]
    return (measured(results["date"], f"{results['cpus']} cores, Python {results['python']}; targets: `--help` "
                                      f"{targets['help_wall_s']:g} s ({'met' if targets['help_met'] else 'not met'}), "
                                      f"a run {targets['run_wall_s']:g} s ({'met' if targets['run_met'] else 'not met'})")
            + "\n\n" + table(["command", "wall, median [s]", "best", "worst", "CPU, median [s]"], rows)
            + "\n\nThe ship run's phases under cProfile (its overhead included), in seconds: "
            + "; ".join(f"{label.strip()} {sig(seconds)}" for label, seconds in results["run_phases_profiled_s"].items())
            + ".")


def codebase_metrics(folder: pathlib.Path) -> str:
    results = load("codebase_metrics.json", folder)
    rows = []
    for revision in results["revisions"]:
        plumbing, pairs, lizard = revision["plumbing"], revision["duplicates"], revision["lizard"]
        rows.append([f"`{revision['commit'][:7]}` ({revision['date'][:10]})", count(plumbing["total_lines"]),
                     count(plumbing["total_code_lines"]), count(pairs["count"]), count(pairs["count_by_kind"]["code"]),
                     count(lizard["functions"]), count(lizard["count"])])
    return (measured(results["measured"][:10]) + "\n\n"
            + table(["revision", "FMI plumbing: lines", "code lines", "`duplicates` pairs in `fmu_src/`", "of them code",
                     "C/C++ functions", "over lizard's limits"], rows))


def callgrind_cost(folder: pathlib.Path) -> str:
    results = load("callgrind_cost_one_face.json", folder)
    rows = []
    for revision in results["revisions"]:
        calls = revision["fmi_calls"]
        rows.append([f"`{revision['commit'][:7]}`", count(round(revision["instructions_per_rhs"])),
                     count(round(revision["instructions_per_dostep"])), count(round(revision["core_instructions_per_dostep"])),
                     count(round(calls["fmi2SetReal"]["instructions_per_call"])),
                     count(round(calls["fmi2GetReal"]["instructions_per_call"])),
                     f"{revision['rhs_per_dostep']:.2f}", count(revision["solver_steps"])])
    return (measured(results["measured"][:10], results["valgrind"]) + "\n\n"
            + table(["revision", "per RHS", "per doStep", "of which the core's step", "`fmi2SetReal`", "`fmi2GetReal`",
                     "RHS per doStep", "steps"], rows))


TABLES = {function.__name__: function for function in (
    speed_machine, at_target_error, speed_targets, default_settings, reference_spread, stiff_variants, cost_vs_duration,
    fmi_overhead, single_dosteps, model_exchange, scene_runner, sweeps, batch_controller, current_drive,
    tracking_scenes, long_runs, record_cost, cli_latency, codebase_metrics, callgrind_cost)}


def render(template: str | None = None, folder: pathlib.Path = RESULTS) -> str:
    """The page: the template with each `{{name}}` line replaced by its table."""
    text = TEMPLATE.read_text() if template is None else template
    names = PLACEHOLDER.findall(text)
    unknown, unused = set(names) - set(TABLES), set(TABLES) - set(names)
    if unknown or unused:
        raise ValueError(f"template placeholders unknown: {sorted(unknown)}, tables unused: {sorted(unused)}")
    return PLACEHOLDER.sub(lambda match: TABLES[match.group(1)](folder), text)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="only compare: exit status 1 when the page is out of date")
    args = parser.parse_args(argv)
    page = render()
    if args.check:
        if PAGE.read_text() != page:
            print(f"{PAGE.relative_to(REPO)} is out of date: run scripts/benchmarks_page.py", file=sys.stderr)
            return 1
        return 0
    PAGE.write_text(page)
    print(f"wrote {PAGE.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
