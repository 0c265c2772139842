"""The one thing pyproject.toml cannot say: scene_lib's C kernels, one extension (scene_lib._native)
built from scripts/scene_lib/native/*.c and used through ctypes (scene_lib/native.py): the compiled
communication loop and the base motion's sums of sinusoids."""
import sys

from setuptools import Extension, setup

# Contracting a*b + c into one fused multiply-add would round differently from Python, whose loop
# the compiled one must reproduce bit for bit (MSVC does not contract by default).
flags = [] if sys.platform == "win32" else ["-O2", "-ffp-contract=off"]
sources = [f"scripts/scene_lib/native/{name}.c" for name in ("module", "master_loop", "sum_of_sines")]

setup(ext_modules=[Extension("scene_lib._native", sources, extra_compile_args=flags)])
