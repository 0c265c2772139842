"""The package's version: its distribution's metadata, which setup.py takes from CMakeLists.txt's
project(VERSION), the FMU's version too. A leaf: `gimbal2axis --version` reads it without importing
the rest of the package."""
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("gimbal2axis")
except PackageNotFoundError:   # imported from a source tree that was never installed: no metadata says
    __version__ = "0+unknown"
