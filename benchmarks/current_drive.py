"""Current drive against voltage drive on the ship scene: CPU time and the error of the reductions, one run.

The ship scene's seaway (scenes/ship_stabilization.toml: its base motion and start state, full fidelity,
solver.rtol 1e-6) drives the FMU (build/Gimbal2Axis.fmu, FMI 2.0 Co-Simulation through fmpy's FMU2Slave) at
1 kHz under a simple PID written here (the scene runner cannot command current yet): per axis, PI on the
encoder angle's error from its start value and damping on the payload gyro (los.omega[3] azimuth,
los.omega[1] elevation), with a one-sample delay. Variants:
- voltage: u_R<j> [V], gains in V/rad, V/(rad s), V s/rad;
- current, inductive motor + PI amplifier at f_c = 2 kHz (pole-zero gains, back-emf feed-forward):
  i_R<j>_cmd [A], the voltage gains divided by R (adding the back-emf damping N k_emf / R that voltage
  drive has to the gyro gain was tried: through the gyro, delayed a sample and not collocated with the
  rotor, it excites the gear mode, LOS rate RMS 0.31 rad/s instead of 0.02);
- current, quasi-static reduction (motor<j>.model = quasi_static): the same controller;
- current PI with RODAS4 only (solver.method 6), and voltage with RODAS4 only, for the method's share;
- current PI at solver.rtol 1e-10: the reference for the default tolerance's error.
CPU time: time.process_time of the do-step calls alone (the Python loop excluded), median of `--repeat`
runs; work: the FMU's solver.steps and solver.rhs_evaluations. Errors: largest differences of alpha, beta
(rad), los.omega (rad/s) and i_R1, i_R2 (A) at the 1 ms points.

    .venv/bin/python benchmarks/current_drive.py [--build build] [--seconds 5] [--repeat 3]
Prints a table and writes benchmarks/results/current_drive.json.
"""
from __future__ import annotations

import argparse
import datetime
import json
import pathlib
import platform
import statistics
import time

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[1]
STEP = 1e-3
RECORDED = ["alpha", "beta", "los.omega[1]", "los.omega[3]", "i_R1", "i_R2", "amplifier1.u", "amplifier2.u"]
COUNTERS = ["solver.steps", "solver.rhs_evaluations", "solver.jacobian_evaluations", "events.total",
            "solver.method_switches"]
R = (2.0, 2.5)                 # motor1.R, motor2.R (start values)
BACK_EMF_DAMPING = (0.0, 0.0)  # added to the gyro gain in current drive, V s/rad (see above)
VOLTAGE_GAINS = {"kp": 40.0, "ki": 400.0, "k_gyro": 8.0}

VARIANTS = {
    "voltage": {},
    "current, PI amplifier (f_c = 2 kHz)": {"motor1.drive": 1, "motor2.drive": 1},
    "current, quasi-static": {"motor1.drive": 1, "motor2.drive": 1, "motor1.model": 0, "motor2.model": 0},
    "current, PI amplifier, RODAS4 only": {"motor1.drive": 1, "motor2.drive": 1, "solver.method": 6},
    "voltage, RODAS4 only": {"solver.method": 6},
    "current, PI amplifier, rtol 1e-10 (reference)": {"motor1.drive": 1, "motor2.drive": 1, "solver.rtol": 1e-10,
                                                     "solver.atol": 1e-12},
}


def gains(current: bool) -> list[dict]:
    out = []
    for axis in range(2):
        if not current:
            out.append(dict(VOLTAGE_GAINS))
        else:
            out.append({"kp": VOLTAGE_GAINS["kp"] / R[axis], "ki": VOLTAGE_GAINS["ki"] / R[axis],
                        "k_gyro": (VOLTAGE_GAINS["k_gyro"] + BACK_EMF_DAMPING[axis]) / R[axis]})
    return out


def run(fmu_path: pathlib.Path, scene, seconds: float, settings: dict) -> dict:
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    from gimbal2axis.scene.base_motion import INPUTS

    md = read_model_description(str(fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    kind = {v.name: v.type for v in md.modelVariables}
    unzipped = extract(str(fmu_path))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="bench")
    slave.instantiate()
    start = {"alpha": np.radians(30.0), "beta": np.radians(5.0), "solver.rtol": 1e-6, "solver.atol": 1e-8}
    start.update(settings)
    for name, value in start.items():
        if kind[name] in ("Integer", "Enumeration"):
            slave.setInteger([vr[name]], [int(value)])
        elif kind[name] == "Boolean":
            slave.setBoolean([vr[name]], [bool(value)])
        else:
            slave.setReal([vr[name]], [float(value)])
    steps = int(round(seconds / STEP))
    times = np.arange(steps + 1) * STEP
    base = scene.base_motion().sample(times)
    base_vr = [vr[name] for name in INPUTS]
    current = settings.get("motor1.drive", 0) == 1
    inputs = [vr["i_R1_cmd"], vr["i_R2_cmd"]] if current else [vr["u_R1"], vr["u_R2"]]
    limit = (4.0, 3.0) if current else (24.0, 24.0)
    k = gains(current)
    slave.setReal(base_vr, list(base[0]))
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    recorded_vr = [vr[name] for name in RECORDED]
    angle_vr, gyro_vr = [vr["alpha"], vr["beta"]], [vr["los.omega[3]"], vr["los.omega[1]"]]
    set_point = [start["alpha"], start["beta"]]
    integral = [0.0, 0.0]
    pending = [0.0, 0.0]          # computed at t_k, applied from t_k+1 (one-sample delay)
    record = np.empty((steps, len(RECORDED)))
    cpu = 0.0
    for n in range(steps):
        slave.setReal(base_vr, list(base[n]))
        slave.setReal(inputs, pending)
        angles, gyro = slave.getReal(angle_vr), slave.getReal(gyro_vr)
        command = []
        for axis in range(2):
            error = set_point[axis] - angles[axis]
            integral[axis] += error * STEP
            out = k[axis]["kp"] * error + k[axis]["ki"] * integral[axis] - k[axis]["k_gyro"] * gyro[axis]
            command.append(float(np.clip(out, -limit[axis], limit[axis])))
        pending = command
        t0 = time.process_time()
        slave.doStep(currentCommunicationPoint=n * STEP, communicationStepSize=STEP)  # raises on an error
        cpu += time.process_time() - t0
        record[n] = slave.getReal(recorded_vr)
    counters = dict(zip(COUNTERS, slave.getInteger([vr[name] for name in COUNTERS])))
    slave.terminate()
    slave.freeInstance()
    return {"cpu": cpu, "record": record, "counters": counters}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=str(REPO / "build"))
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results"))
    args = parser.parse_args()

    from gimbal2axis import load_scene

    scene = load_scene(REPO / "scenes" / "ship_stabilization.toml")
    fmu = pathlib.Path(args.build) / "Gimbal2Axis.fmu"
    results = {}
    for name, settings in VARIANTS.items():
        repeats = 1 if "reference" in name else args.repeat
        runs = [run(fmu, scene, args.seconds, settings) for _ in range(repeats)]
        cpus = [r["cpu"] for r in runs]
        results[name] = {"cpu_s": statistics.median(cpus), "cpu_runs_s": cpus, "record": runs[0]["record"],
                         "counters": runs[0]["counters"]}
        print(f"{name}: {statistics.median(cpus):.3f} s CPU, {runs[0]['counters']}", flush=True)

    summary = summarize(results, args)
    print_summary(summary)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "current_drive.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(f"\nwritten: {out / 'current_drive.json'}")
    return 0


def summarize(results: dict, args) -> dict:
    """What current_drive.json holds: each variant's CPU time, its ratio to voltage drive, its counters,
    and the largest differences between the variants' records."""
    def errors(a: str, b: str) -> dict:
        x, y = results[a]["record"], results[b]["record"]
        d = np.abs(x - y).max(axis=0)
        return {"alpha_rad": float(d[0]), "beta_rad": float(d[1]), "los_omega_rad_s": float(max(d[2], d[3])),
                "i_R1_A": float(d[4]), "i_R2_A": float(d[5])}

    voltage = results["voltage"]["cpu_s"]
    names = list(VARIANTS)
    return {
        "scene": "scenes/ship_stabilization.toml (base motion, full fidelity), own PID at 1 kHz",
        "date": datetime.date.today().isoformat(),
        "simulated_s": args.seconds,
        "repeat": args.repeat,
        "machine": platform.processor() or platform.machine(),
        "variants": {name: {"cpu_s": r["cpu_s"], "cpu_runs_s": r["cpu_runs_s"],
                            "cpu_ratio_to_voltage": r["cpu_s"] / voltage,
                            "counters": {k: int(v) for k, v in r["counters"].items()},
                            "los_rate_rms_rad_s": float(np.sqrt(np.mean(r["record"][:, 2] ** 2 + r["record"][:, 3] ** 2))),
                            "largest_amplifier_u_V": float(np.abs(r["record"][:, 6:8]).max())}
                     for name, r in results.items()},
        "errors": {
            "quasi-static against PI (f_c = 2 kHz), both rtol 1e-6": errors(names[2], names[1]),
            "PI at rtol 1e-6 against PI at rtol 1e-10": errors(names[1], names[5]),
            "PI, RODAS4 only, at rtol 1e-6 against PI at rtol 1e-10": errors(names[3], names[5]),
            "quasi-static at rtol 1e-6 against PI at rtol 1e-10": errors(names[2], names[5]),
        },
    }


def print_summary(summary: dict) -> None:
    print(f"\n{'variant':48s} {'CPU s':>8s} {'ratio':>6s} {'steps':>7s} {'rhs':>8s} {'jac':>6s} {'events':>6s}")
    for name, v in summary["variants"].items():
        c = v["counters"]
        print(f"{name:48s} {v['cpu_s']:8.3f} {v['cpu_ratio_to_voltage']:6.2f} {c['solver.steps']:7d} "
              f"{c['solver.rhs_evaluations']:8d} {c['solver.jacobian_evaluations']:6d} {c['events.total']:6d}")
    print()
    for name, e in summary["errors"].items():
        print(f"{name}: " + ", ".join(f"{k} {v:.3g}" for k, v in e.items()))


if __name__ == "__main__":
    raise SystemExit(main())
