"""An FMU extracted once per worker and reused: a Dask worker (or, without Dask, the calling thread)
keeps the FMU it was sent, one instance of it (reset with fmi2Reset between runs) and a pool of
instances for lockstep batches. The cache is an attribute of the Dask worker (`get_worker()`), else
thread-local, and is keyed by the FMU's SHA-256: a rebuilt FMU is loaded afresh. The FMU arrives as
bytes (scattered to the workers with each sweep), so a worker on another machine needs no copy of its
own; the bytes are checked against the SHA-256 they were sent with before the first use. Used by the
sweeps (gimbal2axis.sweep.worker) and the frequency responses on Dask (gimbal2axis.analysis.frequency_response).
"""
from __future__ import annotations

import atexit
import hashlib
import pathlib
import shutil
import sys
import tempfile
import threading

_LOCAL = threading.local()


class _Loaded:
    """An extracted FMU, one instance of it and the list its logger appends to."""

    def __init__(self, fmu_path: pathlib.Path, workdir: pathlib.Path):
        from .fmu import FMU

        self.fmu = FMU(fmu_path, workdir=workdir)
        self.workdir = workdir   # the FMU's bytes and its extraction: removed with the entry
        self.log: list = []
        self.slave = None
        self.pool: list = []   # (instance, its log) for lockstep batches
        self.cases = 0
        atexit.register(self.close)

    def instances(self, count: int) -> list:
        """`count` (instance, log) pairs of the pool, instantiating what is missing."""
        while len(self.pool) < count:
            log: list = []
            self.pool.append((self.fmu.instantiate(f"sweep-{len(self.pool)}", log), log))
        return self.pool[:count]

    def discard_pool(self):
        for slave, _ in self.pool:
            try:
                slave.freeInstance()
            except Exception:
                pass
        self.pool = []

    def instance(self):
        if self.slave is None:
            self.slave = self.fmu.instantiate("sweep", self.log)
        return self.slave

    def discard_instance(self):
        if self.slave is not None:
            try:
                self.slave.freeInstance()
            except Exception:
                pass
            self.slave = None

    def close(self):
        self.discard_instance()
        self.discard_pool()
        self.fmu.close()
        shutil.rmtree(self.workdir, ignore_errors=True)


def dask_worker():
    """The Dask worker this runs on, or None (a serial sweep: Dask is then not even imported)."""
    if "distributed" not in sys.modules:
        return None
    try:
        from distributed import get_worker

        return get_worker()
    except (ImportError, ValueError):
        return None


def _cache() -> dict:
    worker = dask_worker()
    if worker is not None:
        if not hasattr(worker, "_gimbal_sweep_cache"):
            worker._gimbal_sweep_cache = {}
        return worker._gimbal_sweep_cache
    if not hasattr(_LOCAL, "cache"):
        _LOCAL.cache = {}
    return _LOCAL.cache


def _workdir() -> pathlib.Path:
    worker = dask_worker()
    return pathlib.Path(worker.local_directory) if worker is not None else pathlib.Path(tempfile.gettempdir())


def loaded_fmu(fmu_bytes: bytes, digest: str) -> _Loaded:
    """The worker's FMU with this digest: written to the worker's directory and extracted once (bytes
    that do not have this SHA-256 are refused: ValueError)."""
    cache = _cache()
    entry = cache.get(digest)
    if entry is None:
        received = fmu_digest(fmu_bytes)
        if received != digest:
            raise ValueError(f"the FMU received (SHA-256 {received[:12]}) is not the one sent ({digest[:12]})")
        for old in list(cache.values()):   # an older build: free it
            old.close()
        cache.clear()
        workdir = pathlib.Path(tempfile.mkdtemp(prefix="gimbal_sweep_", dir=_workdir()))
        path = workdir / f"Gimbal2Axis-{digest[:12]}.fmu"
        path.write_bytes(fmu_bytes)
        entry = cache[digest] = _Loaded(path, workdir)
    return entry


def fmu_digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()
