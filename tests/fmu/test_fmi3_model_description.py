"""The FMI 3.0 model description (build/fmi3/modelDescription.xml, from the same variable tables as
FMI 2.0's): valid against the FMI 3.0 schema and fmpy's checks, and the same variables under the
value-reference rule of docs/fmi_interfaces.md (Real as in FMI 2.0, Integer 1000 +, Boolean 2000 +;
time at 3001; the event indicators, every switching element's guards as declared once in
model_core/include/gimbal/switching_elements.def, scalar Float64 locals from 3002 on), and no array variable."""
from __future__ import annotations


import pathlib
import shutil
import subprocess

import fmpy
import pytest
from fmpy import read_model_description

from support import declared_counts

REPO = pathlib.Path(__file__).resolve().parents[2]

BASE = {"Real": 0, "Integer": 1000, "Enumeration": 1000, "Boolean": 2000}
FMI3_TYPE = {"Real": "Float64", "Integer": "Int32", "Enumeration": "Enumeration", "Boolean": "Boolean"}


@pytest.fixture(scope="module")
def descriptions(build_dir):
    path = build_dir / "fmi3" / "modelDescription.xml"
    assert path.is_file(), f"{path} is missing: the build did not generate it"
    return read_model_description(str(build_dir / "fmu_staging" / "modelDescription.xml")), \
        read_model_description(str(path), validate=True), path


def test_it_is_valid_against_the_fmi_3_schema(descriptions):
    _, _, path = descriptions
    xmllint = shutil.which("xmllint")
    assert xmllint, "xmllint is missing: scripts/setup.sh installs libxml2-utils"
    schema = pathlib.Path(fmpy.__file__).parent / "schema" / "fmi3" / "fmi3ModelDescription.xsd"
    done = subprocess.run([xmllint, "--noout", "--schema", str(schema), str(path)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]


def test_the_same_variables_under_the_value_reference_rule(descriptions):
    fmi2, fmi3, _ = descriptions
    assert fmi3.fmiVersion == "3.0" and fmi3.instantiationToken == fmi2.guid
    by_name = {v.name: v for v in fmi3.modelVariables}
    assert by_name["time"].causality == "independent" and by_name["time"].valueReference == 3001
    for v in fmi2.modelVariables:
        w = by_name[v.name]
        assert w.type == FMI3_TYPE[v.type], v.name
        assert w.valueReference == BASE[v.type] + v.valueReference, v.name
        assert (w.causality, w.variability, w.initial) == (v.causality, v.variability, v.initial), v.name
        assert w.unit == v.unit and w.displayUnit == v.displayUnit and w.description == v.description, v.name
        assert (w.start is None) == (v.start is None), v.name
        if v.start is not None and v.type == "Real":
            assert float(w.start) == float(v.start), v.name
        if v.type == "Enumeration":
            assert w.declaredType.name == v.declaredType.name
            assert [(i.name, i.value) for i in w.declaredType.items] == [(i.name, i.value) for i in v.declaredType.items]
    # time and the event indicators
    assert len(fmi3.modelVariables) == len(fmi2.modelVariables) + 1 + fmi2.numberOfEventIndicators


def test_no_variable_is_an_array(descriptions):
    """A host without array support (ecos: tests/fmu/test_fmi3.py) reads every variable as one value: the
    FMU has none with a <Dimension>, the event indicators included (docs/fmi_interfaces.md)."""
    _, fmi3, path = descriptions
    assert [v.name for v in fmi3.modelVariables if v.dimensions] == []
    assert "<Dimension" not in path.read_text()


def test_states_indicators_and_dependencies_are_fmi_2s(descriptions):
    fmi2, fmi3, _ = descriptions
    assert [d.variable.name for d in fmi3.derivatives] == [d.variable.name for d in fmi2.derivatives]
    assert [d.variable.derivative.name for d in fmi3.derivatives] == [d.variable.derivative.name for d in fmi2.derivatives]
    assert fmi3.numberOfContinuousStates == fmi2.numberOfContinuousStates == declared_counts.continuous_states()
    count = declared_counts.event_indicators()
    assert fmi3.numberOfEventIndicators == fmi2.numberOfEventIndicators == count >= 36
    assert [e.variable.name for e in fmi3.eventIndicators] == [f"event_indicators[{k}]" for k in range(1, count + 1)]
    assert [e.variable.valueReference for e in fmi3.eventIndicators] == list(range(3002, 3002 + count))
    assert {(e.variable.causality, e.variable.variability) for e in fmi3.eventIndicators} == {("local", "continuous")}
    for mine, theirs in ((fmi3.outputs, fmi2.outputs), (fmi3.derivatives, fmi2.derivatives)):
        assert [u.variable.name for u in mine] == [u.variable.name for u in theirs]
        for a, b in zip(mine, theirs):
            assert [v.name for v in a.dependencies] == [v.name for v in b.dependencies], a.variable.name
    # (fmpy 0.3.32 reads FMI 2.0's attribute name, providesDirectionalDerivative, for 3.0 too: read the XML.)
    import xml.etree.ElementTree as ElementTree

    root = ElementTree.parse(descriptions[2]).getroot()
    for interface in ("ModelExchange", "CoSimulation"):
        attributes = root.find(interface).attrib
        assert attributes["providesDirectionalDerivatives"] == "true" and attributes["canSerializeFMUState"] == "true"
    assert fmi3.coSimulation.hasEventMode
