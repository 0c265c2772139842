"""A system of FMUs as the engines need it: components (an FMU, its start values, its OSP model
description if it has one) and connections from an output to an input, on one communication step."""
from __future__ import annotations

import pathlib
import re
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


# The segments of OMSimulator's own path to a component (model.root.<component>): its Python SSP API
# drops from a bound name every segment that is also one of these.
OMSIMULATOR_PATH_SEGMENTS = ("model", "root")


def name_segments(variable: str) -> set:
    """The identifiers a variable's name is made of: `target.position[1]` has target, position and 1."""
    return {segment for segment in re.split(r"[^A-Za-z0-9_]+", variable) if segment}


def naming_conflicts(system: System) -> list[str]:
    """Why a component's name would make an importer lose a bound value, one line each (none: the names
    are safe). OMSimulator's SSP import strips a bound name's first segment when it equals the component's
    name (`controller.kind` set on a component `controller` becomes `kind`), its Python SSP API drops every
    segment equal to the component's name or to model or root, and FMPy picks a component's values by
    `name.startswith(component)`: so no component's name is a segment of any variable of the system's FMUs,
    nor model or root, nor the start of another component's name."""
    from fmpy import read_model_description

    segments = {}
    for component in system.components:
        for variable in read_model_description(str(component.fmu)).modelVariables:
            for segment in name_segments(variable.name):
                segments.setdefault(segment, f"{component.name}'s {variable.name}")
    conflicts = []
    for component in system.components:
        if component.name in OMSIMULATOR_PATH_SEGMENTS:
            conflicts.append(f"component {component.name!r} is a segment of OMSimulator's own path "
                             f"model.root.<component>")
        elif component.name in segments:
            conflicts.append(f"component {component.name!r} is a segment of the variable {segments[component.name]}")
        conflicts += [f"component {component.name!r} starts the name of component {other.name!r}"
                      for other in system.components
                      if other is not component and other.name.startswith(component.name)]
    return conflicts


def check_component_names(system: System) -> None:
    """Refuses (ValueError) component names an importer would confuse with a variable's name."""
    conflicts = naming_conflicts(system)
    if conflicts:
        raise ValueError(f"{system.name}: {conflicts[0]}: an SSP importer would lose bound values "
                         f"({len(conflicts)} conflict(s))")
