"""Loaded by each worker process of a local cluster at its start (a Dask preload, make_client): the
worker ignores SIGINT. A terminal's Ctrl-C reaches the whole process group, and the process that made
the cluster (the sweep) alone saves the table and closes the cluster in order; a worker dying of it
would only print a traceback and lose the FMU its cases need. Worker processes are new interpreters
(spawned), so nothing of the main process's signal handling carries over: this sets it in each."""
import signal


def dask_setup(worker) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
