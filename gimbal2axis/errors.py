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
# The longest line a command prints as its error (one_line): a message of the product's own with a
# few excerpts in it fits.
LONGEST_MESSAGE_CHARS = 1000


class SceneError(ValueError):
    """A scene that cannot be run; the message says where and why."""


class SceneWarning(UserWarning):
    """A scene that runs, but probably not as its author meant; the message names the key."""


class StopSignal(BaseException):
    """Raised by a command's own SIGINT or SIGTERM handler (cli/failures.py): the user's signal to the
    process. The wrappers of user code (a controller's reset and step) let it pass and turn every other
    BaseException (sys.exit, a KeyboardInterrupt the user's code raised itself) into the code's failure."""


class Interrupted(StopSignal, KeyboardInterrupt):
    """SIGINT (Ctrl-C), raised where the command cannot end at its next step."""


class Terminated(StopSignal):
    """SIGTERM, raised where the command cannot end at its next step."""


class FMUCallFailed(Exception):
    """An FMI call of a run's loop (the Python loops or the compiled one) that returned fmi2Discard or
    fmi2Error; `function` names it. Here, below every loop, so that none imports another for it."""

    def __init__(self, function: str):
        super().__init__(f"{function} returned fmi2Discard or fmi2Error")
        self.function = function


def excerpt(text, limit: int = EXCERPT_CHARS) -> str:
    """`text` as a message embeds it: each character that is not printable written as repr writes it
    (NUL as \\x00, a newline as \\n, the ESC of a terminal's colour codes as \\x1b), so that a message
    stays one line that cannot rewrite the terminal; its first `limit` characters (as written) and
    '…(N characters)' when it is longer."""
    text = str(text)
    head = text[:limit]
    if head.isprintable():
        return _cut(text, limit)
    pieces, used, taken = [], 0, 0
    for character in head:
        piece = character if character.isprintable() else repr(character)[1:-1]
        if used + len(piece) > limit:
            break
        pieces.append(piece)
        used, taken = used + len(piece), taken + 1
    return "".join(pieces) + ("" if taken == len(text) else f"…({len(text)} characters)")


def one_line(message, limit: int = LONGEST_MESSAGE_CHARS) -> str:
    """A whole message as a command prints it: escaped and cut as `excerpt` does, at `limit`
    characters; the last defence against a multi-line or megabyte text that no check caught."""
    return excerpt(message, limit)


def _cut(text: str, limit: int) -> str:
    if len(text) <= limit:
        return text
    return f"{text[:limit]}…({len(text)} characters)"


def safe_repr(value) -> str:
    """repr(value), or what the value is when its repr fails (an int of more than 4300 digits, a
    user's object whose __repr__ raises)."""
    try:
        return repr(value)
    except Exception:
        if isinstance(value, int):
            return f"an integer of {value.bit_length()} bits"
        return f"a {type(value).__name__} object"


def shown(value, limit: int = EXCERPT_CHARS) -> str:
    """A value as a message quotes it: its repr, cut to an excerpt (a string, a list or a table as
    long as the user made it)."""
    if isinstance(value, str):
        return repr(_cut(value, limit))
    return excerpt(safe_repr(value), limit)


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


def check_keys(where: str, table: dict, allowed: set) -> None:
    """Refuses keys of `table` not in `allowed`, each quoted as an excerpt, with the close matches; and
    a `table` that is not a table (a value where the file needs [where] or { ... })."""
    if not isinstance(table, dict):
        raise SceneError(f"[{where}] must be a table, got {shown(table)}")
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


def within(where: str, value, low: float, high: float) -> float:
    """A finite number in [low, high], both included; else a refusal naming the range."""
    value = number(where, value)
    if not low <= value <= high:
        raise SceneError(f"{where} = {value:g} is outside [{low:g}, {high:g}]")
    return value


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
