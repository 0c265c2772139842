"""The serialized FMU states of two builds' FMUs, compared byte for byte: the check that a refactoring
of the FMI layer kept every FMU-state record of the current format (issue 35, docs/benchmarks.md).

    python benchmarks/fmu_state_blobs.py BUILD_A BUILD_B    # e.g. a build of an older revision, build/

Each build directory holds the packaged FMUs (Gimbal2Axis.fmu, Gimbal2Axis-fmi3.fmu and the small FMUs'
FMI 3.0 ones). In each, the same scenarios run with fmpy: the gimbal's FMI 2.0 and FMI 3.0,
Co-Simulation (FMI 3.0 also with Event Mode and early return, and early return alone) and Model
Exchange, an FMU state serialized when initialized, after 300 steps (or 50 evaluations) with voltage
steps, and when terminated; the small FMUs' FMI 3.0 after 100 steps. Prints one line per state and
writes benchmarks/results/fmu_state_blobs.json (the SHA-256 of every state in both builds). Exit
status 1 when a state differs. Takes a few seconds.
"""
import ctypes
import hashlib
import json
import sys
from pathlib import Path

import fmpy
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Model, FMU3Slave

STATES = 19  # the gimbal's continuous states (Model Exchange)


def record(out, name, blob):
    out[name] = hashlib.sha256(bytes(blob)).hexdigest()


def vr_of(md, name):
    return next(v.valueReference for v in md.modelVariables if v.name == name)


def opened(path, cls, identifier):
    """The model description and an instance of `cls` of the FMU at `path`, named "blob"."""
    md = fmpy.read_model_description(path)
    return md, cls(guid=md.guid, unzipDirectory=fmpy.extract(path), modelIdentifier=identifier, instanceName="blob")


def voltages(k):
    """The voltages of step k: u_R1 switching every 40 steps, u_R2 held."""
    return [3.0 if (k // 40) % 2 else -2.0, 1.5]


def euler_steps(f, get_derivatives):
    """50 explicit Euler steps of 0.1 ms from t = 0.25 s, as a host's continuous-time solver would take."""
    x, dx = (ctypes.c_double * STATES)(), (ctypes.c_double * STATES)()
    f.getContinuousStates(x, STATES)
    for k in range(50):
        f.setTime(0.25 + k * 1e-4)
        get_derivatives(dx, STATES)
        for i in range(STATES):
            x[i] += 1e-4 * dx[i]
        f.setContinuousStates(x, STATES)


def gimbal2(build, out, kind):
    md, f = opened(f"{build}/Gimbal2Axis.fmu", FMU2Slave if kind == "cs" else FMU2Model, "Gimbal2Axis")
    inputs = [vr_of(md, "u_R1"), vr_of(md, "u_R2")]
    f.instantiate()
    f.setupExperiment(startTime=0.25)
    f.enterInitializationMode()
    f.exitInitializationMode()
    record(out, f"fmi2-{kind}-initialized", f.serializeFMUstate(f.getFMUstate()))
    if kind == "cs":
        for k in range(300):
            f.setReal(inputs, voltages(k))
            f.doStep(0.25 + k * 1e-3, 1e-3)
    else:
        f.newDiscreteStates()
        f.enterContinuousTimeMode()
        euler_steps(f, f.getDerivatives)
    record(out, f"fmi2-{kind}-running", f.serializeFMUstate(f.getFMUstate()))
    f.terminate()
    record(out, f"fmi2-{kind}-terminated", f.serializeFMUstate(f.getFMUstate()))
    f.freeInstance()


def gimbal3(build, out, kind, event_mode=False, early=False):
    md, f = opened(f"{build}/Gimbal2Axis-fmi3.fmu", FMU3Slave if kind == "cs" else FMU3Model, "Gimbal2Axis")
    inputs = [vr_of(md, "u_R1"), vr_of(md, "u_R2")]
    if kind == "cs":
        f.instantiate(eventModeUsed=event_mode, earlyReturnAllowed=early)
    else:
        f.instantiate()
    f.enterInitializationMode(startTime=0.25)
    f.exitInitializationMode()
    tag = f"fmi3-{kind}-{int(event_mode)}{int(early)}"
    record(out, tag + "-initialized", f.serializeFMUState(f.getFMUState()))
    if kind == "cs":
        if event_mode:
            f.updateDiscreteStates()
            f.enterStepMode()
        t = 0.25
        for k in range(300):
            f.setFloat64(inputs, voltages(k))
            event, _, _, reached = f.doStep(t, 1e-3)
            t = reached if early else 0.25 + (k + 1) * 1e-3  # an early return ends the step at `reached`
            if early and event_mode and event:
                f.enterEventMode()
                f.updateDiscreteStates()
                f.enterStepMode()
    else:
        f.updateDiscreteStates()
        f.enterContinuousTimeMode()
        euler_steps(f, f.getContinuousStateDerivatives)
    record(out, tag + "-running", f.serializeFMUState(f.getFMUState()))
    f.terminate()
    record(out, tag + "-terminated", f.serializeFMUState(f.getFMUState()))
    f.freeInstance()


def small3(build, out, file, identifier):
    _, f = opened(f"{build}/{file}", FMU3Slave, identifier)
    f.instantiate()
    f.enterInitializationMode(startTime=0.0)
    f.exitInitializationMode()
    for k in range(100):
        f.doStep(k * 1e-3, 1e-3)
    record(out, file + "-running", f.serializeFMUState(f.getFMUState()))
    f.freeInstance()


def states_of(build: str) -> dict:
    out = {}
    gimbal2(build, out, "cs")
    gimbal2(build, out, "me")
    gimbal3(build, out, "cs")
    gimbal3(build, out, "cs", True, True)
    gimbal3(build, out, "cs", False, True)
    gimbal3(build, out, "me")
    small3(build, out, "Gimbal2Axis-ShipMotion-fmi3.fmu", "Gimbal2Axis_ShipMotion")
    small3(build, out, "Gimbal2Axis-Controller-fmi3.fmu", "Gimbal2AxisController")
    return out


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    first, second = (states_of(build) for build in sys.argv[1:])
    differing = [name for name in first if first[name] != second.get(name)]
    for name in first:
        print(f"{name:45s} {'DIFFERENT' if name in differing else 'same bytes'}")
    print(f"{len(first) - len(differing)} of {len(first)} FMU states identical")
    results = Path(__file__).resolve().parent / "results" / "fmu_state_blobs.json"
    results.write_text(json.dumps({"builds": sys.argv[1:], "sha256": [first, second], "differing": differing},
                                  indent=1) + "\n")
    return 1 if differing else 0


if __name__ == "__main__":
    sys.exit(main())
