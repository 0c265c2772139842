#!/usr/bin/env bash
# Instructions per right-hand side and per doStep, counted with callgrind, for revisions of the project
# (default: 72cbcfa, the review's base of issue 35, and HEAD), each built the same way.
#
#   bash benchmarks/callgrind_cost.sh [REV ...]
#
# For each revision: `git archive` into $WORK/<commit>/ (kept: a second run reuses the source and the
# build), configure (Release, -DGIMBAL_RECORD_BUILD_IN_PACKAGE=OFF, plus $CMAKE_ARGS), build
# gimbal_bench_core and gimbal_bench (which builds the FMU), then under callgrind:
#   (a) right-hand side: gimbal_bench_core --calls $CALLS; the inclusive instructions of
#       gimbal::GimbalHybridSystem::derivative over its calls (the core directly: no FMI, no integrator);
#   (b) doStep: gimbal_bench (the ship scene at 1 kHz, defaults) for $DURATION s; the inclusive
#       instructions of fmi2DoStep over its calls (the FMU's whole doStep: integration, events, outputs).
# Instructions do not depend on the load of the shared machine. Prints a table and writes
# benchmarks/results/callgrind_cost.json.
#
# Environment: WORK (default ${TMPDIR:-/tmp}/gimbal2axis_callgrind), CMAKE_ARGS (e.g.
# "-DPython3_EXECUTABLE=/path/to/venv/bin/python" of a Python with fmpy, for the FMI headers), CALLS
# (default 2000: 10,000 right-hand sides), DURATION (default 10: 10,000 doSteps), OUT (the json).
# Needs valgrind (apt-get install valgrind), cmake, ninja, a C and C++ compiler, Eigen and SUNDIALS.
set -euo pipefail

repo=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
WORK=${WORK:-${TMPDIR:-/tmp}/gimbal2axis_callgrind}
CALLS=${CALLS:-2000}
DURATION=${DURATION:-10}
OUT=${OUT:-$repo/benchmarks/results/callgrind_cost.json}
CMAKE_ARGS=${CMAKE_ARGS:-}
if [ $# -eq 0 ]; then set -- 72cbcfa HEAD; fi
command -v valgrind >/dev/null || { echo "valgrind is missing (apt-get install valgrind)" >&2; exit 1; }

mkdir -p "$WORK"
rows=()
for rev in "$@"; do
    commit=$(git -C "$repo" rev-parse --verify "$rev^{commit}")
    dir=$WORK/${commit:0:12}
    if [ ! -f "$dir/CMakeLists.txt" ]; then
        mkdir -p "$dir"
        git -C "$repo" archive "$commit" | tar -x -C "$dir"
    fi
    if [ ! -f "$dir/build/build.ninja" ]; then
        # shellcheck disable=SC2086
        nice -n 15 cmake -S "$dir" -B "$dir/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
            -DGIMBAL_RECORD_BUILD_IN_PACKAGE=OFF $CMAKE_ARGS >"$dir/configure.log"
    fi
    echo "== $rev ($commit): building gimbal_bench_core and gimbal_bench" >&2
    nice -n 15 ninja -C "$dir/build" gimbal_bench_core gimbal_bench >"$dir/build.log"
    fmu=$(ls "$dir"/build/fmu_staging/binaries/linux64/*.so | head -n 1)

    echo "== $rev: callgrind, right-hand side ($CALLS x 5 calls)" >&2
    nice -n 15 valgrind --tool=callgrind --compress-strings=no --compress-pos=no \
        --callgrind-out-file="$dir/rhs.callgrind" "$dir/build/benchmarks/gimbal_bench_core" --calls "$CALLS" \
        >"$dir/rhs.txt" 2>"$dir/rhs.valgrind.log"
    echo "== $rev: callgrind, doStep ($DURATION s of the ship scene)" >&2
    nice -n 15 valgrind --tool=callgrind --compress-strings=no --compress-pos=no \
        --callgrind-out-file="$dir/dostep.callgrind" "$dir/build/benchmarks/gimbal_bench" --fmu "$fmu" \
        --duration "$DURATION" --no-trace --json >"$dir/dostep.json" 2>"$dir/dostep.valgrind.log"
    rows+=("$rev" "$commit" "$dir")
done

python3 - "$OUT" "$CALLS" "$DURATION" "${rows[@]}" <<'EOF'
import datetime, json, os, re, subprocess, sys

out, calls, duration, rows = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), sys.argv[4:]


def inclusive_per_call(path, match):
    """Sum, over every call arc into a function whose name `match` accepts, of the call counts and of
    the inclusive instructions callgrind records for them (the first event, Ir)."""
    names, callee, calls, cost, pending = {}, None, 0, 0, 0
    with open(path) as f:
        for line in f:
            if pending:
                cost += int(line.split()[1])
                pending = 0
                continue
            if line.startswith("cfn="):
                m = re.match(r"cfn=(?:\((\d+)\))? ?(.*)", line.rstrip("\n"))
                ident, name = m.groups()
                if ident and name:
                    names[ident] = name
                callee = name or names.get(ident, "")
            elif line.startswith("fn="):
                m = re.match(r"fn=(?:\((\d+)\))? ?(.*)", line.rstrip("\n"))
                ident, name = m.groups()
                if ident and name:
                    names[ident] = name
            elif line.startswith("calls=") and callee is not None and match(callee):
                calls += int(line.split("=")[1].split()[0])
                pending = 1
    return calls, cost


def compiler(build):
    try:
        with open(os.path.join(build, "CMakeCache.txt")) as f:
            cxx = next(l.split("=", 1)[1].strip() for l in f if l.startswith("CMAKE_CXX_COMPILER:"))
        return subprocess.run([cxx, "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except Exception:
        return None


results = []
for i in range(0, len(rows), 3):
    rev, commit, folder = rows[i:i + 3]
    rhs_calls, rhs_cost = inclusive_per_call(os.path.join(folder, "rhs.callgrind"),
                                             lambda n: n.startswith("gimbal::GimbalHybridSystem::derivative("))
    step_calls, step_cost = inclusive_per_call(os.path.join(folder, "dostep.callgrind"),
                                               lambda n: n == "fmi2DoStep")
    # The same run: the core's step inside fmi2DoStep (what is left of fmi2DoStep is the FMI layer's own
    # work), and the two FMI calls the master makes around every doStep.
    fmi = {}
    for name in ("gimbal_core_do_step", "fmi2SetReal", "fmi2GetReal"):
        n, cost = inclusive_per_call(os.path.join(folder, "dostep.callgrind"), lambda f, name=name: f == name)
        fmi[name] = {"calls": n, "instructions_per_call": cost / n if n else None}
    driver = json.loads(open(os.path.join(folder, "dostep.json")).read().strip().splitlines()[-1])
    rhs_evaluations = driver.get("rhs_evaluations")
    results.append({
        "revision": rev, "commit": commit,
        "rhs_calls": rhs_calls, "rhs_instructions": rhs_cost,
        "instructions_per_rhs": rhs_cost / rhs_calls if rhs_calls else None,
        "dostep_calls": step_calls, "dostep_instructions": step_cost,
        "instructions_per_dostep": step_cost / step_calls if step_calls else None,
        "rhs_per_dostep": rhs_evaluations / step_calls if rhs_evaluations and step_calls else None,
        "core_instructions_per_dostep": fmi["gimbal_core_do_step"]["instructions_per_call"],
        "fmi_own_instructions_per_dostep": (step_cost / step_calls - fmi["gimbal_core_do_step"]["instructions_per_call"]
                                            if step_calls and fmi["gimbal_core_do_step"]["calls"] else None),
        "fmi_calls": fmi,
        "solver_steps": driver.get("solver_steps"), "events": driver.get("events"),
        "compiler": compiler(os.path.join(folder, "build")),
    })

valgrind = subprocess.run(["valgrind", "--version"], capture_output=True, text=True).stdout.strip()
print(f"\ncallgrind ({valgrind}), instructions, Release builds")
print(f"{'revision':<12} {'commit':<10} {'per RHS':>10} {'RHS calls':>10} {'per doStep':>12} {'doSteps':>8} "
      f"{'RHS/doStep':>10} {'steps':>8}")
for r in results:
    print(f"{r['revision']:<12} {r['commit'][:9]:<10} {r['instructions_per_rhs']:10.1f} {r['rhs_calls']:10d} "
          f"{r['instructions_per_dostep']:12.1f} {r['dostep_calls']:8d} {r['rhs_per_dostep'] or 0:10.2f} "
          f"{r['solver_steps'] or 0:8d}")
print("\nin the doStep run, instructions per call")
print(f"{'revision':<12} {'core do_step':>13} {'fmi2DoStep own':>15} {'fmi2SetReal':>12} {'fmi2GetReal':>12}")
for r in results:
    f = r["fmi_calls"]
    cell = lambda v: f"{v:.1f}" if v is not None else "-"
    print(f"{r['revision']:<12} {cell(r['core_instructions_per_dostep']):>13} "
          f"{cell(r['fmi_own_instructions_per_dostep']):>15} {cell(f['fmi2SetReal']['instructions_per_call']):>12} "
          f"{cell(f['fmi2GetReal']['instructions_per_call']):>12}")
if len(results) >= 2:
    a, b = results[0], results[-1]
    print(f"\n{b['revision']} / {a['revision']}: RHS {b['instructions_per_rhs'] / a['instructions_per_rhs']:.4f}, "
          f"doStep {b['instructions_per_dostep'] / a['instructions_per_dostep']:.4f}")
doc = {
    "what": "instructions per right-hand side (gimbal_bench_core, inclusive cost of "
            "GimbalHybridSystem::derivative per call) and per doStep (gimbal_bench, the ship scene at 1 kHz with "
            "the defaults, inclusive cost of fmi2DoStep per call); in the same run gimbal_core_do_step (the core's "
            "step inside fmi2DoStep; fmi2DoStep less it is the FMI layer's own work), fmi2SetReal and fmi2GetReal "
            "per call. benchmarks/callgrind_cost.sh",
    "measured": datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0).isoformat(),
    "valgrind": valgrind, "calls": calls, "duration_s": duration, "revisions": results,
}
if len(results) >= 2:
    doc["ratio_last_to_first"] = {
        "rhs": results[-1]["instructions_per_rhs"] / results[0]["instructions_per_rhs"],
        "dostep": results[-1]["instructions_per_dostep"] / results[0]["instructions_per_dostep"]}
os.makedirs(os.path.dirname(out), exist_ok=True)
with open(out, "w") as f:
    f.write(json.dumps(doc, indent=1) + "\n")
print(f"wrote {out}")
EOF
