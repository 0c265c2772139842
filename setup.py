"""What pyproject.toml cannot say: the version, which is CMakeLists.txt's project(VERSION) (one number
for the FMU, the package and the README), and the C kernel, one extension (gimbal2axis.native._native)
built from gimbal2axis/native/*.c and used through ctypes (gimbal2axis/native/__init__.py): the
built-in controllers, the sensors, the sums of sinusoids of the base motions and the compiled
communication loop."""
import pathlib
import re
import sys

from setuptools import Extension, setup


def cmake_project_version() -> str:
    text = (pathlib.Path(__file__).resolve().parent / "CMakeLists.txt").read_text()
    match = re.search(r"project\(\s*Gimbal2Axis\s+VERSION\s+([0-9]+\.[0-9]+\.[0-9]+)", text)
    if match is None:
        raise RuntimeError("CMakeLists.txt: no project(Gimbal2Axis VERSION x.y.z ...)")
    return match.group(1)


# Contracting a*b + c into one fused multiply-add would round differently from the arithmetic the
# results were recorded with (MSVC does not contract by default).
flags = [] if sys.platform == "win32" else ["-O2", "-ffp-contract=off"]
# The kernel's sources (the CMake build compiles the same files, minus the module, for the drivers:
# gimbal2axis/native/kernel.cmake).
sources = sorted(str(path) for path in pathlib.Path("gimbal2axis/native").glob("*.c"))

setup(version=cmake_project_version(),
      ext_modules=[Extension("gimbal2axis.native._native", sources, extra_compile_args=flags)])
