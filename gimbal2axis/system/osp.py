"""A system as an OSP system structure (OspSystemStructure.xml, the format libcosim reads): the FMUs and
their OSP model descriptions copied beside it (libcosim looks for <modelName>_OspModelDescription.xml
next to the FMU), start values as InitialValues, the connections by variable group where both
components describe the groups, one by one otherwise."""
from __future__ import annotations

import pathlib
import shutil
import xml.etree.ElementTree as ET
from xml.sax.saxutils import quoteattr

from .structure import System, write_fmu

NAMESPACE = "http://opensimulationplatform.com/MSMI/OSPSystemStructure"


def group_variables(description: pathlib.Path) -> dict:
    """{group name: [variable, ...]} of an OSP model description, nested groups included (by their
    own names) and a port's groups' variables in order under the port's name."""
    groups = {}

    def walk(element) -> list:
        variables = []
        for child in element:
            tag = child.tag.split("}")[-1]
            if tag == "Variable":
                variables.append(child.get("ref"))
            else:
                own = walk(child)
                groups[child.get("name")] = own
                variables += own
        return variables

    root = ET.parse(description).getroot()
    for element in root:
        if element.tag.split("}")[-1] == "VariableGroups":
            walk(element)
    return groups


def _value(value) -> str:
    if isinstance(value, bool):
        return f'<Boolean value="{str(value).lower()}"/>'
    if isinstance(value, int):
        return f'<Integer value="{value}"/>'
    return f'<Real value="{float(value)!r}"/>'


def initial_values(component) -> dict:
    """The component's start values libcosim can set. libcosim ignores FMI 2.0 Enumeration variables
    (the gimbal's structural selectors gear<j>.model, motor<j>.model, solver.method): one at its start
    value is left out, another value refused, since libcosim would run the FMU's default silently."""
    from fmpy import read_model_description

    variables = {v.name: v for v in read_model_description(str(component.fmu)).modelVariables}
    values = {}
    for name, value in component.start_values.items():
        variable = variables.get(name)
        if variable is not None and variable.type == "Enumeration":
            if int(value) != int(variable.start):
                raise ValueError(f"{component.name}: {name} = {value} cannot be set in libcosim, which ignores FMI 2.0 "
                                 f"Enumeration variables (its start value {variable.start} would run instead)")
            continue
        values[name] = value
    return values


def write_osp(system: System, out: pathlib.Path) -> pathlib.Path:
    """Writes <out>/OspSystemStructure.xml with the FMUs and descriptions beside it; its path."""
    out.mkdir(parents=True, exist_ok=True)
    simulators, grouped = [], set()
    for component in system.components:
        write_fmu(component, out / component.fmu.name)
        if component.osp_description is not None:
            shutil.copyfile(component.osp_description, out / component.osp_description.name)
        values = "".join(f"\n                <InitialValue variable={quoteattr(name)}>{_value(value)}</InitialValue>"
                         for name, value in initial_values(component).items())
        simulators.append(f'        <Simulator name={quoteattr(component.name)} source={quoteattr(component.fmu.name)} '
                          f'stepSize="{system.step!r}">\n            <InitialValues>{values}\n'
                          f'            </InitialValues>\n        </Simulator>')
    connections = []
    for source, source_group, target, target_group in system.groups:
        outputs = group_variables(system.component(source).osp_description)[source_group]
        inputs = group_variables(system.component(target).osp_description)[target_group]
        pairs = {(source, o, target, i) for o, i in zip(outputs, inputs)}
        missing = pairs - {(c.source, c.output, c.target, c.input) for c in system.connections}
        if len(outputs) != len(inputs) or missing:
            raise ValueError(f"{source}.{source_group} -> {target}.{target_group} connects what the system does not: "
                             f"{sorted(missing)[:3]}")
        grouped |= pairs
        connections.append(f'        <VariableGroupConnection>\n'
                           f'            <VariableGroup simulator={quoteattr(source)} name={quoteattr(source_group)}/>\n'
                           f'            <VariableGroup simulator={quoteattr(target)} name={quoteattr(target_group)}/>\n'
                           f'        </VariableGroupConnection>')
    for c in system.connections:
        if (c.source, c.output, c.target, c.input) in grouped:
            continue
        connections.append(f'        <VariableConnection>\n'
                           f'            <Variable simulator={quoteattr(c.source)} name={quoteattr(c.output)}/>\n'
                           f'            <Variable simulator={quoteattr(c.target)} name={quoteattr(c.input)}/>\n'
                           f'        </VariableConnection>')
    path = out / "OspSystemStructure.xml"
    path.write_text(f'<?xml version="1.0" encoding="utf-8"?>\n<OspSystemStructure xmlns="{NAMESPACE}" version="0.1">\n'
                    f'    <StartTime>0.0</StartTime>\n    <BaseStepSize>{system.step!r}</BaseStepSize>\n'
                    f'    <Algorithm>fixedStep</Algorithm>\n    <Simulators>\n' + "\n".join(simulators) +
                    '\n    </Simulators>\n    <Connections>\n' + "\n".join(connections) +
                    '\n    </Connections>\n</OspSystemStructure>\n')
    return path
