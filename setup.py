"""What pyproject.toml cannot say: the version, which is CMakeLists.txt's project(VERSION) (one number
for the FMU, the package and the README), and the C kernel, one extension (gimbal2axis.native._native)
built from the kernel's library folder c_kernel/ (src/*.c, include/gimbal_kernel/*.h; the FMUs and the
native drivers link the same sources) and gimbal2axis/native/module.c, the extension's empty module, and
used through ctypes (gimbal2axis/native/__init__.py): the built-in controllers, the sensors, the sums of
sinusoids of the base motions, the sea state, the recorded motion and the compiled communication loop."""
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
# The kernel's sources (the CMake build compiles the same files for the FMUs and the drivers:
# c_kernel/CMakeLists.txt) and the extension's module. Relative paths, as setuptools wants them; an
# sdist carries the sources by being given them here and the headers by `depends`.
kernel = pathlib.Path("c_kernel")
sources = sorted(str(path) for path in (kernel / "src").glob("*.c")) + ["gimbal2axis/native/module.c"]
headers = sorted(str(path) for path in (kernel / "include" / "gimbal_kernel").glob("*.h"))

setup(version=cmake_project_version(),
      ext_modules=[Extension("gimbal2axis.native._native", sources, include_dirs=[str(kernel / "include")],
                             depends=headers, extra_compile_args=flags)])
