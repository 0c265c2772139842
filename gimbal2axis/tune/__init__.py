"""Tuning a controller: an optimizer (Optuna) over the sweep engine. docs/tuning.md."""
from .spec import TuneError, Tuning, load_tuning

__all__ = ["TuneError", "Tuning", "load_tuning"]
