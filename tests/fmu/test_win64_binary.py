"""The FMU's Windows binary (binaries/win64, cross-compiled with mingw-w64 by fmu_src/win64.cmake):
a well-behaved guest by its import and export tables, the same scene under Wine as the linux64
binary natively, and the SUNDIALS methods refused with a message that says why. The FMI 3.0 FMU's
x86_64-windows binary runs the same scene under Wine through the fmi3* functions and gives the FMI
2.0 DLL's results bit for bit.

tests/fmu/fmu_scene_driver.c, built natively and for Windows, runs the scene; Wine is started once per
binary."""
import os
import pathlib
import re
import shutil
import subprocess
import zipfile

import fmpy
import numpy as np
import pytest

pytestmark = pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                                reason="the sanitizer build makes no win64 binary (GIMBAL_WIN64=AUTO leaves it out)")

OBJDUMP = "x86_64-w64-mingw32-objdump"
SUNDIALS_METHODS = (0, 1, 2, 3)


def built(path):
    if not path.is_file():
        pytest.fail(f"{path} is missing: the win64 build needs the mingw-w64 tool chain "
                    "(g++-mingw-w64-x86-64-win32; scripts/setup.sh installs it for the tests)")
    return path


@pytest.fixture(scope="module")
def win64_dll(build_dir):
    return built(build_dir / "fmu_staging" / "binaries" / "win64" / "Gimbal2Axis.dll")


@pytest.fixture(scope="module")
def fmi3_dll(build_dir, fmu_path):
    dll = build_dir / "win64" / "fmi3" / "binary" / "Gimbal2Axis.dll"
    with zipfile.ZipFile(build_dir / "Gimbal2Axis-fmi3.fmu") as fmu:
        assert fmu.read("binaries/x86_64-windows/Gimbal2Axis.dll") == built(dll).read_bytes()
    return dll


@pytest.fixture(scope="module")
def win64_driver(build_dir):
    return built(build_dir / "win64" / "fmu_scene_driver.exe")


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


def windows_path(path: pathlib.Path) -> str:
    return "Z:" + str(path).replace("/", "\\")  # Wine's drive Z: is the Unix root


@pytest.fixture(scope="module")
def scene_runs(build_dir, win64_dll, fmi3_dll, win64_driver, tmp_path_factory):
    """Both drivers on the scene; the Windows one also tries every SUNDIALS method (one Wine start)."""
    wine = next((shutil.which(c) for c in ("wine64", "/usr/lib/wine/wine64", "wine") if shutil.which(c)), None)
    if wine is None:
        pytest.fail("Wine is missing (Debian: wine64; scripts/setup.sh installs it for the tests)")
    out = tmp_path_factory.mktemp("win64_scene")
    guid = fmpy.read_model_description(str(build_dir / "fmu_staging" / "modelDescription.xml")).guid
    so = build_dir / "fmu_staging" / "binaries" / "linux64" / "Gimbal2Axis.so"
    native = subprocess.run([str(build_dir / "fmu_scene_driver"), str(so), guid, str(out / "linux64.csv")],
                            capture_output=True, text=True, timeout=120)
    assert native.returncode == 0, native.stdout + native.stderr
    # Headless and throwaway: a prefix of its own in the build directory (made on the first run, ~15 s),
    # no debug output, no Mono/Gecko installers.
    env = dict(os.environ, WINEPREFIX=str(build_dir / "wine-prefix"), WINEDEBUG="-all",
               WINEDLLOVERRIDES="mscoree,mshtml=")
    env.pop("DISPLAY", None)
    windows = subprocess.run([wine, str(win64_driver), windows_path(win64_dll), guid, windows_path(out / "win64.csv")] +
                             [str(m) for m in SUNDIALS_METHODS], capture_output=True, text=True, timeout=600, env=env)
    assert windows.returncode == 0, windows.stdout + windows.stderr
    token = fmpy.read_model_description(str(build_dir / "Gimbal2Axis-fmi3.fmu")).instantiationToken
    fmi3 = subprocess.run([wine, str(win64_driver), "--fmi3", windows_path(fmi3_dll), token,
                           windows_path(out / "win64_fmi3.csv")] + [str(m) for m in SUNDIALS_METHODS],
                          capture_output=True, text=True, timeout=600, env=env)
    assert fmi3.returncode == 0, fmi3.stdout + fmi3.stderr
    return out / "linux64.csv", out / "win64.csv", windows.stdout, out / "win64_fmi3.csv", fmi3.stdout


def read_csv(path):
    return np.genfromtxt(path, delimiter=",", names=True)


def test_wine_runs_the_scene_like_linux(scene_runs):
    linux_csv, windows_csv = scene_runs[:2]
    linux, windows = read_csv(linux_csv), read_csv(windows_csv)
    assert linux.shape == windows.shape == (301,)
    np.testing.assert_array_equal(linux["time"], windows["time"])
    # The scene does switch: saturated voltages, current limits, backlash stops.
    assert linux["eventstotal"][-1] > 10
    # Different compilers and C libraries (glibc's libm, msvcrt's): the same trajectory to the
    # integrator's tolerance (solver.rtol = 1e-6), relative to each signal's range.
    worst = {}
    for name in linux.dtype.names:
        if name in ("time", "eventstotal", "solversteps"):
            continue
        scale = max(np.max(np.abs(linux[name])), 1e-300)
        worst[name] = np.max(np.abs(windows[name] - linux[name])) / scale
    assert max(worst.values()) < 1e-6, worst
    assert abs(int(windows["eventstotal"][-1]) - int(linux["eventstotal"][-1])) <= 2


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_dll_refuses_the_sundials_methods_by_name(scene_runs, version):
    log = scene_runs[2] if version == "fmi2" else scene_runs[4]
    for method in SUNDIALS_METHODS:
        assert f"refusal: solver.method = {method} status = 3" in log, log  # fmi2Error, fmi3Error
        assert (f"{version}ExitInitializationMode: solver.method = {method} is not available in this binary: "
                "it was built without SUNDIALS") in log, log


def test_the_fmi3_dll_under_wine_equals_the_fmi2_dll_bit_for_bit(scene_runs):
    """The same core behind the other interface, the same calls in the same order: the same doubles."""
    _, fmi2_csv, _, fmi3_csv, _ = scene_runs
    fmi2, fmi3 = read_csv(fmi2_csv), read_csv(fmi3_csv)
    assert fmi2.shape == fmi3.shape == (301,)
    assert fmi3["eventstotal"][-1] > 10
    for name in fmi2.dtype.names:
        np.testing.assert_array_equal(fmi3[name], fmi2[name], err_msg=name)


def test_the_fmi3_binaries_give_the_fmi2_binaries_results_natively(build_dir, tmp_path):
    """The native driver on both linux binaries: the FMI 3.0 calls change no double."""
    guid = fmpy.read_model_description(str(build_dir / "fmu_staging" / "modelDescription.xml")).guid
    token = fmpy.read_model_description(str(build_dir / "Gimbal2Axis-fmi3.fmu")).instantiationToken
    driver = str(build_dir / "fmu_scene_driver")
    so2 = build_dir / "fmu_staging" / "binaries" / "linux64" / "Gimbal2Axis.so"
    so3 = build_dir / "fmi3" / "binary" / "Gimbal2Axis.so"
    for command in ([driver, str(so2), guid, str(tmp_path / "fmi2.csv")],
                    [driver, "--fmi3", str(so3), token, str(tmp_path / "fmi3.csv")]):
        done = subprocess.run(command, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stdout + done.stderr
    assert (tmp_path / "fmi2.csv").read_bytes() == (tmp_path / "fmi3.csv").read_bytes()
