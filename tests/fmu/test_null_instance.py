"""Every exported fmi2*/fmi3* function of every binary the build makes (the gimbal's, the ship-motion and
the controller FMUs', FMI 2.0 and 3.0) called with a NULL instance and NULL or zero arguments: an error
status (or NULL from an instantiation, nothing from fmiXFreeInstance), never a crash. One face per FMI
version serves all of them (fmu_src/fmi_layer/fmi2_functions.c, fmi3_functions.c); an entry that reads
the instance before checking it (as fmi3EnterEventMode and fmi3GetDirectionalDerivative of the
gimbal's former FMI 3.0 face did) takes the test's process down."""
import ctypes
import subprocess
import sys
import textwrap

import pytest

BINARIES = {
    "gimbal FMI 2.0": "fmu_src/Gimbal2Axis.so",
    "gimbal FMI 3.0": "fmi3/binary/Gimbal2Axis.so",
    "ship motion FMI 2.0": "fmu_src/ship_motion/Gimbal2Axis_ShipMotion.so",
    "ship motion FMI 3.0": "fmu_src/ship_motion/fmi3/Gimbal2Axis_ShipMotion.so",
    "controller FMI 2.0": "fmu_src/controller/Gimbal2AxisController.so",
    "controller FMI 3.0": "fmu_src/controller/fmi3/Gimbal2AxisController.so",
}
RETURNS_TEXT = {"fmi2GetTypesPlatform", "fmi2GetVersion", "fmi3GetVersion"}


def exported_functions(binary):
    symbols = subprocess.run(["nm", "-D", "--defined-only", str(binary)], capture_output=True, text=True,
                             check=True).stdout.split("\n")
    return sorted(line.split()[-1] for line in symbols
                  if len(line.split()) == 3 and line.split()[1] == "T" and line.split()[-1].startswith("fmi"))


# Each function is called in a child process: a crash is then a failed test naming the function, not a
# lost pytest worker.
CALLER = textwrap.dedent("""
    import ctypes, sys
    library = ctypes.CDLL(sys.argv[1])
    for name in sys.argv[2:]:
        function = getattr(library, name)
        function.restype = ctypes.c_void_p if "Instantiate" in name else ctypes.c_int
        result = function(*([None] * 12))
        if "FreeInstance" in name:
            continue
        ok = result is None if "Instantiate" in name else result == 3
        print(name, "ok" if ok else f"returned {result}", flush=True)
""")


@pytest.mark.parametrize("name", BINARIES)
def test_every_exported_function_refuses_a_null_instance(build_dir, name):
    binary = build_dir / BINARIES[name]
    functions = [f for f in exported_functions(binary) if f not in RETURNS_TEXT]
    assert len(functions) in (44 - 2, 75 - 1), functions  # FMI 2.0's 44 functions, FMI 3.0's 75, all of them
    done = subprocess.run([sys.executable, "-c", CALLER, str(binary), *functions], capture_output=True, text=True,
                          timeout=120)
    answered = [line.split()[0] for line in done.stdout.splitlines()]
    unanswered = [f for f in functions if f not in answered and "FreeInstance" not in f]
    assert done.returncode == 0, (f"{name}: crashed in {unanswered[0] if unanswered else 'fmiXFreeInstance'} "
                                  f"(return code {done.returncode}): {done.stderr[-2000:]}")
    wrong = [line for line in done.stdout.splitlines() if not line.endswith(" ok")]
    assert wrong == [] and unanswered == [], (wrong, unanswered)
