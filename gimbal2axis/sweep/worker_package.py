"""The gimbal2axis package sent to the workers of an existing Dask scheduler (gimbal2axis sweep
--scheduler, gimbal2axis freqresp --scheduler), so that a worker needs only Python and the package's
dependencies, not the package itself.

The client packs the package as it imports it: its Python files and its compiled kernel
(gimbal2axis.native._native, built for this Python and platform), not the build_locations.json of this
checkout. A Dask worker plugin (ShippedPackage) unpacks the archive once per worker into the worker's
local directory (named by the archive's SHA-256) and puts it first on sys.path, ahead of any
gimbal2axis installed there (another checkout, an older version), whose modules already imported are
dropped. The scheduler gives the plugin to workers that join later too. Zip imports cannot load
compiled modules, hence unpacking rather than client.upload_file of a zip.

Before any case runs, every worker imports the package it was sent and loads the compiled kernel
(check_worker); a worker that cannot (another Python version or platform, a missing dependency) is
refused in one line that names it and says why. The FMU travels as bytes with each sweep and is
extracted once per worker, keyed by its SHA-256 (gimbal2axis.fmu.worker_cache).

The scheduler needs no gimbal2axis either: it unpickles the task graphs it is sent, so a task is
call_pickled (of this module, sent by value) with the function and arguments to call as bytes, which
only the worker unpickles (pickled_call).

This module is sent to the workers by value (cloudpickle, register_by_value), as they cannot import
it before the plugin ran: it uses only the standard library and distributed at module level.
"""
from __future__ import annotations

import hashlib
import importlib
import io
import os
import pathlib
import shutil
import sys
import zipfile

from distributed.diagnostics.plugin import WorkerPlugin

PLUGIN_NAME = "gimbal2axis-package"
PACKAGE = "gimbal2axis"
LEFT_OUT = {"build_locations.json"}   # this checkout's build paths: a worker gets the FMU with the sweep


def register_by_value() -> None:
    """Pickles what this module defines by value: the scheduler and the workers cannot import it."""
    import cloudpickle

    cloudpickle.register_pickle_by_value(sys.modules[__name__])


def pickled_call(function, *args, **kwargs) -> bytes:
    """function, args and kwargs as bytes for call_pickled: opaque to the scheduler."""
    import cloudpickle

    return cloudpickle.dumps((function, args, kwargs))


def _call_pickled_by_value():
    """call_pickled, defined inside this function: pickle cannot refer to it by name, so Dask falls back
    to cloudpickle for the task graph, which sends its code. (A module-level function inside a graph
    is pickled by reference, whatever register_by_value says, and the scheduler, which unpickles the
    graph, cannot import this module.)"""

    def call_pickled(payload: bytes, **resolved):
        """On a worker: the call that pickled_call packed, with `resolved` (arguments that Dask
        resolves before the task runs, such as the FMU scattered to the workers) added to its keywords."""
        import pickle

        function, args, kwargs = pickle.loads(payload)
        return function(*args, **kwargs, **resolved)

    return call_pickled


call_pickled = _call_pickled_by_value()


def package_archive() -> tuple[bytes, str]:
    """(zip bytes, SHA-256) of the gimbal2axis package as this process imports it, compiled kernel
    included; the same files give the same bytes (fixed times and order), so the digest names the code."""
    import importlib.resources

    root = pathlib.Path(str(importlib.resources.files(PACKAGE)))
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for path in sorted(root.rglob("*")):
            if not path.is_file() or "__pycache__" in path.parts or path.name in LEFT_OUT or path.suffix == ".pyc":
                continue
            entry = zipfile.ZipInfo(f"{PACKAGE}/{path.relative_to(root).as_posix()}", date_time=(1980, 1, 1, 0, 0, 0))
            entry.compress_type = zipfile.ZIP_DEFLATED
            entry.external_attr = 0o644 << 16
            archive.writestr(entry, path.read_bytes())
    data = buffer.getvalue()
    return data, hashlib.sha256(data).hexdigest()


class ShippedPackage(WorkerPlugin):
    """Unpacks the archive on a worker and makes it the gimbal2axis that the worker imports."""

    def __init__(self, archive: bytes, digest: str):
        self.archive, self.digest = archive, digest

    def setup(self, worker) -> None:
        folder = pathlib.Path(worker.local_directory) / f"gimbal2axis-package-{self.digest[:16]}"
        if not folder.is_dir():
            unpacking = folder.with_name(f"{folder.name}.unpacking-{os.getpid()}")
            shutil.rmtree(unpacking, ignore_errors=True)
            with zipfile.ZipFile(io.BytesIO(self.archive)) as archive:
                archive.extractall(unpacking)
            try:   # whole or not at all, should two workers share the directory
                os.replace(unpacking, folder)
            except OSError:
                if not folder.is_dir():
                    raise
                shutil.rmtree(unpacking, ignore_errors=True)   # another worker unpacked the same archive first
        self.archive = b""   # unpacked: the worker need not keep a copy in memory
        path = str(folder)
        imported = sys.modules.get(PACKAGE)
        if imported is not None and str(getattr(imported, "__file__", "")).startswith(path + os.sep):
            return   # this very package is imported already (an earlier sweep of the same code)
        for name in [n for n in sys.modules if n == PACKAGE or n.startswith(PACKAGE + ".")]:
            del sys.modules[name]   # another gimbal2axis (installed here, or sent by an earlier sweep)
        cache = getattr(worker, "_gimbal_sweep_cache", None)   # FMU instances of that other code
        if cache:
            for loaded in cache.values():
                try:
                    loaded.close()
                except Exception:
                    pass
            cache.clear()
        sys.path[:] = [p for p in sys.path if not pathlib.Path(p).name.startswith("gimbal2axis-package-")]
        sys.path.insert(0, path)
        importlib.invalidate_caches()


def python_and_platform() -> str:
    import platform

    return f"Python {platform.python_version()} on {sys.platform}-{platform.machine()}"


def check_worker(digest: str, client_python: str) -> dict:
    """On a worker: imports the package it was sent and its compiled kernel; {"ok": True} or
    {"ok": False, "reason": ...}."""
    where = python_and_platform()
    try:
        package = importlib.import_module(PACKAGE)
        importlib.import_module(f"{PACKAGE}.sweep.worker")   # what the cases run, with its dependencies
        native = importlib.import_module(f"{PACKAGE}.native")
    except Exception as exc:   # e.g. a dependency missing there (numpy, scipy, fmpy)
        return {"ok": False, "reason": f"cannot import the gimbal2axis package ({type(exc).__name__}: {exc}; "
                                       f"{where})"}
    location = pathlib.Path(str(getattr(package, "__file__", "")))
    if not location.parent.parent.name.startswith(f"gimbal2axis-package-{digest[:16]}"):
        return {"ok": False, "reason": f"imports gimbal2axis from {location.parent}, not the package sent to it"}
    native.library()
    if native.why_not() is not None:
        return {"ok": False, "reason": f"runs {where}, but the compiled kernel sent to it was built for "
                                       f"{client_python}: {native.why_not()}"}
    return {"ok": True, "versions": dependency_versions()}


# What the cases compute with besides the kernel: other versions may round differently.
DEPENDENCIES = ("numpy", "scipy", "fmpy")


def dependency_versions() -> dict:
    from importlib import metadata

    versions = {}
    for name in DEPENDENCIES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions
