"""What pyproject.toml cannot say: the version, which is CMakeLists.txt's project(VERSION) (one number
for the FMU, the package and the README), and scene_lib's C kernels, one extension (scene_lib._native)
built from gimbal2axis/native/*.c and used through ctypes (scene_lib/native.py): the compiled
communication loop and the base motion's sums of sinusoids."""
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


# Contracting a*b + c into one fused multiply-add would round differently from Python, whose loop
# the compiled one must reproduce bit for bit (MSVC does not contract by default).
flags = [] if sys.platform == "win32" else ["-O2", "-ffp-contract=off"]
sources = [f"gimbal2axis/native/{name}.c" for name in ("module", "master_loop", "sum_of_sines")]

setup(version=cmake_project_version(),
      ext_modules=[Extension("scene_lib._native", sources, extra_compile_args=flags)])
