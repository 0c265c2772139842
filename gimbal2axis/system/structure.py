"""A system of FMUs as the engines need it: components (an FMU, its start values, its OSP model
description if it has one) and connections from an output to an input, on one communication step."""
from __future__ import annotations

import pathlib
import shutil
import zipfile
from dataclasses import dataclass, field


@dataclass
class Component:
    name: str                           # the instance name in the system
    fmu: pathlib.Path
    start_values: dict = field(default_factory=dict)   # variable name -> float, int or bool
    osp_description: pathlib.Path | None = None        # <modelName>_OspModelDescription.xml
    # files the system adds to the FMU's resources folder (name -> bytes): the ship-motion FMU's
    # target table of a scene's moving target
    resources: dict = field(default_factory=dict)


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


def write_fmu(component: Component, path: pathlib.Path) -> None:
    """The component's FMU at `path`, with its added resources (resources/<name>) when it has any."""
    if not component.resources:
        shutil.copyfile(component.fmu, path)
        return
    with zipfile.ZipFile(component.fmu) as original, zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as copy:
        added = {f"resources/{name}" for name in component.resources}
        for item in original.infolist():
            if item.filename not in added:
                copy.writestr(item, original.read(item))
        for name, data in component.resources.items():
            copy.writestr(f"resources/{name}", data)
