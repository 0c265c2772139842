"""The FMU as a master sees it (fmu.py: extracted once, variables by name, typed setters and getters,
instances whose log is collected, and `simulate`, a plain fixed-step master) and an FMU kept extracted
per worker process and reused across runs (worker_cache.py)."""
from .fmu import FIDELITY, FMU, LogEntry, enumeration_items, simulate, state_names, value_type

__all__ = ["FIDELITY", "FMU", "LogEntry", "enumeration_items", "simulate", "state_names", "value_type"]
