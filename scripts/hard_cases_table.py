#!/usr/bin/env python3
"""Runs tests/model_core/integrators/test_hard_cases.py and prints the table of docs/hard_cases.md from its measurements.

Each test appends its measurements (case, what is asserted, measured error, solver.steps,
solver.rhs_evaluations, wall time) to $HARD_CASES_JSON; this script sets that variable, runs pytest and
formats the lines, with the pytest outcome of each test file (pass / xfail) summarised underneath.

    .venv/bin/python scripts/hard_cases_table.py > /tmp/table.md
"""
import json
import os
import pathlib
import subprocess
import sys
import tempfile

REPO = pathlib.Path(__file__).resolve().parents[1]


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp) / "hard_cases.jsonl"
        env = dict(os.environ, HARD_CASES_JSON=str(path))
        run = subprocess.run([sys.executable, "-m", "pytest", str(REPO / "tests" / "model_core" / "integrators" / "test_hard_cases.py"), "-q",
                              "-p", "no:cacheprovider", "-rxXf"], cwd=REPO, env=env, capture_output=True, text=True)
        entries = [json.loads(line) for line in path.read_text().splitlines()] if path.exists() else []
    print("| case | asserted | measured | steps | RHS evaluations | wall [s] | note |")
    print("|---|---|---|---:|---:|---:|---|")
    for e in entries:
        steps = "" if e["steps"] is None else f"{e['steps']:,}"
        rhs = "" if e["rhs"] is None else f"{e['rhs']:,}"
        wall = "" if e["wall"] is None else f"{e['wall']:.2f}"
        print(f"| {e['case']} | {e['asserted']} | {e['error']} | {steps} | {rhs} | {wall} | {e['note']} |")
    summary = [line for line in run.stdout.splitlines() if line.startswith(("XFAIL", "XPASS", "FAILED"))]
    print()
    print("pytest: " + (run.stdout.strip().splitlines()[-1] if run.stdout.strip() else "no output"))
    for line in summary:
        print(f"- {line}")
    return run.returncode


if __name__ == "__main__":
    sys.exit(main())
