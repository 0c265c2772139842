"""The error and warning types of scene handling, and small validation helpers shared by the modules.

Every message that quotes what the user wrote (a key, a value, a name) quotes it through `excerpt`
or `shown`: a typo is shown whole, a 40 MB key is not, so a refusal stays one readable line."""
from __future__ import annotations

import difflib
import math

# The most characters of user-provided text a message quotes: a dotted FMU name or a file name fits,
# a pasted block does not.
EXCERPT_CHARS = 80
# Names longer than this get no close-match search: difflib's cost grows with the length, and no
# name of the scene format or of the FMU is anywhere near it.
LONGEST_NAME_TO_MATCH = 200


class SceneError(ValueError):
    """A scene that cannot be run; the message says where and why."""


class SceneWarning(UserWarning):
    """A scene that runs, but probably not as its author meant; the message names the key."""


class FMUCallFailed(Exception):
    """An FMI call of a run's loop (the Python loops or the compiled one) that returned fmi2Discard or
    fmi2Error; `function` names it. Here, below every loop, so that none imports another for it."""

    def __init__(self, function: str):
        super().__init__(f"{function} returned fmi2Discard or fmi2Error")
        self.function = function


def excerpt(text: str, limit: int = EXCERPT_CHARS) -> str:
    """`text` itself when short, else its first `limit` characters and '…(N characters)'."""
    text = str(text)
    if len(text) <= limit:
        return text
    return f"{text[:limit]}…({len(text)} characters)"


def shown(value, limit: int = EXCERPT_CHARS) -> str:
    """A value as a message quotes it: its repr, cut to an excerpt (a string, a list or a table as
    long as the user made it)."""
    if isinstance(value, str):
        return repr(excerpt(value, limit))
    return excerpt(repr(value), limit)


def did_you_mean(name, known) -> str:
    """' (did you mean 'a' or 'b'?)' for the names of `known` close to `name`, else '' (to append to a
    refusal). difflib's ratio at its default cutoff 0.6 catches a dropped, doubled or swapped character
    in the FMU's dotted names (motor1.R vs motor1.RR) without proposing unrelated ones."""
    if not isinstance(name, str) or len(name) > LONGEST_NAME_TO_MATCH:
        return ""
    matches = difflib.get_close_matches(name, [k for k in known if isinstance(k, str)], n=3)
    if not matches:
        return ""
    return " (did you mean " + " or ".join(f"'{match}'" for match in matches) + "?)"


def read_toml(path, error: type = SceneError) -> dict:
    """The parsed TOML file at `path`; an `error` (the exception type to raise) naming the file when
    it cannot be read or is not TOML."""
    import tomllib

    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except OSError as exc:
        raise error(f"{path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise error(f"{path}: not a text file (TOML is UTF-8)") from None
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML: {excerpt(exc, 2 * EXCERPT_CHARS)}") from None


def check_keys(where: str, table: dict, allowed: set) -> None:
    """Refuses keys of `table` not in `allowed`, each quoted as an excerpt, with the close matches."""
    unknown = sorted(set(table) - set(allowed), key=str)
    if unknown:
        listed = "[" + ", ".join(shown(key) for key in unknown[:5]) + (", …" if len(unknown) > 5 else "") + "]"
        raise SceneError(f"[{where}]: unknown key(s) {listed}{did_you_mean(unknown[0], sorted(allowed))}; "
                         f"allowed: {sorted(allowed)}")


def number(where: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        hint = " (a string: write the number without quotes)" if isinstance(value, str) and is_number_text(value) \
            else ""
        raise SceneError(f"{where} must be a finite number, got {shown(value)}{hint}")
    return float(value)


def is_number_text(text: str) -> bool:
    """Whether a string holds a finite number (a number the user quoted)."""
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def positive(where: str, value) -> float:
    value = number(where, value)
    if not value > 0:
        raise SceneError(f"{where} must be positive, got {value!r}")
    return value


def non_negative(where: str, value) -> float:
    value = number(where, value)
    if value < 0:
        raise SceneError(f"{where} must be >= 0, got {value!r}")
    return value


def integer(where: str, value, minimum: int | None = None) -> int:
    """An integer (not a bool, not a float such as 1.5) of at least `minimum`."""
    if isinstance(value, bool) or not isinstance(value, int) or (minimum is not None and value < minimum):
        at_least = "" if minimum is None else f" >= {minimum}"
        raise SceneError(f"{where} must be an integer{at_least}, got {shown(value)}")
    return value


def boolean(where: str, value) -> bool:
    if not isinstance(value, bool):
        raise SceneError(f"{where} must be true or false, got {shown(value)}")
    return value


def choice(where: str, value, allowed) -> str:
    """`value` when it is one of `allowed` (strings), else a refusal listing them, with the close ones."""
    if not isinstance(value, str) or value not in allowed:
        raise SceneError(f"{where} must be one of {', '.join(repr(a) for a in allowed)}, got {shown(value)}"
                         f"{did_you_mean(value, allowed)}")
    return value
