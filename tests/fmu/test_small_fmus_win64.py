"""The ship-motion and controller FMUs' Windows binaries (binaries/win64, and binaries/x86_64-windows of
their FMI 3.0 FMUs; cross-compiled with mingw-w64 by fmu_src/win64.cmake from the same sources as their
Linux binaries, over the same FMI instance layer as the gimbal's): in the FMU, well-behaved guests by
their import tables, and exporting exactly the functions of the Linux binary: the fmi2* ones, the
fmi3* ones for FMI 3.0."""
import os
import re
import shutil
import subprocess
import zipfile

import pytest

pytestmark = pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                                reason="the sanitizer build makes no win64 binary (GIMBAL_WIN64=AUTO leaves it out)")

OBJDUMP = "x86_64-w64-mingw32-objdump"
# (FMU, model identifier, Windows folder, Linux folder, the prefix of every exported function)
SMALL_FMUS = [("Gimbal2Axis-ShipMotion.fmu", "Gimbal2Axis_ShipMotion", "win64", "linux64", "fmi2"),
              ("Gimbal2Axis-Controller.fmu", "Gimbal2AxisController", "win64", "linux64", "fmi2"),
              ("Gimbal2Axis-ShipMotion-fmi3.fmu", "Gimbal2Axis_ShipMotion", "x86_64-windows", "x86_64-linux", "fmi3"),
              ("Gimbal2Axis-Controller-fmi3.fmu", "Gimbal2AxisController", "x86_64-windows", "x86_64-linux", "fmi3")]


def objdump(dll):
    if shutil.which(OBJDUMP) is None:
        pytest.fail(f"{OBJDUMP} is missing (Debian: binutils-mingw-w64-x86-64)")
    return subprocess.run([OBJDUMP, "-p", str(dll)], capture_output=True, text=True, check=True).stdout


@pytest.fixture(scope="module", params=SMALL_FMUS, ids=[fmu_name for fmu_name, *_ in SMALL_FMUS])
def binaries(request, build_dir, tmp_path_factory):
    """The FMU's Windows DLL and Linux shared object, extracted, and the prefix of their functions."""
    fmu_name, identifier, windows, linux, prefix = request.param
    fmu_path = build_dir / fmu_name
    assert fmu_path.is_file(), f"{fmu_path} is missing"
    out = tmp_path_factory.mktemp(identifier)
    with zipfile.ZipFile(fmu_path) as fmu:
        names = set(fmu.namelist())
        dll_name, so_name = f"binaries/{windows}/{identifier}.dll", f"binaries/{linux}/{identifier}.so"
        assert dll_name in names, (f"{fmu_name} has no {dll_name}: the win64 build needs the mingw-w64 tool chain "
                                   "(g++-mingw-w64-x86-64-win32; scripts/setup.sh installs it for the tests)")
        assert so_name in names
        fmu.extract(dll_name, out)
        fmu.extract(so_name, out)
    return out / dll_name, out / so_name, prefix


def test_dll_imports_only_windows_system_dlls(binaries):
    dll, _, _ = binaries
    imports = re.findall(r"DLL Name: (\S+)", objdump(dll))
    assert imports, "no import table found"
    system = re.compile(r"(?i)^(kernel32|msvcrt|ucrtbase|api-ms-win-[a-z0-9-]+)\.dll$")
    assert [name for name in imports if not system.match(name)] == [], imports


def test_dll_exports_exactly_the_functions_of_the_linux_binary(binaries):
    dll, so, prefix = binaries
    table = objdump(dll).split("[Ordinal/Name Pointer] Table", 1)
    assert len(table) == 2, "no export table found"
    exports = set()
    for line in table[1].splitlines()[1:]:
        if not re.match(r"\s*\[\s*\d+\]", line):
            break
        exports.add(line.split()[-1])
    assert exports and all(name.startswith(prefix) for name in exports), sorted(exports)
    nm = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True).stdout
    assert exports == {line.split()[-1] for line in nm.splitlines() if line.strip()}
