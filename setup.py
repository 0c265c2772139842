"""The one thing pyproject.toml cannot say: scene_lib's compiled master loop, a C extension
(scripts/scene_lib/_master_loop.c, used through ctypes; see scene_lib/compiled_loop.py)."""
import sys

from setuptools import Extension, setup

# Contracting a*b + c into one fused multiply-add would round differently from Python, whose loop
# the compiled one must reproduce bit for bit (MSVC does not contract by default).
flags = [] if sys.platform == "win32" else ["-O2", "-ffp-contract=off"]

setup(ext_modules=[Extension("scene_lib._master_loop", ["scripts/scene_lib/_master_loop.c"], extra_compile_args=flags)])
