"""The model's counts as its declarations give them (model_core/include/gimbal/*.def), for the tests to check
the FMU's model description and headers against instead of numbers copied into each test: a state, a
switching element or an instance more changes them here, and every test that compares follows."""
from __future__ import annotations

import pathlib
import re

GIMBAL = pathlib.Path(__file__).resolve().parents[2] / "model_core" / "include" / "gimbal"


def continuous_states() -> int:
    """The continuous states: every state is declared with its derivative, a Real variable der_<state>."""
    return len(re.findall(r"^X\(der_\w+,", (GIMBAL / "real_variables.def").read_text(), re.MULTILINE))


def elements() -> list[tuple[str, int, int]]:
    """The switching elements' ELEMENT rows: (identifier, instances, guards per instance), in order."""
    rows = re.findall(r"^ELEMENT\((\w+), (\d+), (\d+),", (GIMBAL / "switching_elements.def").read_text(), re.MULTILINE)
    return [(name, int(instances), int(guards)) for name, instances, guards in rows]


def event_indicators() -> int:
    """Every switching element's guards (Model Exchange's event indicators)."""
    return sum(instances * guards for _, instances, guards in elements())


def real_units() -> list[str]:
    """The unit of every Real variable, in real_variables.def's order."""
    return re.findall(r'^X\(\w+, "[^"]*", \w+, \w+, \w+, "[^"]*", "([^"]*)",', (GIMBAL / "real_variables.def").read_text(),
                      re.MULTILINE)


def axis_stops() -> list[dict[str, str]]:
    """The AXIS_STOP rows of switching_elements.def: each axis stop's element and its variables' identifiers
    (lower, upper, restitution, rest_rate, contact)."""
    text = (GIMBAL / "switching_elements.def").read_text()
    rows = re.findall(r"^AXIS_STOP\((\w+),\s*(\w+),\s*(\w+),\s*(\w+),\s*(\w+),\s*(\w+),\s*(\w+)\)", text, re.MULTILINE)
    keys = ("element", "coordinate", "lower", "upper", "restitution", "rest_rate", "contact")
    return [dict(zip(keys, row)) for row in rows]


def real_name(identifier: str) -> str:
    """A Real variable's FMI name from its identifier in real_variables.def."""
    match = re.search(rf'^X\({identifier}, "([^"]*)"', (GIMBAL / "real_variables.def").read_text(), re.MULTILINE)
    return match.group(1)


def indicators_of(element: str) -> range:
    """The event indicators (from 0) of one element kind's instances."""
    first = 0
    for name, instances, guards in elements():
        if name == element:
            return range(first, first + instances * guards)
        first += instances * guards
    raise KeyError(element)
