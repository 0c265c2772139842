"""Parameter sweeps and Monte Carlo runs of a scene on Dask: sweep files (spec), the parameter names a
sweep may vary (names), the per-worker case runner (worker), the results table and summary plot (table),
the progress counter (progress) and the orchestration (runner)."""
from .runner import Outcome, SweepOptions, close_client, make_client, prepare, run_sweep
from .spec import Sweep, SweepError, apply_case, case_key, load_sweep

__all__ = ["Outcome", "Sweep", "SweepError", "SweepOptions", "apply_case", "case_key", "close_client", "load_sweep",
           "make_client", "prepare", "run_sweep"]
