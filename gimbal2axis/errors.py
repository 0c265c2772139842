"""The error and warning types of scene handling, and small validation helpers shared by the modules."""
from __future__ import annotations

import math


class SceneError(ValueError):
    """A scene that cannot be run; the message says where and why."""


class SceneWarning(UserWarning):
    """A scene that runs, but probably not as its author meant; the message names the key."""


def read_toml(path, error: type = SceneError) -> dict:
    """The parsed TOML file at `path`; an `error` (the exception type to raise) naming the file when
    it cannot be read or is not TOML."""
    import tomllib

    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except OSError as exc:
        raise error(f"{path}: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML: {exc}") from None


def check_keys(where: str, table: dict, allowed: set) -> None:
    unknown = set(table) - set(allowed)
    if unknown:
        raise SceneError(f"[{where}]: unknown key(s) {sorted(unknown)}; allowed: {sorted(allowed)}")


def number(where: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SceneError(f"{where} must be a finite number, got {value!r}")
    return float(value)


def positive(where: str, value) -> float:
    value = number(where, value)
    if not value > 0:
        raise SceneError(f"{where} must be positive, got {value!r}")
    return value
