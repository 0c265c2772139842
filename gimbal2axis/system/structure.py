"""A system of FMUs as the engines need it: components (an FMU, its start values, its OSP model
description if it has one) and connections from an output to an input, on one communication step."""
from __future__ import annotations

import pathlib
from dataclasses import dataclass, field


@dataclass
class Component:
    name: str                           # the instance name in the system
    fmu: pathlib.Path
    start_values: dict = field(default_factory=dict)   # variable name -> float, int or bool
    osp_description: pathlib.Path | None = None        # <modelName>_OspModelDescription.xml


@dataclass(frozen=True)
class Connection:
    source: str            # component name
    output: str            # its output variable
    target: str
    input: str


@dataclass
class System:
    name: str
    step: float            # the communication step, s
    stop_time: float       # s
    components: list
    connections: list
    # (source, group, target, group): connections of OSP variable groups; each group's variables are
    # connected one by one in `connections` too, for the engines that know no groups
    groups: list = field(default_factory=list)

    def component(self, name: str) -> Component:
        return next(c for c in self.components if c.name == name)
