"""Digests of the results the product computes, to show that a restructuring changed no bit.

`python tests/package/golden/digests.py record` (from main, before a move) writes tests/package/golden/digests.json;
tests/package/test_golden_results.py computes the same digests from the tree under test and compares them.
A digest is the SHA-256 of a float64 array's bytes (NaN included), so equal digests are equal bits.
What is digested: every scene file (the whole run, or its first minute when longer; every recorded
signal, through the loop the scene runner takes), the user-controller example (the Python loop), a
small serial sweep's table (its numeric columns, not the timings), and two linearizations (A, B, C,
D)."""
import hashlib
import json
import pathlib
import sys

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[3]
DIGEST_FILE = pathlib.Path(__file__).resolve().parent / "digests.json"

SWEEP = """
name = "golden"
seed = 11
samples = 2
stop_time = 0.08
metrics_from_s = 0.02
[grid]
"gear1.model" = [2, 1]
"controller.azimuth.kp" = [200.0, 800.0]
[random]
"base_motion.seed" = { integers = [0, 9999] }
"body2.m" = { uniform = [1.5, 3.0] }
"""
# Columns of the sweep table that record the run, not its result (instance_use counts the cases an
# instance ran before, which depends on what else ran in the process).
SWEEP_UNTIMED = ("wall", "cpu_time", "fmu_sha", "host", "worker", "elapsed", "duration", "instance_use")


def digest(values) -> str:
    return hashlib.sha256(np.ascontiguousarray(np.asarray(values, dtype=np.float64)).tobytes()).hexdigest()


LONGEST_HELD_S = 60.0   # s of a scene's run the digests hold


def scene_digests(fmu_path) -> dict:
    from gimbal2axis import FMU, load_scene, run

    scenes = sorted((REPO / "scenes").glob("*.toml")) + [REPO / "examples" / "user_controller.toml"]
    out = {}
    with FMU(fmu_path) as fmu:
        for path in scenes:
            scene = load_scene(path)
            # A long scene is held over its first minute: the same code as the rest of its run, without
            # 20 minutes of simulation (and their record in memory) in every test run.
            result = run(scene, fmu, stop_time=min(scene.stop_time, LONGEST_HELD_S))
            out[path.stem] = {"loop": result.loop,
                              **{name: digest(values) for name, values in sorted(result.signals.items())}}
    return out


def sweep_digests(fmu_path, workdir: pathlib.Path) -> dict:
    import pyarrow.parquet as pq
    from gimbal2axis.sweep import SweepOptions, run_sweep

    sweep = workdir / "golden.toml"
    sweep.write_text(SWEEP)
    run_sweep(REPO / "scenes" / "ship_stabilization.toml", sweep, fmu_path, workdir,
              SweepOptions(serial=True, progress=False, plot=False))
    rows = sorted(pq.read_table(next(workdir.glob("golden__*.parquet"))).to_pylist(), key=lambda r: r["case_id"])
    out = {}
    for column in rows[0]:
        if any(word in column for word in SWEEP_UNTIMED):
            continue
        values = [row[column] for row in rows]
        if all(isinstance(v, (int, float, bool)) or v is None for v in values):
            out[column] = digest([np.nan if v is None else float(v) for v in values])
        else:
            out[column] = hashlib.sha256("\n".join(map(str, values)).encode()).hexdigest()
    return out


def linearization_digests(fmu_path) -> dict:
    from gimbal2axis.analysis.linearization import linearize

    out = {}
    # gear<j>.start = as_given (2): the rotors at 0 under displaced loads, the gears twisted, as recorded.
    model = linearize({"gear1.model": 0, "motor1.model": 0, "beta": 0.3, "u_R1": 2.0, "gear2.start": 2})
    out["fixed_base"] = {name: digest(getattr(model, name)) for name in "ABCD"}
    out["fixed_base"]["states"] = ",".join(model.states)
    full = linearize({"base.gamma": 0.1, "alpha": 0.2, "beta": -0.4, "gear1.start": 2, "gear2.start": 2})
    out["full_model"] = {name: digest(getattr(full, name)) for name in "ABCD"}
    return out


def compute(fmu_path, workdir) -> dict:
    return {"scenes": scene_digests(fmu_path), "sweep": sweep_digests(fmu_path, pathlib.Path(workdir)),
            "linearization": linearization_digests(fmu_path)}


if __name__ == "__main__":
    import tempfile

    if sys.argv[1:] != ["record"]:
        sys.exit("usage: python tests/package/golden/digests.py record")
    fmu = REPO / "build" / "Gimbal2Axis.fmu"
    with tempfile.TemporaryDirectory() as tmp:
        DIGEST_FILE.write_text(json.dumps(compute(fmu, tmp), indent=1, sort_keys=True) + "\n")
    print(f"wrote {DIGEST_FILE}")
