"""Looking up a variable name the user typed: a refusal that suggests the close matches."""
from __future__ import annotations

import difflib


def did_you_mean(name: str, known) -> str:
    """' (did you mean 'a' or 'b'?)' for the names of `known` close to `name`, else '' (to append to a
    refusal). difflib's ratio at its default cutoff 0.6 catches a dropped, doubled or swapped character
    in the FMU's dotted names (motor1.R vs motor1.RR) without proposing unrelated ones."""
    matches = difflib.get_close_matches(name, list(known), n=3)
    if not matches:
        return ""
    return " (did you mean " + " or ".join(f"'{match}'" for match in matches) + "?)"
