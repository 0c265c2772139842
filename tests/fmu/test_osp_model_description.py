"""The gimbal FMU's OSP model description (systems/Gimbal2Axis_OspModelDescription.xml, copied beside
the FMU by the build): every variable it names is the FMU's, with the FMU's unit, in a group whose
kind fits it (OSP-IS: displacements in rad or m, velocities in rad/s or m/s, ...), and the causalities
of a group agree (a port's voltage and current opposite)."""
import pathlib
import xml.etree.ElementTree as ET

import pytest

from gimbal2axis import FMU

REPO = pathlib.Path(__file__).resolve().parents[2]
SOURCE = REPO / "systems" / "Gimbal2Axis_OspModelDescription.xml"
NS = {"osp": "https://open-simulation-platform.com/OspModelDescription/1.0.1"}
UNITS = {"AngularDisplacement": {"rad"}, "AngularVelocity": {"rad/s"}, "AngularAcceleration": {"rad/s2"},
         "LinearDisplacement": {"m"}, "LinearVelocity": {"m/s"}, "LinearAcceleration": {"m/s2"},
         "Voltage": {"V"}, "Current": {"A"}}


def groups(element, parent=None):
    """(kind, name, parent kind, [(ref, unit)]) of every group, nested ones too."""
    found = []
    for group in element:
        kind = group.tag.split("}")[1]
        variables = [(v.get("ref"), v.get("unit")) for v in group.findall("osp:Variable", NS)]
        found.append((kind, group.get("name"), parent, variables))
        found += groups([g for g in group if g.tag.split("}")[1] != "Variable"], kind)
    return found


@pytest.fixture(scope="module")
def description():
    root = ET.parse(SOURCE).getroot()
    return groups(root.find("osp:VariableGroups", NS))


def test_every_reference_is_a_variable_of_the_fmu_with_its_unit(description, gimbal_fmu):
    assert len(description) >= 10
    for kind, name, _, variables in description:
        for ref, unit in variables:
            variable = gimbal_fmu.variables.get(ref)
            assert variable is not None, f"{name}: {ref} is not a variable of the FMU"
            declared = variable.declaredType.unit if getattr(variable, "declaredType", None) else None
            assert unit == (variable.unit or declared), (name, ref, unit, variable.unit)
            assert unit in UNITS[kind], f"{kind} {name}: {ref} in {unit}"


def test_the_groups_hold_one_causality_and_a_port_two_opposite_ones(description, gimbal_fmu):
    names = [name for _, name, _, _ in description]
    assert len(names) == len(set(names)), "group names must be unique"
    for kind, name, parent, variables in description:
        causalities = {gimbal_fmu.variables[ref].causality for ref, _ in variables}
        assert len(causalities) <= 1, f"{name} mixes {causalities}"
    ports = [(name, [g for g in description if g[2] == "ElectromagneticPort" and g[1].startswith(name)])
             for kind, name, _, _ in description if kind == "ElectromagneticPort"]
    assert len(ports) == 2
    for name, (voltage, current) in ports:
        assert gimbal_fmu.variables[voltage[3][0][0]].causality == "input"
        assert gimbal_fmu.variables[current[3][0][0]].causality == "output"
    # the carrier's motion: every base input of the FMU is in a group
    grouped = {ref for _, _, _, variables in description for ref, _ in variables}
    base_inputs = {n for n, v in gimbal_fmu.variables.items() if v.causality == "input" and n.startswith("base.")}
    assert base_inputs and base_inputs <= grouped


def test_the_build_puts_it_beside_the_fmu(fmu_path):
    beside = fmu_path.parent / "Gimbal2Axis_OspModelDescription.xml"
    assert beside.read_bytes() == SOURCE.read_bytes()
