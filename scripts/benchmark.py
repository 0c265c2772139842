#!/usr/bin/env python3
"""Work-precision benchmark of the Gimbal2Axis FMU, in one command:

    .venv/bin/python scripts/benchmark.py            # ~1 minute on a 2-core machine

It builds nothing: it runs the native driver build/benchmarks/gimbal_bench (benchmarks/bench_driver.cpp)
on the FMU's shared object in build/fmu_staging (run `bash scripts/setup.sh` or `cmake --build build`
first). Both are copied to a temporary directory first, so a rebuild during the benchmark does not
disturb it. Steps:

1. a reference trajectory per fidelity (full, reduced) of the ship-stabilization scene at very tight
   tolerance (rtol 1e-12, atol 1e-14, method 0 or the FMU's default), and a second one with ARKODE's
   explicit RK (method 3) at the same tolerance to show how far the reference itself can be trusted;
2. the work-precision sweep: the integrators of `solver.method` (by default 4 automatic, 5
   Dormand-Prince, 6 RODAS4, 7 the real-time method, and the references 0 CVODE BDF and 3 ARKODE
   explicit Runge-Kutta) x fidelity x rtol in 1e-4 ... 1e-10 (atol = rtol * 1e-2; the real-time
   method x 1, 2, 4, 8 substeps instead): CPU time and the max error of alpha, beta and los.omega
   against the reference at every communication point;
3. cost against simulated time (1, 10, 100, 1000 s) with the FMU's default integrator, full fidelity;
4. the FMI overhead (doStep of a model at rest, 1 us steps) and the instance memory;
5. heap allocations inside doStep and their call sites;
6. the stiff variants (L = 1e-7 H, k_s = 1e8 N.m/rad, c_s = 1e-6 N.m.s/rad) at default settings,
   against CVODE BDF at rtol 1e-11 and at its own defaults;
7. single doSteps of the default and of the real-time method (1, 2, 4 substeps): median, p99, p99.9
   and maximum in wall time and in right-hand sides;
8. the core's pieces without FMI or an integrator (build/benchmarks/gimbal_bench_core): a right-hand
   side, an event check, a Jacobian, the outputs.

Writes benchmarks/results/results.json and benchmarks/results/work_precision.png, prints a summary.
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import pathlib
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO = pathlib.Path(__file__).resolve().parent.parent
METHOD_NAMES = {
    None: "FMU default",
    0: "CVODE BDF, analytic Jacobian",
    1: "CVODE BDF, finite-difference Jacobian",
    2: "CVODE Adams",
    3: "ARKODE explicit RK",
    4: "automatic DP5 / RODAS4 (default)",
    5: "Dormand-Prince 5(4)",
    6: "RODAS4",
    7: "real time: RODAS4, fixed substeps",
}
REAL_TIME = 7
# The real-time method has no tolerance: its accuracy is set by the substeps per doStep.
REAL_TIME_SUBSTEPS = (1, 2, 4, 8)
FIDELITIES = ("full", "reduced")
TARGET_BETA_ERROR = 1e-6
TARGET_RTF = {"full": 1e3, "reduced": 3e3}
TARGET_OVERHEAD_NS = 100.0
# The stiff variants of the same scene, at default settings: each must run >= 100x real time, within
# tolerance and without a discarded step.
STIFF_VARIANTS = {
    "L = 1e-7 H": {"motor1.L": 1e-7, "motor2.L": 1e-7},
    "k_s = 1e8 N.m/rad": {"gear1.k_s": 1e8, "gear2.k_s": 1e8},
    "c_s = 1e-6 N.m.s/rad": {"gear1.c_s": 1e-6, "gear2.c_s": 1e-6},
    # The issue's stiff tracking scene: stiff, lightly damped shafts that chatter in their backlash.
    "tracking: k_s 1e6, c_s 0.5, L 0.2 mH": {"gear1.k_s": 1e6, "gear2.k_s": 1e6, "gear1.c_s": 0.5, "gear2.c_s": 0.5,
                                             "motor1.L": 2e-4, "motor2.L": 2e-4},
}
# The chattering variants are sensitive to the impact times: two tight references (CVODE BDF at rtol
# 1e-10 and 1e-11) part by 1e-4 rad within 2 s. Errors are also given over the first SHORT_HORIZON s,
# before that sensitivity has grown, next to the references' own spread there.
SHORT_HORIZON = 0.1
TARGET_STIFF_RTF = 100.0


def log(message: str) -> None:
    print(message, flush=True)


class Driver:
    """Runs gimbal_bench on a private copy of the FMU."""

    def __init__(self, bench: pathlib.Path, so: pathlib.Path, md: pathlib.Path, workdir: pathlib.Path,
                 timeout: float):
        self.dir = workdir / "fmu"
        (self.dir / "binaries" / "linux64").mkdir(parents=True)
        shutil.copy2(md, self.dir / "modelDescription.xml")
        self.so = self.dir / "binaries" / "linux64" / so.name
        shutil.copy2(so, self.so)
        self.bench = workdir / "gimbal_bench"
        shutil.copy2(bench, self.bench)
        self.workdir = workdir
        self.timeout = timeout
        text = (self.dir / "modelDescription.xml").read_text()
        self.has_method = 'name="solver.method"' in text
        self.guid = text.split('guid="', 1)[1].split('"', 1)[0]
        self.default_method = None
        if self.has_method:
            block = text.split('name="solver.method"', 1)[1].split("</ScalarVariable>", 1)[0]
            if 'start="' in block:
                self.default_method = int(block.split('start="', 1)[1].split('"', 1)[0])
        self.count = 0

    def run(self, *, timeout=None, trajectory=False, overhead=False, **settings) -> dict:
        """One gimbal_bench run with `settings` (command's keywords); its JSON, with the trajectory as
        `_trajectory` when asked for, or {"failure": ...}."""
        traj_path = None
        if trajectory and not overhead:
            self.count += 1
            traj_path = self.workdir / f"traj{self.count}.bin"
        cmd = self.command(overhead=overhead, trajectory=traj_path, **settings)
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout or self.timeout)
        except subprocess.TimeoutExpired:
            return {"failure": f"timeout after {timeout or self.timeout:.0f} s", "command": " ".join(cmd)}
        lines = [line for line in proc.stdout.splitlines() if line.startswith("{")]
        if not lines:
            return {"failure": (proc.stderr.strip() or f"exit status {proc.returncode}")[-500:],
                    "command": " ".join(cmd)}
        result = json.loads(lines[-1])
        if proc.stderr.strip():
            result["stderr"] = proc.stderr.strip()[-500:]
        if traj_path is not None and traj_path.exists():
            result["_trajectory"] = np.fromfile(traj_path, dtype="<f8").reshape(-1, 6)
            traj_path.unlink()
        return result

    def command(self, *, method=None, fidelity="full", rtol=None, atol=None, duration=10.0, step=1e-3,
                trajectory=None, overhead=False, overhead_steps=None, trace=False, parameters=None,
                time_dostep=False) -> list[str]:
        """gimbal_bench's command line: options only for what is given."""
        cmd = [str(self.bench), "--fmu", str(self.so), "--json", "--fidelity", fidelity]
        flags = {"--time-dostep": time_dostep, "--no-trace": not trace, "--fmi-overhead": overhead}
        cmd += [flag for flag, wanted in flags.items() if wanted]
        for name, value in (parameters or {}).items():
            cmd += ["--set", f"{name}={value!r}"]
        options = {"--method": method, "--rtol": rtol, "--atol": atol}
        if overhead:
            options["--overhead-steps"] = overhead_steps or None
        else:
            options.update({"--duration": duration, "--step": step, "--trajectory": trajectory})
        for option, value in options.items():
            if value is not None:
                cmd += [option, str(value) if isinstance(value, (int, pathlib.Path)) else repr(value)]
        return cmd


def errors_against(run: dict, reference: np.ndarray, horizon: float | None = None) -> dict:
    """Max absolute errors at the communication points: alpha, beta [rad], los.omega [rad/s]; with a
    horizon, also over t <= horizon (keys *_short)."""
    traj = run.get("_trajectory")
    if traj is None or len(traj) != len(reference) or run.get("failure"):
        return {"err_alpha": None, "err_beta": None, "err_omega": None}
    d = np.abs(traj[:, 1:] - reference[:, 1:])
    errors = {"err_alpha": float(d[:, 0].max()), "err_beta": float(d[:, 1].max()), "err_omega": float(d[:, 2:].max())}
    if horizon is not None:
        early = d[reference[:, 0] <= horizon + 1e-12]
        errors.update({"err_alpha_short": float(early[:, 0].max()), "err_beta_short": float(early[:, 1].max())})
    return errors


def machine_info(build_dir: pathlib.Path) -> dict:
    cpu = "?"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    compiler = "?"
    cache = build_dir / "CMakeCache.txt"
    try:
        cxx = "c++"
        for line in cache.read_text().splitlines():
            if line.startswith("CMAKE_CXX_COMPILER:"):
                cxx = line.split("=", 1)[1]
        compiler = subprocess.run([cxx, "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        pass

    def git(*args):
        try:
            return subprocess.run(["git", *args], cwd=REPO, capture_output=True, text=True).stdout.strip()
        except OSError:
            return "?"

    dirty = git("status", "--porcelain", "--untracked-files=no")
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "kernel": platform.release(),
        "compiler": compiler,
        "git_commit": git("rev-parse", "HEAD"),
        "git_dirty": bool(dirty),
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "python": platform.python_version(),
    }


def strip(run: dict) -> dict:
    return {k: v for k, v in run.items() if not k.startswith("_")}


def fmt(x, spec=".3g"):
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def parse_args(argv=None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build-dir", type=pathlib.Path, default=REPO / "build")
    ap.add_argument("--bench", type=pathlib.Path, help="gimbal_bench executable (default BUILD/benchmarks/gimbal_bench)")
    ap.add_argument("--duration", type=float, default=10.0, help="simulated time of the sweep runs [s] (default 10)")
    ap.add_argument("--step", type=float, default=1e-3, help="communication step [s] (default 1e-3)")
    ap.add_argument("--rtols", default="1e-4,1e-5,1e-6,1e-7,1e-8,1e-9,1e-10")
    ap.add_argument("--atol-factor", type=float, default=1e-2, help="atol = rtol * this (default 1e-2)")
    ap.add_argument("--methods", default=None,
                    help="comma-separated solver.method values (default 4,5,6,7,0,3: the project's own methods and the "
                         "SUNDIALS BDF and explicit references; 1 and 2 on request)")
    ap.add_argument("--stiff-duration", type=float, default=2.0, help="simulated time of the stiff variants [s]")
    ap.add_argument("--fidelities", default="full,reduced")
    ap.add_argument("--durations", default="1,10,100,1000", help="cost-vs-duration table [s]")
    ap.add_argument("--duration-budget", type=float, default=90.0,
                    help="CPU seconds allowed for the longest cost-vs-duration run (longer ones are shortened)")
    ap.add_argument("--run-timeout", type=float, default=90.0, help="give up a single sweep run after this [s]")
    ap.add_argument("--overhead-steps", type=int, default=200000)
    ap.add_argument("--out", type=pathlib.Path, default=REPO / "benchmarks" / "results")
    ap.add_argument("--quick", action="store_true", help="smoke test: 1 s runs, 3 tolerances, no long durations")
    ap.add_argument("--replot", action="store_true", help="only redraw the PNG and the tables from OUT/results.json")
    args = ap.parse_args(argv)
    if args.quick:
        args.duration = 1.0
        args.rtols = "1e-4,1e-6,1e-8"
        args.durations = "1,2"
        args.overhead_steps = 20000
    return args


def main(argv=None) -> int:
    """The steps of the module's docstring, one function each; results.json, the plot, the tables."""
    args = parse_args(argv)
    if args.replot:
        return replot(args.out)
    binaries = find_binaries(args)
    if binaries is None:
        return 2

    t_start = time.time()
    rtols = [float(x) for x in args.rtols.split(",")]
    fidelities = [f for f in args.fidelities.split(",") if f]
    results: dict = {"machine": machine_info(args.build_dir), "settings": {
        "scene": "ship_stabilization (benchmarks/bench_driver.cpp: sea state seed 1, PD + gyro, one-step delay)",
        "duration_s": args.duration, "step_s": args.step, "rtols": rtols, "atol_factor": args.atol_factor,
        "reference": "rtol 1e-12, atol 1e-14", "error": "max abs over communication points"}}

    with tempfile.TemporaryDirectory(prefix="gimbal_bench_") as tmp:
        drv = Driver(*binaries, pathlib.Path(tmp), args.run_timeout)
        results["fmu_guid"] = drv.guid
        methods = choose_methods(drv, args.methods)
        if methods is None:
            return 2
        results["methods"] = {str(m): METHOD_NAMES.get(m, f"method {m}") for m in methods}
        results["references"] = {}
        references = measure_references(drv, fidelities, args, results["references"])
        if references is None:
            return 1
        results["sweep"] = work_precision_sweep(drv, methods, fidelities, rtols, args, references)
        results["at_target_error"] = best = at_target_error(results["sweep"], methods, fidelities)
        results["cost_vs_duration"] = cost_vs_duration(drv, best, args)
        results["fmi_overhead"] = fmi_overhead(drv, fidelities, args.overhead_steps)
        results["allocations_in_dostep"] = allocations_in_dostep(drv, fidelities, args.step)
        results["stiff_cases"] = stiff_cases(drv, args.stiff_duration, args.step, args.run_timeout)
        results["single_dosteps"] = single_dosteps(drv, args.duration, args.step)
    results["core_costs"] = core_costs(args.build_dir.resolve() / "benchmarks" / "gimbal_bench_core", fidelities)

    results["elapsed_s"] = round(time.time() - t_start, 1)
    write_results(results, args.out, methods, fidelities, args.duration)
    return 0


def replot(out: pathlib.Path) -> int:
    """--replot: the PNG and the tables again, from OUT/results.json."""
    results = json.loads((out / "results.json").read_text())
    methods = [None if m == "None" else int(m) for m in results["methods"]]
    fidelities = list(results["references"])
    plot(results, out / "work_precision.png", methods, fidelities, results["settings"]["duration_s"])
    summary(results, methods, fidelities, results["settings"]["duration_s"])
    return 0


def find_binaries(args) -> tuple | None:
    """(gimbal_bench, the FMU's shared object, its modelDescription.xml), or None when one is
    missing (said on stderr)."""
    build = args.build_dir.resolve()
    bench = (args.bench or build / "benchmarks" / "gimbal_bench").resolve()
    so = build / "fmu_staging" / "binaries" / "linux64" / "Gimbal2Axis.so"
    md = build / "fmu_staging" / "modelDescription.xml"
    missing = [p for p in (bench, so, md) if not p.exists()]
    if missing:
        print("benchmark: missing " + ", ".join(str(p) for p in missing) + ".\n"
              "Build first: `bash scripts/setup.sh` (fresh machine) or `cmake --build build` "
              "(the top-level CMakeLists.txt must contain add_subdirectory(benchmarks)).", file=sys.stderr)
        return None
    return bench, so, md


def choose_methods(drv: Driver, requested: str | None) -> list | None:
    """The solver.method values to measure: `requested` (comma-separated), else the FMU's own
    methods and the SUNDIALS references; [None] (the default integrator) for an FMU without the
    parameter; None when methods are requested of such an FMU (said on stderr)."""
    if requested is not None:
        methods = [int(m) for m in requested.split(",")]
        if not drv.has_method:
            print("benchmark: --methods given but the FMU has no parameter solver.method", file=sys.stderr)
            return None
        return methods
    if drv.has_method:
        return [4, 5, 6, REAL_TIME, 0, 3] if drv.default_method == 4 else [0, 1, 2, 3]
    log("note: the FMU has no parameter 'solver.method': only its default integrator is measured")
    return [None]


def measure_references(drv: Driver, fidelities, args, record: dict) -> dict | None:
    """Step 1: the reference trajectory per fidelity (rtol 1e-12), and a second solution to bound
    its own error, each put in `record`; returns the trajectories, None if a reference failed."""
    references: dict = {}
    ref_method = 0 if drv.has_method else None
    for fid in fidelities:
        log(f"[reference] {fid}: rtol 1e-12, atol 1e-14, {args.duration:g} s ...")
        ref = drv.run(method=ref_method, fidelity=fid, rtol=1e-12, atol=1e-14, duration=args.duration,
                      step=args.step, trajectory=True, timeout=max(args.run_timeout, 600))
        if ref.get("failure") or "_trajectory" not in ref:
            log(f"  reference failed: {ref.get('failure')}")
            return None
        references[fid] = ref["_trajectory"]
        # A second solution to bound the reference's own error: another method, or rtol 1e-11.
        # ARKODE's explicit RK (method 3) shares nothing with CVODE BDF but the model.
        check_method = 3 if drv.has_method else None
        check = drv.run(method=check_method, fidelity=fid, rtol=1e-12 if drv.has_method else 1e-11,
                        atol=1e-14 if drv.has_method else 1e-13, duration=args.duration, step=args.step,
                        trajectory=True, timeout=max(args.run_timeout, 600))
        spread = errors_against(check, references[fid])
        record[fid] = {"run": strip(ref), "check_run": strip(check), "check_difference": spread}
        log(f"  cpu {ref['cpu_s']:.2f} s; second solution differs by beta {fmt(spread['err_beta'])} rad, "
            f"alpha {fmt(spread['err_alpha'])} rad, omega {fmt(spread['err_omega'])} rad/s")
    return references


def work_precision_sweep(drv: Driver, methods, fidelities, rtols, args, references: dict) -> list:
    """Step 2: every method x fidelity x rtol, its CPU time and its errors against the reference
    (the tighter tolerances of a method that timed out are skipped)."""
    sweep = []
    for fid in fidelities:
        for m in methods:
            # The real-time method's axis is its substeps (rtol None), every other method's its tolerance.
            settings = ([(None, None, n) for n in REAL_TIME_SUBSTEPS] if m == REAL_TIME else
                        [(rtol, rtol * args.atol_factor, None) for rtol in rtols])
            for rtol, atol, substeps in settings:
                point = sweep_point(drv, fid, m, rtol, atol, substeps, args, references[fid])
                sweep.append(point)
                if point.get("failure", "").startswith("timeout"):
                    log("  (tighter tolerances of this method skipped)")
                    break
    return sweep


def sweep_point(drv: Driver, fid: str, m, rtol, atol, substeps, args, reference) -> dict:
    """One point of the sweep: the fastest of up to three runs (cheap runs are noisy), its errors."""
    parameters = {"solver.substeps": substeps} if substeps else None
    settings = {"method": m, "fidelity": fid, "rtol": rtol, "atol": atol, "duration": args.duration,
                "step": args.step, "parameters": parameters}
    run = drv.run(trajectory=True, **settings)
    keep_fastest(drv, run, settings, repeats=2)
    if not run.get("failure"):
        fmu_cpu = run["cpu_s"] - (run.get("master_cpu_s") or 0.0)
        run["fmu_cpu_s"] = fmu_cpu
        run["fmu_rtf"] = run["simulated"] / fmu_cpu if fmu_cpu > 0 else None
    point = {"fidelity": fid, "method": m, "rtol": rtol, "atol": atol, "substeps": substeps,
             **errors_against(run, reference), **strip(run)}
    log(f"[sweep] {fid:7s} method {fmt(m, '')!s:4s} {setting_label(point):>7s}: "
        + (f"FAILED {run['failure']}" if run.get("failure") else
           f"cpu {run['cpu_s']:.3f} s  rtf {run['rtf']:9.1f}  err beta {fmt(point['err_beta'])}  "
           f"alpha {fmt(point['err_alpha'])}  omega {fmt(point['err_omega'])}  "
           f"steps {run['solver_steps']}  rhs {run['rhs_evaluations']}  jac {run['jacobian_evaluations']}"))
    return point


def keep_fastest(drv: Driver, run: dict, settings: dict, repeats: int) -> None:
    """A run under 0.5 s of CPU is repeated up to `repeats` times; `run` takes the fastest's times."""
    if run.get("failure") or run["cpu_s"] >= 0.5:
        return
    for _ in range(repeats):
        again = drv.run(**settings)
        if not again.get("failure") and again["cpu_s"] < run["cpu_s"]:
            for key in ("cpu_s", "wall_s", "rtf", "cpu_us_per_step", "master_cpu_s"):
                run[key] = again[key]


def setting_label(point: dict) -> str:
    """What sets a sweep point's accuracy: its rtol, or the real-time method's substeps."""
    if point.get("substeps"):
        return f"n={point['substeps']}"
    return f"{point['rtol']:.0e}".replace("e-0", "e-")


def at_target_error(sweep: list, methods, fidelities) -> list:
    """The cheapest run meeting the beta target, per method and fidelity."""
    best = []
    for fid in fidelities:
        for m in methods:
            ok = [p for p in sweep if p["fidelity"] == fid and p["method"] == m and p["err_beta"] is not None
                  and p["err_beta"] <= TARGET_BETA_ERROR]
            if ok:
                p = min(ok, key=lambda p: p["cpu_s"])
                best.append({"fidelity": fid, "method": m, "rtol": p["rtol"], "substeps": p.get("substeps"),
                             "cpu_s": p["cpu_s"],
                             "rtf": p["rtf"], "fmu_rtf": p.get("fmu_rtf"),
                             "cpu_us_per_step": p["cpu_us_per_step"], "err_beta": p["err_beta"], "err_alpha": p["err_alpha"],
                             "err_omega": p["err_omega"], "target_rtf": TARGET_RTF.get(fid),
                             "meets_target": p["rtf"] >= TARGET_RTF.get(fid, 0)})
            else:
                best.append({"fidelity": fid, "method": m, "rtol": None, "cpu_s": None, "rtf": None,
                             "err_beta": None, "target_rtf": TARGET_RTF.get(fid), "meets_target": False})
    return best


def cost_vs_duration(drv: Driver, best: list, args) -> dict:
    """Step 3: the FMU's default integrator, full fidelity, at the loosest swept tolerance that
    meets the beta target, for each of --durations (shortened to fit --duration-budget)."""
    full_default = [p for p in best if p["fidelity"] == "full" and p["method"] == drv.default_method]
    default_rtol = full_default[0]["rtol"] if full_default and full_default[0]["rtol"] else None
    durations = [float(x) for x in args.durations.split(",")]
    growth = []
    rate = None
    for d in durations:
        planned = d
        if rate is not None and d / rate > args.duration_budget:
            planned = max(durations[0], math.floor(args.duration_budget * rate / 10.0) * 10.0)
            log(f"[duration] {d:g} s would take ~{d / rate:.0f} s CPU: running {planned:g} s instead")
        run = drv.run(fidelity="full", rtol=default_rtol, atol=None if default_rtol is None else default_rtol * args.atol_factor,
                      duration=planned, step=args.step, timeout=max(args.run_timeout, 4 * args.duration_budget))
        if run.get("failure"):
            log(f"[duration] {planned:g} s: FAILED {run['failure']}")
            growth.append({"requested_s": d, "simulated_s": planned, "failure": run["failure"]})
            continue
        rate = run["simulated"] / run["cpu_s"]
        growth.append({"requested_s": d, "simulated_s": run["simulated"], "cpu_s": run["cpu_s"],
                       "cpu_us_per_simulated_ms": 1e3 * run["cpu_s"] / run["simulated"], "rtf": run["rtf"],
                       "solver_steps": run["solver_steps"], "rhs_evaluations": run["rhs_evaluations"],
                       "events": run["events"], "dostep_allocations": run["dostep_allocations"]})
        log(f"[duration] {run['simulated']:g} s: cpu {run['cpu_s']:.3f} s = "
            f"{1e3 * run['cpu_s'] / run['simulated']:.2f} us per simulated ms, rtf {run['rtf']:.1f}")
    return {"method": drv.default_method, "fidelity": "full", "rtol": default_rtol, "runs": growth}


def fmi_overhead(drv: Driver, fidelities, overhead_steps: int) -> dict:
    """Step 4: doStep of a model at rest (1 us steps) per fidelity, and the instance's memory."""
    overhead = {}
    for fid in fidelities:
        run = drv.run(fidelity=fid, overhead=True, overhead_steps=overhead_steps, trace=True)
        overhead[fid] = strip(run)
        if run.get("failure"):
            log(f"[overhead] {fid}: FAILED {run['failure']}")
        else:
            log(f"[overhead] {fid}: {run['ns_per_dostep']:.0f} ns per doStep (CPU), "
                f"{run['rhs_evaluations'] / max(1, run['dostep_calls']):.2f} rhs per doStep; instance "
                f"{run['instance_bytes']} bytes in {run['instance_allocations']} allocations; "
                f"{run['dostep_allocations']} allocations in {run['dostep_calls']} doSteps")
    return overhead


def allocations_in_dostep(drv: Driver, fidelities, step: float) -> dict:
    """Step 5: heap allocations inside doStep after the first (2 s of the scene) and their call sites."""
    alloc = {}
    for fid in fidelities:
        run = drv.run(fidelity=fid, duration=2.0, step=step, trace=True)
        alloc[fid] = {k: run.get(k) for k in ("dostep_calls", "first_step_allocations", "dostep_allocations",
                                              "dostep_alloc_bytes", "events", "allocation_sites", "failure")}
        log(f"[allocations] {fid}: {run.get('dostep_allocations')} allocations in "
            f"{run.get('dostep_calls')} doSteps after the first ({run.get('events')} events)")
    return alloc


def core_costs(core_bench: pathlib.Path, fidelities) -> dict:
    """Step 8: the core's pieces without FMI or an integrator (gimbal_bench_core): ns per right-hand
    side, event check, Jacobian and outputs, per fidelity; {} when the driver was not built."""
    if not core_bench.exists():
        log(f"[core] {core_bench} is missing: the core's costs are not measured")
        return {}
    costs = {}
    for fid in fidelities:
        done = subprocess.run([str(core_bench), "--json", "--fidelity", fid], capture_output=True, text=True)
        lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
        costs[fid] = json.loads(lines[-1]) if lines else {"failure": done.stderr.strip()[-500:]}
        log(f"[core] {fid}: " + ", ".join(f"{k} {v}" for k, v in costs[fid].items()))
    return costs


def write_results(results: dict, out: pathlib.Path, methods, fidelities, duration: float) -> None:
    """OUT/results.json and OUT/work_precision.png; the tables on stdout."""
    out.mkdir(parents=True, exist_ok=True)
    out_json = out / "results.json"
    out_json.write_text(json.dumps(results, indent=1) + "\n")
    png = out / "work_precision.png"
    plot(results, png, methods, fidelities, duration)
    summary(results, methods, fidelities, duration)
    log(f"\nwrote {out_json.relative_to(REPO) if out_json.is_relative_to(REPO) else out_json} and "
        f"{png.relative_to(REPO) if png.is_relative_to(REPO) else png} in {results['elapsed_s']:.0f} s")


def single_dosteps(drv: Driver, duration: float, step: float) -> list:
    """Step 7: the distribution of single doSteps, in wall time (the machine's noise included) and in
    right-hand sides (the work, free of it): the default and the real-time method at 1, 2, 4 substeps."""
    runs = []
    for label, method, parameters in (("default", None, None),
                                      *((f"real time, {n} substep{'s' if n > 1 else ''}", REAL_TIME,
                                         {"solver.substeps": n}) for n in (1, 2, 4))):
        log(f"[doStep] {label}: {duration:g} s, every doStep timed ...")
        run = drv.run(method=method, duration=duration, step=step, parameters=parameters, time_dostep=True)
        entry = {"label": label, "method": method, "parameters": parameters, **strip(run)}
        runs.append(entry)
        if run.get("failure"):
            log(f"  FAILED {run['failure']}")
            continue
        log(f"  wall us: median {1e6 * run['dostep_p50_s']:.2f}  p99 {1e6 * run['dostep_p99_s']:.2f}  "
            f"p99.9 {1e6 * run['dostep_p999_s']:.2f}  max {1e6 * run['dostep_max_s']:.2f};  thread CPU us: median "
            f"{1e6 * run['dostep_cpu_p50_s']:.2f}  p99.9 {1e6 * run['dostep_cpu_p999_s']:.2f}  max "
            f"{1e6 * run['dostep_cpu_max_s']:.2f};  right-hand sides: median "
            f"{run['rhs_per_dostep_median']:.0f}  p99.9 {run['rhs_per_dostep_p999']:.0f}  max {run['rhs_per_dostep_max']:.0f}")
    return runs


def stiff_cases(drv: Driver, duration: float, step: float, timeout: float) -> list:
    """Each stiff variant at default settings, against CVODE BDF at rtol 1e-11 and at its default."""
    cases = []
    for name, parameters in STIFF_VARIANTS.items():
        log(f"[stiff] {name}: reference (CVODE BDF, rtol 1e-11), {duration:g} s ...")
        ref = drv.run(method=0, rtol=1e-11, atol=1e-13, duration=duration, step=step, trajectory=True,
                      parameters=parameters, timeout=max(timeout, 900))
        if ref.get("failure"):
            log(f"  reference failed: {ref['failure']}")
            cases.append({"case": name, "parameters": parameters, "failure": "reference: " + ref["failure"]})
            continue
        case = {"case": name, "parameters": parameters, "reference": strip(ref)}
        second = drv.run(method=0, rtol=1e-10, atol=1e-12, duration=duration, step=step, trajectory=True,
                         parameters=parameters, timeout=max(timeout, 900))
        if not second.get("failure"):
            case["reference_spread"] = errors_against(second, ref["_trajectory"], SHORT_HORIZON)
        for label, method in (("default", None), ("cvode_default", 0)):
            settings = {"method": method, "duration": duration, "step": step, "parameters": parameters}
            run = drv.run(trajectory=True, **settings)
            keep_fastest(drv, run, settings, repeats=1)
            case[label] = {**errors_against(run, ref["_trajectory"], SHORT_HORIZON), **strip(run)}
            if not run.get("failure") and run.get("events"):
                # Where impacts set the cost: the work per mode change (nearly all are backlash impacts).
                case[label]["steps_per_event"] = run["solver_steps"] / run["events"]
                case[label]["us_per_event"] = 1e6 * run["cpu_s"] / run["events"]
            log(f"  {label:13s} " + (f"FAILED {run['failure']}" if run.get("failure") else
                                     f"rtf {run['rtf']:8.1f}  err beta {fmt(case[label]['err_beta'])}  alpha "
                                     f"{fmt(case[label]['err_alpha'])}  steps {run['solver_steps']}  jac "
                                     f"{run['jacobian_evaluations']}  switches {run.get('method_switches')}"))
        cases.append(case)
    return cases


PLOT_COLORS = {None: "k", 0: "tab:blue", 1: "tab:orange", 2: "tab:green", 3: "tab:red", 4: "k", 5: "tab:purple",
               6: "tab:brown", REAL_TIME: "tab:cyan"}
PLOT_STYLES = {"full": ("-", "o"), "reduced": ("--", "s")}


def plot(results: dict, path: pathlib.Path, methods, fidelities, duration: float) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 5.8), sharey=True)
    for ax, key, label in ((axes[0], "err_beta", "max error of beta [rad]"),
                           (axes[1], "err_omega", "max error of los.omega [rad/s]")):
        for fid in fidelities:
            for m in methods:
                plot_method(ax, results["sweep"], key, fid, m)
        ax.set_xlabel(label)
        ax.grid(True, which="both", alpha=0.3)
    plot_targets(axes, fidelities)
    axes[0].set_ylabel("CPU time per simulated ms [us]  (1000 / real-time factor)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=7, loc="lower center", ncol=4, frameon=False)
    m = results["machine"]
    fig.suptitle(f"Gimbal2Axis work-precision, ship stabilization {duration:g} s at 1 kHz "
                 f"(labels: rtol, atol = rtol/100; n = the real-time method's substeps)\n{m['cpu']}, {m['compiler']}, commit {m['git_commit'][:10]}"
                 f"{' (dirty)' if m['git_dirty'] else ''}", fontsize=9)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(path, dpi=90)
    plt.close(fig)


def plot_method(ax, sweep: list, key: str, fid: str, m) -> None:
    """One method's curve at one fidelity: CPU per simulated ms against the error `key`, labelled."""
    pts = [p for p in sweep if p["fidelity"] == fid and p["method"] == m and p.get(key) is not None
           and not p.get("failure")]
    if not pts:
        return
    x = [max(p[key], 1e-16) for p in pts]
    y = [1e3 * p["cpu_s"] / p["simulated"] for p in pts]
    ls, mk = PLOT_STYLES.get(fid, ("-", "o"))
    ax.loglog(x, y, ls=ls, marker=mk, color=PLOT_COLORS.get(m, "gray"), ms=4, label=f"{METHOD_NAMES.get(m, m)}, {fid}")
    for p, xi, yi in zip(pts, x, y):
        ax.annotate(setting_label(p), (xi, yi), fontsize=6, alpha=0.6, xytext=(2, 2), textcoords="offset points")


def plot_targets(axes, fidelities) -> None:
    """The real-time targets as horizontal lines, the beta bound as a vertical one."""
    axes[0].axvline(TARGET_BETA_ERROR, color="gray", lw=0.8, ls=":")
    for fid, rtf in TARGET_RTF.items():
        if fid in fidelities:
            for ax in axes:
                ax.axhline(1e3 / rtf, color="gray", lw=0.8, ls=PLOT_STYLES[fid][0])
                ax.text(0.01, 1e3 / rtf * 1.08, f"target {fid}: {rtf:.0f}x real time", fontsize=7, color="gray",
                        transform=ax.get_yaxis_transform())
    axes[0].text(TARGET_BETA_ERROR * 0.9, 0.5, "beta bound 1e-6 rad", rotation=90, fontsize=7, color="gray",
                 ha="right", transform=axes[0].get_xaxis_transform())


def summary(results: dict, methods, fidelities, duration: float) -> None:
    """The tables on stdout, one function per step."""
    for section in (summary_sweep, summary_at_target, summary_durations, summary_overhead, summary_allocations,
                    summary_stiff, summary_single_dosteps, summary_core):
        section(results, duration)


def method_name(m) -> str:
    return str(METHOD_NAMES.get(m, m))


def summary_sweep(results: dict, duration: float) -> None:
    log("\n=== work precision (ship stabilization, %g s, 1 kHz; errors vs rtol 1e-12 reference) ===" % duration)
    log(f"{'fidelity':8s} {'method':38s} {'rtol':>7s} {'cpu [s]':>9s} {'RTF':>10s} {'err beta':>9s} "
        f"{'err alpha':>9s} {'err omega':>9s} {'steps':>8s} {'rhs':>9s} {'jac':>7s} {'events':>6s}")
    for p in results["sweep"]:
        head = f"{p['fidelity']:8s} {method_name(p['method']):38s} {setting_label(p):>7s}"
        if p.get("failure"):
            log(f"{head}  FAILED: {p['failure'][:60]}")
            continue
        log(f"{head} {p['cpu_s']:9.3f} {p['rtf']:10.1f} {fmt(p['err_beta']):>9s} {fmt(p['err_alpha']):>9s} "
            f"{fmt(p['err_omega']):>9s} {p['solver_steps']:8d} {p['rhs_evaluations']:9d} {p['jacobian_evaluations']:7d} "
            f"{p['events']:6d}")


def summary_at_target(results: dict, duration: float) -> None:
    log(f"\n=== at max beta error <= {TARGET_BETA_ERROR:g} rad (cheapest tolerance of the sweep) ===")
    log(f"{'fidelity':8s} {'method':38s} {'rtol':>7s} {'us/step':>8s} {'RTF':>9s} {'RTF FMU':>9s} {'target':>7s}  met")
    for b in results["at_target_error"]:
        log(f"{b['fidelity']:8s} {method_name(b['method']):38s} {fmt(b['rtol'], '.0e'):>7s} "
            f"{fmt(b.get('cpu_us_per_step'), '.2f'):>8s} {fmt(b['rtf'], '.1f'):>9s} {fmt(b.get('fmu_rtf'), '.1f'):>9s} "
            f"{fmt(b['target_rtf'], '.0f'):>7s}  {'yes' if b['meets_target'] else 'NO'}"
            + (f"  (substeps {b['substeps']})" if b.get("substeps") else ""))
    log("(RTF = simulated / CPU time of the whole master loop; RTF FMU leaves out the master's own share)")


def summary_durations(results: dict, duration: float) -> None:
    log("\n=== cost against simulated time (FMU default integrator, full fidelity) ===")
    for g in results["cost_vs_duration"]["runs"]:
        if g.get("failure"):
            log(f"{g['simulated_s']:8g} s  FAILED {g['failure']}")
        else:
            log(f"{g['simulated_s']:8g} s  cpu {g['cpu_s']:9.3f} s  {g['cpu_us_per_simulated_ms']:8.2f} us/ms  "
                f"RTF {g['rtf']:9.1f}  steps {g['solver_steps']}")


def summary_overhead(results: dict, duration: float) -> None:
    log(f"\n=== FMI overhead (model at rest, fixed base, 1 us steps; target < {TARGET_OVERHEAD_NS:.0f} ns) ===")
    for fid, o in results["fmi_overhead"].items():
        if o.get("failure"):
            log(f"{fid:8s} FAILED {o['failure']}")
        else:
            log(f"{fid:8s} {o['ns_per_dostep']:8.0f} ns per doStep; instance {o['instance_bytes']} bytes; "
                f"{o['dostep_allocations']} allocations in {o['dostep_calls']} doSteps")


def summary_allocations(results: dict, duration: float) -> None:
    log("\n=== heap allocations in doStep after the first (ship stabilization 2 s) ===")
    for fid, a in results["allocations_in_dostep"].items():
        log(f"{fid:8s} {a['dostep_allocations']} allocations ({a['dostep_alloc_bytes']} bytes) in {a['dostep_calls']} doSteps")
        for site in (a.get("allocation_sites") or [])[:6]:
            lines = [line for line in re.split(r"\n|\s{4,}(?=#\d)", site) if line.strip()]
            # The first frames that are neither the allocator nor the C++ library say who allocates.
            own = [line.strip().split(" ", 2)[-1] for line in lines[1:]
                   if not any(x in line for x in ("operator new", "std::", " N_VNew", " N_VClone", "malloc"))]
            log("    " + lines[0] + " " + " <- ".join(own[:3]))


def summary_stiff(results: dict, duration: float) -> None:
    log(f"\n=== stiff variants at default settings (target >= {TARGET_STIFF_RTF:.0f}x real time, no discard) ===")
    for c in results.get("stiff_cases", []):
        if c.get("failure"):
            log(f"{c['case']:22s} FAILED {c['failure']}")
            continue
        spread = c.get("reference_spread")
        if spread:
            log(f"{c['case']:22s} {'references':13s} CVODE BDF rtol 1e-10 against 1e-11: beta {fmt(spread['err_beta'])}"
                f" (first {SHORT_HORIZON:g} s: {fmt(spread['err_beta_short'])})")
        for label in ("default", "cvode_default"):
            log(f"{c['case']:22s} {label:13s} " + stiff_line(c[label]))


def stiff_line(r: dict) -> str:
    if r.get("failure"):
        return f"FAILED {r['failure'][:60]}"
    return (f"RTF {r['rtf']:8.1f}  {r['cpu_us_per_step']:8.1f} us/step  err beta {fmt(r['err_beta'])} "
            f"(first {SHORT_HORIZON:g} s: {fmt(r.get('err_beta_short'))})  alpha {fmt(r['err_alpha'])}  omega "
            f"{fmt(r['err_omega'])}  mode changes {r.get('events')}: {r.get('steps_per_event', 0):.1f} steps, "
            f"{r.get('us_per_event', 0):.1f} us each")


def summary_single_dosteps(results: dict, duration: float) -> None:
    log("\n=== single doSteps (wall and thread CPU time include the machine's interrupts; right-hand sides "
        "are the work) ===")
    log(f"{'':26s} {'median':>8s} {'p99':>8s} {'p99.9':>8s} {'max':>8s}  [us wall]   {'median':>7s} {'p99.9':>7s} "
        f"{'max':>7s}  [us CPU]   {'median':>6s} {'p99.9':>6s} {'max':>6s}  [right-hand sides]  max/median")
    for r in results.get("single_dosteps", []):
        if r.get("failure"):
            log(f"{r['label']:26s} FAILED {r['failure'][:60]}")
            continue
        wall = [1e6 * r[k] for k in ("dostep_p50_s", "dostep_p99_s", "dostep_p999_s", "dostep_max_s")]
        cpu = [1e6 * r[k] for k in ("dostep_cpu_p50_s", "dostep_cpu_p999_s", "dostep_cpu_max_s")]
        work = [r[k] for k in ("rhs_per_dostep_median", "rhs_per_dostep_p999", "rhs_per_dostep_max")]
        log(f"{r['label']:26s} " + " ".join(f"{w:8.2f}" for w in wall) + "             "
            + " ".join(f"{c:7.2f}" for c in cpu) + "            "
            + " ".join(f"{w:6.0f}" for w in work)
            + f"                      {wall[3] / wall[0]:.1f} / {cpu[2] / cpu[0]:.1f} / {work[2] / work[0]:.1f}")


def summary_core(results: dict, duration: float) -> None:
    log("\n=== the core without FMI or an integrator (gimbal_bench_core; targets: RHS <= 150 ns, event check "
        "<= 50 ns) ===")
    for fid, c in results.get("core_costs", {}).items():
        log(f"{fid:8s} " + (f"FAILED {c['failure']}" if c.get("failure") else
                            f"RHS {c['rhs_ns']:.0f} ns, event check {c['event_check_ns']:.0f} ns, Jacobian "
                            f"{c['jacobian_ns']:.0f} ns, outputs {c['outputs_ns']:.0f} ns"))


if __name__ == "__main__":
    sys.exit(main())
