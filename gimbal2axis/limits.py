"""The largest sizes an input may ask for, and the bounded readers of input files.

Every count or length a user sets (a number of sinusoids, of grid values, of steps, a delay, the bytes
of a file) is checked against its limit here before anything is allocated for it: a refusal names the
key, its value and the limit, in one line, instead of a MemoryError, an OverflowError or an hour of
work. The limits sit far above what any scene, sweep or tuning of the project uses."""
from __future__ import annotations

import math
import os
import stat
import sys

from .errors import EXCERPT_CHARS, SceneError, excerpt

# A scene, sweep or tuning file: ours are a few kB, and a file of this size still parses in seconds (the
# loaders then quote a 40 MB key as an excerpt). Read no further, so that a path such as /dev/zero is
# refused after that instead of filling the memory.
MAX_TOML_BYTES = 64 << 20
# Tables and arrays nested in a TOML file (a scene's deepest is 4: [controller.azimuth] and the like).
# Deeper values would make the recursive walks over the parsed file (flattening the dotted FMU names,
# hashing, copying) exceed Python's recursion limit.
MAX_TOML_DEPTH = 32
# TOML's integers are 64-bit (toml.io, "Integer"); Python's parser reads any length, numpy takes no more.
TOML_INTEGER_RANGE = (-2 ** 63, 2 ** 63 - 1)
# A recorded base motion or target track (CSV): 20 min at 100 Hz of 16 columns is about 3 MB.
MAX_RECORDING_BYTES = 256 << 20
# A scene's `name` (the plot's title) and a scene's, sweep's or tuning's `description`.
MAX_TITLE_CHARS = 200
MAX_DESCRIPTION_CHARS = 10_000
# What a plot's title quotes of a description: its first line, cut to this.
TITLE_DESCRIPTION_CHARS = 160
# Communication steps of a run (stop_time / step_size), steps between two recorded rows
# (output_interval / step_size), samples of a Welch segment: 10**9 steps are a day at 0.1 ms.
MAX_STEPS = 10 ** 9
# Sinusoids per degree of freedom of a sea state (the scenes use 100 to 120), or of a sum of sinusoids.
MAX_SEA_STATE_COMPONENTS = 10_000
# The figure of a run: panels of a [plot] table, and signals of one panel (each a subplot or a line drawn).
MAX_PLOT_PANELS = 32
MAX_PLOT_SIGNALS = 64
# Bands of an [analysis.bands] table (each a column of the spectrum's table and a span in its figure).
MAX_ANALYSIS_BANDS = 100
# Steps between a voltage's computation and its application ([controller] delay_steps).
MAX_DELAY_STEPS = 10_000
# Cases of a sweep (after its `cases` limit), values of one grid parameter, random draws per grid point.
MAX_SWEEP_CASES = 1_000_000
# A tuning: parameters (CMA-ES keeps a covariance matrix of their number squared), candidates, candidates
# per batch, and runs per candidate (its robustness set or holdout).
MAX_TUNE_PARAMETERS = 1_000
MAX_TUNE_TRIALS = 100_000
MAX_TUNE_BATCH = 10_000
MAX_SCENARIOS = 10_000
# A tuned parameter's bounds: the optimizers sample and scale within [low, high], whose width must be a
# finite float (1e308 - (-1e308) is not).
MAX_TUNE_BOUND = 1e300


class TooLarge(ValueError):
    """A file longer than its limit (read_bounded); the message names it and the limit."""


def over_limit(where: str, value, limit, unit: str = "", error: type | None = None) -> None:
    """Refuses (`error`, SceneError by default) `value` above `limit`, naming `where` (the file's key)."""
    if value > limit:
        shown = f"{value:g}" if isinstance(value, float) else str(value)
        raise (error or SceneError)(f"{where} = {shown} is over the limit of {limit:,}{unit}")


def too_long(where: str, length: int, limit: int, unit: str = "characters", error: type | None = None) -> None:
    """Refuses a text or list of `length` (characters, items) above `limit`, naming `where`."""
    if length > limit:
        raise (error or SceneError)(f"{where} is {length:,} {unit} long, over the limit of {limit:,} {unit}")


def steps_of(where: str, duration: float, step: float, error: type | None = None) -> float:
    """duration / step, refused when over MAX_STEPS (a float: the quotient of 1e308 s by 1 ms is inf)."""
    steps = duration / step
    if not steps <= MAX_STEPS:
        count = f"{steps:.3g}" if math.isfinite(steps) else f"over {sys.float_info.max:.3g}"
        raise (error or SceneError)(f"{where} = {duration:g} s is {count} steps of {step:g} s, over the limit of "
                                    f"{MAX_STEPS:,} steps")
    return steps


def read_bounded(path, limit: int, what: str) -> bytes:
    """The bytes of the file at `path`, at most `limit` of them: OSError for a file that cannot be read,
    TooLarge (naming the file, `what` it is and the limit) for a longer one. A regular file is refused
    by its size before reading; anything else (a pipe, a device such as /dev/zero) after limit + 1 bytes."""
    with open(path, "rb") as file:
        info = os.fstat(file.fileno())
        if stat.S_ISREG(info.st_mode) and info.st_size > limit:
            raise TooLarge(f"{path}: {info.st_size:,} bytes is over the limit of {limit:,} bytes of {what}")
        data = file.read(limit + 1)
    if len(data) > limit:
        raise TooLarge(f"{path}: more than the limit of {limit:,} bytes of {what}")
    return data


def toml_structure_refusal(document: dict) -> str | None:
    """Why the parsed TOML `document` cannot be taken (a value nested deeper than MAX_TOML_DEPTH, an
    integer outside 64 bits), naming the key; None when it can. Iterative: the walk itself must not
    exceed the recursion limit it guards."""
    low, high = TOML_INTEGER_RANGE
    pending = [(document, "", 1)]
    while pending:
        value, where, depth = pending.pop()
        if isinstance(value, (dict, list)):
            if depth > MAX_TOML_DEPTH:
                return f"{_where(where)} is nested {depth} tables or arrays deep, over the limit of {MAX_TOML_DEPTH}"
            items = value.items() if isinstance(value, dict) else enumerate(value)
            for key, item in items:
                pending.append((item, f"{where}.{key}" if isinstance(value, dict) else f"{where}[{key}]", depth + 1))
        elif isinstance(value, int) and not isinstance(value, bool) and not low <= value <= high:
            return f"{_where(where)}: an integer of {value.bit_length()} bits is outside TOML's 64-bit range " \
                   f"[-2**63, 2**63 - 1]"
    return None


def _where(dotted: str) -> str:
    return f"'{excerpt(dotted.lstrip('.'))}'"


def read_toml(path, error: type | None = None) -> dict:
    """The parsed TOML file at `path`; an `error` (the exception type to raise) naming the file when
    it cannot be read or is not TOML (SceneError by default), is longer than MAX_TOML_BYTES, nested deeper
    than MAX_TOML_DEPTH or holds an integer outside 64 bits."""
    error = error or SceneError
    import tomllib

    try:
        document = tomllib.loads(read_bounded(path, MAX_TOML_BYTES, "a TOML file").decode("utf-8"))
    except OSError as exc:
        raise error(f"{path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise error(f"{path}: not a text file (TOML is UTF-8)") from None
    except TooLarge as exc:
        raise error(str(exc)) from None
    except RecursionError:   # tomllib parses nested arrays and inline tables recursively
        raise error(f"{path}: arrays or inline tables nested deeper than the TOML parser can read (the "
                    f"limit is {MAX_TOML_DEPTH} levels)") from None
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML: {excerpt(exc, 2 * EXCERPT_CHARS)}") from None
    except ValueError:   # int() of more digits than Python converts (sys.get_int_max_str_digits)
        raise error(f"{path}: not valid TOML: an integer of thousands of digits (TOML's integers are "
                    "64-bit)") from None
    refusal = toml_structure_refusal(document)
    if refusal:
        raise error(f"{path}: {refusal}")
    return document
