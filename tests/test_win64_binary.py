"""The FMU's Windows binary (binaries/win64, cross-compiled with mingw-w64 by fmu_src/win64.cmake):
a well-behaved guest by its import and export tables."""
import os
import re
import shutil
import subprocess
import zipfile

import pytest

pytestmark = pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                                reason="the sanitizer build makes no win64 binary (GIMBAL_WIN64=AUTO leaves it out)")

OBJDUMP = "x86_64-w64-mingw32-objdump"


@pytest.fixture(scope="module")
def win64_dll(build_dir):
    dll = build_dir / "fmu_staging" / "binaries" / "win64" / "Gimbal2Axis.dll"
    if not dll.is_file():
        pytest.fail(f"{dll} is missing: the win64 build needs the mingw-w64 tool chain "
                    "(g++-mingw-w64-x86-64-win32; scripts/setup.sh installs it for the tests)")
    return dll


def objdump(dll):
    if shutil.which(OBJDUMP) is None:
        pytest.fail(f"{OBJDUMP} is missing (Debian: binutils-mingw-w64-x86-64)")
    return subprocess.run([OBJDUMP, "-p", str(dll)], capture_output=True, text=True, check=True).stdout


def test_fmu_holds_both_binaries(fmu_path, win64_dll):
    with zipfile.ZipFile(fmu_path) as fmu:
        names = set(fmu.namelist())
        assert {"binaries/linux64/Gimbal2Axis.so", "binaries/win64/Gimbal2Axis.dll"} <= names
        assert fmu.read("binaries/win64/Gimbal2Axis.dll") == win64_dll.read_bytes()


def test_dll_imports_only_windows_system_dlls(win64_dll):
    imports = re.findall(r"DLL Name: (\S+)", objdump(win64_dll))
    assert imports, "no import table found"
    runtime = [name for name in imports if re.match(r"(?i)lib(stdc\+\+|gcc_s|winpthread)", name)]
    assert runtime == [], f"the C++ runtime is not linked statically: {runtime}"
    system = re.compile(r"(?i)^(kernel32|msvcrt|ucrtbase|api-ms-win-[a-z0-9-]+)\.dll$")
    assert [name for name in imports if not system.match(name)] == [], imports


def test_dll_exports_exactly_the_fmi2_functions_of_the_linux_binary(build_dir, win64_dll):
    table = objdump(win64_dll).split("[Ordinal/Name Pointer] Table", 1)
    assert len(table) == 2, "no export table found"
    exports = set()
    for line in table[1].splitlines()[1:]:
        if not re.match(r"\s*\[\s*\d+\]", line):
            break
        exports.add(line.split()[-1])
    assert exports and all(name.startswith("fmi2") for name in exports), sorted(exports)
    so = build_dir / "fmu_staging" / "binaries" / "linux64" / "Gimbal2Axis.so"
    nm = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True).stdout
    assert exports == {line.split()[-1] for line in nm.splitlines() if line.strip()}
