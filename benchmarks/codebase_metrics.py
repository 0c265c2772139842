#!/usr/bin/env python3
"""The codebase measurements of issue 35, for any revisions (default: 72cbcfa, the review's base, and HEAD).

Each revision is extracted with `git archive` into a temporary folder (the working tree is not read), and
measured three ways:

- the lines of FMI plumbing: the C files under fmu_src/ that implement the FMI functions or what they
  share (rule below), per file and in total, physical lines (as `wc -l`) and code lines (not blank, not
  only a comment);
- the `duplicates` pairs in fmu_src/ (`duplicates --repo fmu_src --most 200`), each marked code,
  declarations or build script;
- the functions lizard flags with `-C 15 -L 60` (cyclomatic complexity above 15 or longer than 60 lines)
  in the C and C++ of model_core/, fmu_src/, c_kernel/ and gimbal2axis/native/ (where the C kernel was
  before it had a folder of its own), whichever the revision has.

It prints the tables and writes benchmarks/results/codebase_metrics.json. It installs nothing: without
`duplicates` or lizard on PATH that part is recorded as missing and the rest still runs.

    python benchmarks/codebase_metrics.py [REV ...] [--lizard CMD] [--out FILE] [--no-write]

The instructions per right-hand side and per doStep are measured by benchmarks/callgrind_cost.sh (it
needs builds).
"""
from __future__ import annotations

import argparse
import csv
import datetime as _dt
import fnmatch
import io
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

DEFAULT_REVISIONS = ["72cbcfa", "HEAD"]

# The rule for FMI plumbing. Counted: the C sources and headers under fmu_src/ that implement the FMI
# functions or what they share: the files that export fmi2*/fmi3* functions, the instance they work on
# (its states and the table of states each function may be called in, logging, refusals, the settable
# and communication-point rules), the FMU-state record, and the glue from the FMI layer to a model.
# At 72cbcfa these are exactly the files the 3,731 lines add up to. First match wins.
PLUMBING = [
    ("fmu_src/fmi_layer/*", "layer", "the FMI instance layer, written once (HEAD)"),
    ("fmu_src/gimbal_fmu/*", "gimbal", "the gimbal's model file and tables (its FMI faces until 6054b9c)"),
    ("model_core/src/simulation/fmu_model_table.cpp", "gimbal", "the gimbal's model table over the core (issue 46)"),
    ("fmu_src/fmi2_*.c", "gimbal", "the gimbal's FMI 2.0 functions (72cbcfa)"),
    ("fmu_src/fmi3_*.c", "gimbal", "the gimbal's FMI 3.0 functions (72cbcfa)"),
    ("fmu_src/fmu_instance.h", "gimbal", "the gimbal's FMI 2.0 instance (72cbcfa)"),
    ("fmu_src/common/cosim_instance.*", "layer", "the small FMUs' shared instance (72cbcfa)"),
    ("fmu_src/common/communication_point.h", "layer", "the communication-point rule of every FMU"),
    ("fmu_src/fmi_layer/fmu_state.*", "layer", "the FMU-state record"),
    ("fmu_src/common/fmi3_value_references.h", "layer", "the small FMUs' FMI 3.0 value references"),
    ("fmu_src/*/fmi2_*.c", "small FMUs", "a small FMU's exported FMI 2.0 functions (its model file until 6054b9c)"),
    ("fmu_src/*/*_fmu_model.c", "small FMUs", "a small FMU's model file: its tables for the faces"),
    ("fmu_src/*/fmi3_*.c", "small FMUs", "a small FMU's exported FMI 3.0 functions"),
]
GROUPS = ["layer", "gimbal", "small FMUs"]  # what is shared, the gimbal's own, the small FMUs' own
# Not counted, by kind. A C file under fmu_src/ that matches nothing is listed as unclassified, so that a
# new file is seen and the rule extended.
NOT_PLUMBING = [
    ("runtime support", ["fmu_src/fmi_layer/host_fp_environment.h", "fmu_src/silent_stdio.c", "fmu_src/exception_globals.cpp",
                         "fmu_src/runtime_release.cpp"]),
    ("model description", ["fmu_src/*model_description*"]),
    ("model", ["fmu_src/controller/*", "fmu_src/ship_motion/*"]),
]
C_SUFFIXES = (".c", ".h", ".cc", ".cpp", ".hpp")
LIZARD_FOLDERS = ["model_core", "fmu_src", "c_kernel", "gimbal2axis/native"]
LIZARD_CCN, LIZARD_LENGTH = 15, 60
LIZARD_HELP = ("lizard is not on PATH. It is not a dependency of the project; to get it:\n"
               "    python3 -m venv /tmp/lizard-venv && /tmp/lizard-venv/bin/pip install lizard\n"
               "and rerun with --lizard /tmp/lizard-venv/bin/lizard")


def git(repo: Path, *args: str) -> str:
    return subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True, text=True).stdout.strip()


def extract(repo: Path, commit: str, folder: Path) -> None:
    data = subprocess.run(["git", "-C", str(repo), "archive", "--format=tar", commit], check=True,
                          capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(data)) as archive:
        if hasattr(tarfile, "data_filter"):  # Python 3.12+: say what 3.14 will do by default
            archive.extractall(folder, filter="data")
        else:
            archive.extractall(folder)


# --- lines -------------------------------------------------------------------------------------------

def code_lines(text: str) -> int:
    """Lines with code: not blank, and not only a comment (C and C++ comments; string and character
    literals are skipped so that a // or /* inside them is not taken for a comment)."""
    has_code = set()
    line = 0
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
            i += 1
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            line += text.count("\n", i, end)
            i = end
        elif text.startswith("//", i):
            end = text.find("\n", i)
            i = n if end < 0 else end
        elif c in "\"'":
            has_code.add(line)
            i += 1
            while i < n and text[i] != c and text[i] != "\n":
                i += 2 if text[i] == "\\" else 1
            i += 1
        else:
            if not c.isspace():
                has_code.add(line)
            i += 1
    return len(has_code)


def physical_lines(text: str) -> int:
    return text.count("\n")  # as wc -l


def classify(path: str) -> tuple[str, str, str]:
    # The runtime support first: since issue 46 it lies in fmu_src/fmi_layer/, whose other files are plumbing.
    if any(fnmatch.fnmatch(path, p) for p in dict(NOT_PLUMBING)["runtime support"]):
        return "runtime support", "", ""
    for pattern, group, why in PLUMBING:
        if fnmatch.fnmatch(path, pattern):
            return "plumbing", group, why
    for kind, patterns in NOT_PLUMBING:
        if any(fnmatch.fnmatch(path, p) for p in patterns):
            return kind, "", ""
    return "unclassified", "", ""


def plumbing_lines(tree: Path) -> dict:
    plumbing, others = [], []
    # The gimbal's model table sits in the core since issue 46, compiled into the FMU.
    for file in sorted((tree / "fmu_src").rglob("*")) + [tree / "model_core/src/simulation/fmu_model_table.cpp"]:
        if not file.is_file() or file.suffix not in C_SUFFIXES:
            continue
        path = file.relative_to(tree).as_posix()
        text = file.read_text(encoding="utf-8", errors="replace")
        kind, group, why = classify(path)
        row = {"path": path, "lines": physical_lines(text), "code_lines": code_lines(text)}
        if kind == "plumbing":
            plumbing.append({**row, "group": group, "what": why})
        else:
            others.append({**row, "kind": kind})
    return {
        "files": plumbing,
        "total_lines": sum(r["lines"] for r in plumbing),
        "total_code_lines": sum(r["code_lines"] for r in plumbing),
        "by_group": {g: {"lines": sum(r["lines"] for r in plumbing if r["group"] == g),
                         "code_lines": sum(r["code_lines"] for r in plumbing if r["group"] == g)} for g in GROUPS},
        "not_counted": others,
        "unclassified": [r["path"] for r in others if r["kind"] == "unclassified"],
    }


# --- duplicates ----------------------------------------------------------------------------------------

ROW = re.compile(r"^D(\d+) (\S+):(\d+)-(\d+) ~ (\S+):(\d+)-(\d+)(.*)$")
CODE_LINE = re.compile(r"^\s*(return|if|else|for|while|do|switch|case|goto|break|continue)\b|\)\s*\{\s*$")


def side_kind(folder: Path, path: str, first: int, last: int) -> str:
    """'build' for CMake, 'declarations' where no line of the run is a statement or opens a function
    body (type and table definitions, prototypes, field lists, static assertions), else 'code'."""
    name = Path(path).name
    if name == "CMakeLists.txt" or name.endswith(".cmake"):
        return "build"
    try:
        lines = (folder / path).read_text(encoding="utf-8", errors="replace").splitlines()[first - 1:last]
    except OSError:
        return "unknown"
    for line in lines:
        stripped = line.strip()
        if stripped.startswith(("/*", "*", "//")):
            continue
        if CODE_LINE.search(line):
            return "code"
    return "declarations"


def duplicate_pairs(tree: Path, command: str | None) -> dict:
    if command is None:
        return {"missing": "duplicates is not on PATH: no pairs measured"}
    folder = tree / "fmu_src"
    result = subprocess.run([command, "--repo", str(folder), "--most", "200", "--seconds", "120"],
                            capture_output=True, text=True)
    lines = result.stdout.splitlines()
    pairs, notes = [], []
    for line in lines[1:]:
        m = ROW.match(line)
        if not m:
            notes.append(line)
            continue
        _, a, a0, a1, b, b0, b1, rest = m.groups()
        kinds = {side_kind(folder, a, int(a0), int(a1)), side_kind(folder, b, int(b0), int(b1))}
        kind = "build" if kinds == {"build"} else "declarations" if kinds == {"declarations"} else "code"
        more = re.search(r"\(\+(\d+) more runs?\)", rest)
        pairs.append({
            "row": line,
            "a": f"fmu_src/{a}:{a0}-{a1}",
            "b": f"fmu_src/{b}:{b0}-{b1}",
            "shape": " shape" in rest,
            "boilerplate": "boilerplate" in rest,
            "more_runs": int(more.group(1)) if more else 0,
            "kind": kind,
        })
    return {
        "summary": lines[0] if lines else "",
        "pairs": pairs,
        "count": len(pairs),
        "count_by_kind": {k: sum(p["kind"] == k for p in pairs) for k in ("code", "declarations", "build")},
        "notes": notes,
    }


# --- lizard --------------------------------------------------------------------------------------------

WARNING = re.compile(r"^(.*?):(\d+): warning: (.*) has (\d+) NLOC, (\d+) CCN, (\d+) token, (\d+) PARAM, "
                     r"(\d+) length")


def find_lizard(option: str | None) -> list[str] | None:
    if option:
        return shlex.split(option)
    found = shutil.which("lizard")
    if found:
        return [found]
    try:
        import importlib.util
        if importlib.util.find_spec("lizard") is not None:
            return [sys.executable, "-m", "lizard"]
    except (ImportError, ValueError):
        pass
    return None


def lizard_offenders(tree: Path, command: list[str] | None) -> dict:
    if command is None:
        return {"missing": LIZARD_HELP}
    folders = [f for f in LIZARD_FOLDERS if (tree / f).is_dir()]
    base = [*command, "-l", "cpp"]
    # Every function (for the count), then lizard's own verdict with the limits.
    listing = subprocess.run([*base, "--csv", *folders], cwd=tree, capture_output=True, text=True)
    functions = sum(1 for row in csv.reader(io.StringIO(listing.stdout)) if len(row) >= 11)
    warned = subprocess.run([*base, "-C", str(LIZARD_CCN), "-L", str(LIZARD_LENGTH), "-w", *folders], cwd=tree,
                            capture_output=True, text=True)
    offenders = []
    for line in warned.stdout.splitlines():
        m = WARNING.match(line)
        if not m:
            continue
        path, start, name, nloc, ccn, _tokens, params, length = m.groups()
        offenders.append({"path": path, "line": int(start), "function": name, "ccn": int(ccn),
                          "length": int(length), "nloc": int(nloc), "params": int(params),
                          "over": [w for w, bad in (("ccn", int(ccn) > LIZARD_CCN),
                                                    ("length", int(length) > LIZARD_LENGTH)) if bad]})
    offenders.sort(key=lambda o: (-o["ccn"], -o["length"]))
    by_folder = {f: sum(o["path"].startswith(f + "/") for o in offenders) for f in folders}
    return {"folders": folders, "functions": functions, "count": len(offenders), "by_folder": by_folder,
            "over_ccn": sum("ccn" in o["over"] for o in offenders),
            "over_length": sum("length" in o["over"] for o in offenders), "offenders": offenders}


def lizard_version(command: list[str] | None) -> str | None:
    if command is None:
        return None
    out = subprocess.run([*command, "--version"], capture_output=True, text=True)
    return (out.stdout or out.stderr).strip() or None


# --- printing ------------------------------------------------------------------------------------------

def print_report(results: list[dict]) -> None:
    names = [r["revision"] for r in results]
    print("FMI plumbing (rule: benchmarks/codebase_metrics.py, PLUMBING)")
    for r in results:
        p = r["plumbing"]
        print(f"\n  {r['revision']} ({r['commit'][:9]}, {r['date'][:10]})")
        for f in p["files"]:
            print(f"    {f['lines']:6d} {f['code_lines']:6d}  {f['path']}  [{f['group']}]")
        for g, v in p["by_group"].items():
            print(f"    {v['lines']:6d} {v['code_lines']:6d}  ({g})")
        print(f"    {p['total_lines']:6d} {p['total_code_lines']:6d}  total (lines, code lines)")
        if p["unclassified"]:
            print(f"    unclassified C files (extend the rule): {', '.join(p['unclassified'])}")
    if len(results) >= 2:
        a, b = results[0]["plumbing"], results[-1]["plumbing"]
        print(f"\n  {names[0]} -> {names[-1]}: {a['total_lines']} -> {b['total_lines']} lines "
              f"({b['total_lines'] - a['total_lines']:+d}), {a['total_code_lines']} -> {b['total_code_lines']} "
              f"code lines ({b['total_code_lines'] - a['total_code_lines']:+d})")
    print("\nduplicates pairs in fmu_src/")
    for r in results:
        d = r["duplicates"]
        if "missing" in d:
            print(f"  {r['revision']}: {d['missing']}")
            continue
        k = d["count_by_kind"]
        print(f"  {r['revision']}: {d['count']} pairs ({k['code']} code, {k['declarations']} declarations, "
              f"{k['build']} build script)")
        for p in d["pairs"]:
            print(f"    [{p['kind']}] {p['row']}")
        for note in d["notes"]:
            print(f"    {note}")
    print(f"\nlizard -C {LIZARD_CCN} -L {LIZARD_LENGTH} (C and C++)")
    for r in results:
        z = r["lizard"]
        if "missing" in z:
            print(f"  {r['revision']}: missing. {z['missing']}")
            continue
        print(f"  {r['revision']}: {z['count']} of {z['functions']} functions over the limits "
              f"({z['over_ccn']} CCN > {LIZARD_CCN}, {z['over_length']} longer than {LIZARD_LENGTH} lines) in "
              f"{', '.join(z['folders'])}; by folder {z['by_folder']}")
        for o in z["offenders"]:
            print(f"    CCN {o['ccn']:3d} length {o['length']:4d}  {o['function']}  {o['path']}:{o['line']}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("revisions", nargs="*", default=DEFAULT_REVISIONS, help="default: 72cbcfa HEAD")
    parser.add_argument("--lizard", help="the lizard command (default: lizard on PATH, or python -m lizard)")
    parser.add_argument("--out", help="default: benchmarks/results/codebase_metrics.json of this clone")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    repo = Path(git(Path(__file__).resolve().parent, "rev-parse", "--show-toplevel"))
    duplicates = shutil.which("duplicates")
    if duplicates is None:
        print("duplicates is not on PATH: the pairs are not measured", file=sys.stderr)
    lizard = find_lizard(args.lizard)
    if lizard is None:
        print(LIZARD_HELP, file=sys.stderr)

    results = []
    with tempfile.TemporaryDirectory(prefix="codebase_metrics_") as scratch:
        for revision in args.revisions:
            try:
                commit = git(repo, "rev-parse", "--verify", revision + "^{commit}")
            except subprocess.CalledProcessError:
                print(f"{revision}: not a commit of this clone (a shallow clone lacks 72cbcfa: git fetch --unshallow)",
                      file=sys.stderr)
                return 1
            tree = Path(scratch) / commit
            extract(repo, commit, tree)
            results.append({
                "revision": revision,
                "commit": commit,
                "date": git(repo, "show", "-s", "--format=%cI", commit),
                "plumbing": plumbing_lines(tree),
                "duplicates": duplicate_pairs(tree, duplicates),
                "lizard": lizard_offenders(tree, lizard),
            })
    print_report(results)
    if args.no_write:
        return 0
    out = Path(args.out) if args.out else repo / "benchmarks" / "results" / "codebase_metrics.json"
    document = {
        "what": "issue 35: FMI plumbing lines, duplicates pairs in fmu_src/, lizard offenders "
                "(benchmarks/codebase_metrics.py)",
        "measured": _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat(),
        "plumbing_rule": {"counted": [{"pattern": p, "group": g, "what": w} for p, g, w in PLUMBING],
                          "not_counted": [{"kind": k, "patterns": ps} for k, ps in NOT_PLUMBING],
                          "suffixes": list(C_SUFFIXES),
                          "lines": "physical lines, as wc -l",
                          "code_lines": "lines that are not blank and not only a comment"},
        "duplicates_command": f"duplicates --repo fmu_src --most 200 --seconds 120 ({duplicates or 'missing'})",
        "duplicates_kinds": "a pair is 'declarations' when no line of either named run is a statement "
                            "(return, if, for, ...) or opens a function body; 'build' when both are CMake; "
                            "else 'code'. Only the named run of each pair is judged.",
        "lizard_command": f"lizard -l cpp -C {LIZARD_CCN} -L {LIZARD_LENGTH} -w FOLDERS",
        "lizard_version": lizard_version(lizard),
        "revisions": results,
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")
    print(f"\nwrote {os.path.relpath(out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
