"""Issue 44's fuzz test: scene, sweep and tuning files mutated from the project's own (random types,
sizes, nesting, numbers at the float limits), each run through the command under a memory limit.
Every case must end with exit status 0, 1, 2 or 3, with no traceback; a refused run (exit 2) must
leave the record of the run before it in the same --out as it was.

The cases are made from a fixed seed (GIMBAL2AXIS_FUZZ_SEED overrides it; GIMBAL2AXIS_FUZZ_SCALE multiplies their number) and run in ONE Python
process, started with an address-space limit (RLIMIT_AS, what `ulimit -v` sets), which calls
gimbal2axis.cli.main.main in-process case after case: a process per case would cost a second of
imports each. Runs are cut to a few steps; most figures are not rendered (savefig writes an empty file:
rendering is 95 % of a short run's time), every RENDER_EVERY-th case renders them for real.

    python tests/package/test_toml_fuzz.py CASES.json RESULTS.json   # the driver the test starts
"""
from __future__ import annotations

import contextlib
import hashlib
import io
import json
import math
import os
import pathlib
import random
import resource
import shutil
import signal
import subprocess
import sys
import time
import tomllib
import traceback

import pytest

pytestmark = pytest.mark.memory_limit

ROOT = pathlib.Path(__file__).resolve().parents[2]
SEED = int(os.environ.get("GIMBAL2AXIS_FUZZ_SEED", "44"))
# GIMBAL2AXIS_FUZZ_SCALE multiplies the cases (a longer search than CI's, by hand)
SCALE = float(os.environ.get("GIMBAL2AXIS_FUZZ_SCALE", "1"))
CASES_PER_KIND = {kind: round(count * SCALE) for kind, count in {"run": 150, "sweep": 60, "tune": 50}.items()}
MEMORY_LIMIT_BYTES = 3 << 30          # the driver's RLIMIT_AS: ulimit -v 3145728
CASE_TIME_LIMIT_S = 30.0              # a case still going after this is a hang
DRIVER_TIME_LIMIT_S = 600.0 * max(SCALE, 1.0)
EXPECTED_STATUSES = {0, 1, 2, 3}
RENDER_EVERY = 10
# What a case's run is cut to: a few communication steps of the scenes' 1 ms.
RUN_STOP_TIME = "0.005"
# The sweep and the tuning a case mutates start as the project's, shrunk to a few short runs.
SWEEP_SCENE = "ship_stabilization.toml"
TUNE_SCENE = "ship_stabilization.toml"

# Values put in place of the file's: the float limits, integers at and beyond 64 bits, every TOML type.
HOSTILE_FLOATS = [1e308, -1e308, 1.7976931348623157e308, 5e-324, -5e-324, 1e-300, 1e300, 2.0 ** 63, -0.0, 0.0,
                  math.inf, -math.inf, math.nan]
HOSTILE_INTEGERS = [0, -1, 1, 2, 2 ** 31, 2 ** 53 + 1, 10 ** 9, 10 ** 12, 2 ** 63 - 1, -2 ** 63, 2 ** 63, 10 ** 20]
HOSTILE_STRINGS = ["", " ", "x", "1e308", "nan", "fixed", "pid", "$\\foo$", "a\nb", "\u0000", "é" * 50,
                   "../../../../etc/passwd", "/dev/zero", "x" * 200_000]


class CaseTimeout(BaseException):
    """Raised by the alarm into a case past CASE_TIME_LIMIT_S."""


# ---------------------------------------------------------------- mutation

def hostile_value(rng: random.Random, original):
    kind = rng.choice(["float", "float", "integer", "integer", "string", "bool", "array", "table", "scaled",
                       "deep"])
    if kind == "float":
        return rng.choice(HOSTILE_FLOATS)
    if kind == "integer":
        return rng.choice(HOSTILE_INTEGERS)
    if kind == "string":
        return rng.choice(HOSTILE_STRINGS)
    if kind == "bool":
        return rng.choice([True, False])
    if kind == "array":
        return rng.choice([[], [1e308, -1e308, 5e-324], [0] * 100_000, [1, "a", True, {}], [[[]]],
                           [original, original], [original] * 3])
    if kind == "table":
        return rng.choice([{}, {"type": "fixed"}, {"bounds": [0, 1e308]}, {"linspace": [0.0, 1.0, 10 ** 9]},
                           {"uniform": [-1e308, 1e308]}, {"integers": [0, 2 ** 63 - 1]}, {"x": original}])
    if kind == "scaled" and isinstance(original, (int, float)) and not isinstance(original, bool):
        return original * rng.choice([1e300, -1e300, 1e-300, 1e6, -1.0, 0.0])
    depth = rng.choice([8, 31, 33, 60])
    value = original
    for _ in range(depth):
        value = [value]
    return value


def node_paths(document) -> list:
    """The path (keys and indexes) of every value in the document, tables and arrays included."""
    paths, pending = [], [((), document)]
    while pending:
        path, value = pending.pop()
        if path:
            paths.append(path)
        if isinstance(value, dict):
            pending.extend((path + (key,), item) for key, item in value.items())
        elif isinstance(value, list) and len(value) < 50:
            pending.extend((path + (index,), item) for index, item in enumerate(value))
    return sorted(paths, key=repr)


def at(document, path):
    for key in path:
        document = document[key]
    return document


def mutate(rng: random.Random, document: dict) -> tuple[dict, list[str]]:
    """The document with one to three mutations (replace, delete, add a key), and raw TOML lines to append."""
    extra_lines = []
    for _ in range(rng.choice([1, 1, 2, 3])):
        paths = node_paths(document)
        action = rng.choice(["replace"] * 7 + ["delete", "add", "raw"])
        if action == "raw":
            extra_lines.append(rng.choice([
                "deep = " + "[" * 5000 + "]" * 5000,
                "a" + ".a" * 3000 + " = 1",
                "parameters" + ".x" * 40 + " = 1",
                "big = 1" + "0" * 5000,
                "huge = 1e400",
                "negative_huge = -1e400",
                f"text = \"{'y' * 300_000}\"",
            ]))
            continue
        if not paths:
            continue
        path = rng.choice(paths)
        parent = at(document, path[:-1])
        if action == "replace":
            parent[path[-1]] = hostile_value(rng, parent[path[-1]])
        elif action == "delete" and isinstance(parent, dict):
            del parent[path[-1]]
        elif isinstance(parent, dict):
            parent[rng.choice(["unknown", "type", "file", "components", "delay_steps", "stop_time"])] = \
                hostile_value(rng, 1.0)
    return document, extra_lines


def toml_text(document: dict, extra_lines=()) -> str:
    """TOML of the document: every top-level key a line, tables inline (any nesting fits one line)."""
    lines = [f"{key_text(key)} = {value_text(value)}" for key, value in document.items()]
    return "\n".join([*lines, *extra_lines]) + "\n"


def key_text(key) -> str:
    return string_text(str(key))


def string_text(text: str) -> str:
    escaped = json.dumps(text, ensure_ascii=False)
    return escaped.replace("\x7f", "\\u007f")


def value_text(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return string_text(value)
    if isinstance(value, list):
        return "[" + ", ".join(value_text(item) for item in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{key_text(k)} = {value_text(v)}" for k, v in value.items()) + "}"
    raise TypeError(type(value))


# ---------------------------------------------------------------- the cases

def shrunk_sweep() -> dict:
    sweep = tomllib.loads((ROOT / "sweeps" / "gains_1000.toml").read_text())
    sweep.update(stop_time=0.005, metrics_from_s=0.0, cases=3, samples=2)
    return sweep


def shrunk_tuning() -> dict:
    tuning = tomllib.loads((ROOT / "tunings" / "ship_pid.toml").read_text())
    tuning.update(stop_time=0.005, metrics_from_s=0.0)
    tuning["optimizer"].update(trials=2, batch=2)
    for section in ("robustness", "holdout"):
        tuning[section].update(seeds=tuning[section]["seeds"][:1], sea_states=tuning[section]["sea_states"][:1],
                               draws=1)
    return tuning


def short_enough(document: dict, keys: dict) -> None:
    """Cuts what the file may legitimately ask for and a case cannot afford (a million cases of a sweep,
    a stop time of a day): each key of `keys` (a path) that holds a number above its value gets it."""
    for path, most in keys.items():
        try:
            parent = at(document, path[:-1])
            value = parent[path[-1]]
        except (KeyError, IndexError, TypeError):
            continue
        if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) \
                and most < value <= 10 ** 15:
            parent[path[-1]] = type(value)(most)
        elif isinstance(value, list) and most < len(value) and path[-1] in ("seeds", "sea_states"):
            parent[path[-1]] = value[:int(most)]


SWEEP_SIZES = {("stop_time",): 0.005, ("cases",): 3}
TUNE_SIZES = {("stop_time",): 0.005, ("optimizer", "trials"): 2, ("optimizer", "batch"): 2,
              ("robustness", "draws"): 1, ("holdout", "draws"): 1, ("robustness", "seeds"): 1,
              ("holdout", "seeds"): 1, ("robustness", "sea_states"): 1, ("holdout", "sea_states"): 1}


def make_cases(seed: int) -> list[dict]:
    rng = random.Random(seed)
    scenes = sorted(path.name for path in (ROOT / "scenes").glob("*.toml"))
    cases = []
    for index in range(CASES_PER_KIND["run"]):
        scene = scenes[index % len(scenes)]
        document, extra = mutate(rng, tomllib.loads((ROOT / "scenes" / scene).read_text()))
        # each source scene's cases under one name of their own (a stem no derived file name can end in)
        cases.append({"kind": "run", "source": scene, "file": f"scene{index % len(scenes)}.toml",
                      "text": toml_text(document, extra)})
    for kind, make, sizes in (("sweep", shrunk_sweep, SWEEP_SIZES), ("tune", shrunk_tuning, TUNE_SIZES)):
        for _ in range(CASES_PER_KIND[kind]):
            document, extra = mutate(rng, make())
            if kind == "sweep" and "cases" not in document:   # the full 1000-case grid: refused or too long
                document["cases"] = 3
            short_enough(document, sizes)
            cases.append({"kind": kind, "source": kind, "file": f"fuzz{kind}.toml", "text": toml_text(document, extra)})
    for number, case in enumerate(cases):
        case["number"] = number
        case["render"] = number % RENDER_EVERY == 0
    return cases


# ---------------------------------------------------------------- the driver (in its own process)

def record_snapshot(out: pathlib.Path) -> dict:
    """{relative path: sha256} of every file of the records in `out` (not the lock files)."""
    if not out.exists():
        return {}
    return {str(path.relative_to(out)): hashlib.sha256(path.read_bytes()).hexdigest()
            for path in sorted(out.rglob("*")) if path.is_file() and not path.name.endswith(".lock")}


def lost_files(before: dict, after: dict) -> list[str]:
    return sorted(name for name, digest in before.items() if after.get(name) != digest)


def run_case(main, argv: list[str]) -> dict:
    err = io.StringIO()
    started = time.monotonic()
    escaped = None
    signal.setitimer(signal.ITIMER_REAL, CASE_TIME_LIMIT_S)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            status = main(argv)
    except SystemExit as exc:   # argparse
        status = exc.code
    except BaseException:
        status, escaped = None, traceback.format_exc()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    return {"status": status, "escaped": escaped, "stderr": err.getvalue()[-3000:],
            "seconds": time.monotonic() - started}


def drive(cases_path: str, results_path: str) -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT_BYTES, resource.getrlimit(resource.RLIMIT_AS)[1]))

    def alarm(signum, frame):
        raise CaseTimeout(f"still running after {CASE_TIME_LIMIT_S:g} s")

    signal.signal(signal.SIGALRM, alarm)
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    from gimbal2axis.cli.main import main

    render = {"now": False}
    real_savefig = Figure.savefig

    def savefig(figure, path, *args, **kwargs):
        if render["now"]:
            return real_savefig(figure, path, *args, **kwargs)
        pathlib.Path(path).write_bytes(b"")

    Figure.savefig = savefig
    cases = json.loads(pathlib.Path(cases_path).read_text())
    work = pathlib.Path(cases_path).parent
    shutil.copytree(ROOT / "scenes" / "tracks", work / "tracks")
    results, baselines = [], {}
    for case in cases:
        render["now"] = case["render"]
        path = work / case["file"]
        out = work / "out" / (pathlib.Path(case["file"]).stem if case["kind"] == "run" else case["kind"])
        if case["kind"] == "run" and case["file"] not in baselines:   # the earlier, complete record
            shutil.copy(ROOT / "scenes" / case["source"], path)
            first = run_case(main, ["run", str(path), "--stop-time", RUN_STOP_TIME, "--out", str(out), "--quiet"])
            assert first["status"] == 0, first
            baselines[case["file"]] = record_snapshot(out)
        path.write_text(case["text"])
        if case["kind"] == "run":
            argv = ["run", str(path), "--stop-time", RUN_STOP_TIME, "--out", str(out), "--quiet"]
        else:
            argv = [case["kind"], str(ROOT / "scenes" / (SWEEP_SCENE if case["kind"] == "sweep" else TUNE_SCENE)),
                    str(path), "--serial", "--out", str(out), "--quiet"]
            if case["kind"] == "tune" and not case["render"]:
                argv.append("--no-report")
        result = run_case(main, argv)
        result.update(number=case["number"], argv=argv)
        if case["kind"] == "run":
            after = record_snapshot(out)
            if result["status"] == 2:
                result["lost"] = lost_files(baselines[case["file"]], after)
            else:   # a run that ran replaces the record: the next refusal must keep this one
                baselines[case["file"]] = after
        results.append(result)
        pathlib.Path(results_path).write_text(json.dumps(results))


# ---------------------------------------------------------------- the tests

@pytest.fixture(scope="module")
def fuzzed(tmp_path_factory):
    work = tmp_path_factory.mktemp("toml_fuzz")
    cases = make_cases(SEED)
    (work / "cases.json").write_text(json.dumps(cases))
    results_path = work / "results.json"
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    done = subprocess.run([sys.executable, __file__, str(work / "cases.json"), str(results_path)], cwd=work,
                          capture_output=True, text=True, timeout=DRIVER_TIME_LIMIT_S, env=env)
    results = json.loads(results_path.read_text()) if results_path.exists() else []
    assert done.returncode == 0 and len(results) == len(cases), \
        f"seed {SEED}: the driver ended with {done.returncode} after {len(results)} of {len(cases)} cases; " \
        f"case {len(results)}:\n{excerpt_case(cases[len(results)]) if len(results) < len(cases) else ''}\n" \
        f"{done.stderr[-4000:]}"
    return cases, results


def excerpt_case(case: dict) -> str:
    text = case["text"]
    return text if len(text) < 3000 else text[:3000] + f"\n... ({len(text)} characters)"


def failure_report(cases, result, why: str) -> str:
    case = cases[result["number"]]
    return (f"seed {SEED}, case {result['number']} ({case['kind']} of {case['source']}): {why}\n"
            f"argv: {result['argv']}\n--- the file ---\n{excerpt_case(case)}\n--- stderr ---\n{result['stderr']}\n"
            f"{result['escaped'] or ''}")


def problems(cases, results) -> list[tuple[dict, str]]:
    """(result, why) of every case that ended badly."""
    found = []
    for result in results:
        if result["escaped"] is not None:
            found.append((result, "an exception escaped the command: " + result["escaped"].strip().splitlines()[-1]))
        elif "Traceback" in result["stderr"]:
            found.append((result, "a traceback on stderr"))
        elif result["status"] not in EXPECTED_STATUSES:
            found.append((result, f"exit status {result['status']}"))
        elif result["seconds"] > CASE_TIME_LIMIT_S:
            found.append((result, f"took {result['seconds']:.0f} s"))
    return found


def fail_with(cases, found) -> None:
    summary = "\n".join(f"  case {result['number']} ({cases[result['number']]['source']}): {why[:300]}"
                        for result, why in found)
    details = "\n\n".join(failure_report(cases, result, why) for result, why in found[:3])
    pytest.fail(f"seed {SEED}: {len(found)} of {len(cases)} cases failed:\n{summary}\n\n{details}")


def test_every_case_ends_with_a_known_status_and_no_traceback(fuzzed):
    cases, results = fuzzed
    found = problems(cases, results)
    if found:
        fail_with(cases, found)
    statuses = {status: sum(r["status"] == status for r in results) for status in EXPECTED_STATUSES}
    assert statuses[2] < len(results), statuses   # some cases ran: the fuzz reaches past the loaders


def test_a_refused_run_keeps_the_earlier_record(fuzzed):
    cases, results = fuzzed
    found = [(result, f"refused, and the earlier record lost {result['lost']}") for result in results
             if result.get("lost")]
    if found:
        fail_with(cases, found)


if __name__ == "__main__":
    drive(sys.argv[1], sys.argv[2])
