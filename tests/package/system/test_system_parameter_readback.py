"""Every value the system binds reaches its FMU, in each engine the tests have (libcosim on the OSP
structure, libcosim's SSP loader, FMPy's SSP support): the engines read each one back after
instantiation and refuse a run that lost one, naming the component and the variable. And the
archive's component names are none an importer confuses with a segment of a bound name: OMSimulator's
oms_importFile turned `controller.kind` bound on a component `controller` into `kind` and ran the
controller with zero gains while reporting success (docs/systems.md)."""
import dataclasses
import pathlib
import re
import xml.etree.ElementTree as ET
import zipfile

import pytest
from fmpy import read_model_description

from gimbal2axis import load_scene
from gimbal2axis.system.engines import ParameterNotApplied, run_fmpy_ssp, run_libcosim, run_libcosim_ssp
from gimbal2axis.system.from_scene import CONTROLLER, GIMBAL, ship_system
from gimbal2axis.system.osp import initial_values, write_osp
from gimbal2axis.system.ssp import SSV, parameter_file, write_ssp
from gimbal2axis.system.structure import naming_conflicts

pytest.importorskip("libcosimpy")
REPO = pathlib.Path(__file__).resolve().parents[3]
STOP = 0.004


@pytest.fixture(scope="module")
def system(build_dir):
    return ship_system(load_scene(REPO / "scenes" / "track_coastal_point.toml"), build_dir, stop_time=STOP)


def libcosim_values(system) -> dict:
    """What libcosim can be given: the system's values less the Enumerations at their start (osp.py)."""
    return {component.name: initial_values(component) for component in system.components}


def test_no_component_name_is_a_segment_of_any_variable_of_the_systems_fmus(system):
    assert naming_conflicts(system) == []
    segments = set()
    for component in system.components:
        for variable in read_model_description(str(component.fmu)).modelVariables:
            segments |= set(re.split(r"[^A-Za-z0-9_]+", variable.name))
            assert not variable.name.startswith(component.name + ".")
    assert {component.name for component in system.components}.isdisjoint(segments | {"model", "root"})
    assert "controller" in segments   # the old name: the controller FMU has controller.kind


def test_an_archive_whose_component_name_is_a_segment_of_a_variable_is_refused(system, tmp_path):
    renamed = dataclasses.replace(system, components=[dataclasses.replace(c, name="controller") if c.name == CONTROLLER
                                                      else c for c in system.components])
    with pytest.raises(ValueError, match="component 'controller' is a segment of the variable controller's "
                                         "controller"):
        write_ssp(renamed, tmp_path / "old_names.ssp")
    assert not (tmp_path / "old_names.ssp").exists()


def test_every_bound_value_is_declared_as_a_connector_of_its_component(system, tmp_path):
    archive = write_ssp(system, tmp_path / "ship.ssp")
    ssd = "{http://ssp-standard.org/SSP1/SystemStructureDescription}"
    root = ET.fromstring(zipfile.ZipFile(archive).read("SystemStructure.ssd"))
    for element in root.iter(f"{ssd}Component"):
        connectors = {c.get("name") for c in element.iter(f"{ssd}Connector")}
        assert set(system.component(element.get("name")).start_values) <= connectors


def test_every_value_of_the_scene_reaches_the_fmu_in_each_engine(system, tmp_path):
    """The system's own values (not the archive's, which could have lost one) are read back."""
    structure = write_osp(system, tmp_path / "osp")
    archive = write_ssp(system, tmp_path / "ship.ssp")
    everything = {component.name: dict(component.start_values) for component in system.components}
    assert sum(len(values) for values in everything.values()) > 50
    run_libcosim(structure, GIMBAL, ["alpha"], 2, intended=libcosim_values(system))
    run_libcosim_ssp(archive, GIMBAL, ["alpha"], 2, intended=libcosim_values(system))
    run_fmpy_ssp(archive, GIMBAL, ["alpha"], system.step, STOP, intended=everything)


def strip_as_omsimulator(archive: pathlib.Path, component: str, segment: str, out: pathlib.Path) -> pathlib.Path:
    """The archive with the component's bound names resolved as OMSimulator resolves them on a
    component named `segment`: a first segment equal to that name is dropped (controller.kind -> kind)."""
    resource = parameter_file(component)
    with zipfile.ZipFile(archive) as original, zipfile.ZipFile(out, "w") as copy:
        for item in original.infolist():
            data = original.read(item)
            if item.filename == resource:
                data = re.sub(rf'name="{segment}\.', 'name="', data.decode()).encode()
            copy.writestr(item, data)
    return out


def test_a_binding_resolved_to_another_name_is_refused_by_each_ssp_engine(system, tmp_path):
    archive = write_ssp(system, tmp_path / "ship.ssp")
    stripped = strip_as_omsimulator(archive, CONTROLLER, "controller", tmp_path / "stripped.ssp")
    parameters = ET.fromstring(zipfile.ZipFile(stripped).read(parameter_file(CONTROLLER)))
    assert "kind" in {p.get("name") for p in parameters.iter(f"{{{SSV}}}Parameter")}
    with pytest.raises(ParameterNotApplied, match=rf"{CONTROLLER}: the bound value kind = "):
        run_libcosim_ssp(stripped, GIMBAL, ["alpha"], 2)
    with pytest.raises(ParameterNotApplied, match=rf"{CONTROLLER}: the bound value kind = "):
        run_fmpy_ssp(stripped, GIMBAL, ["alpha"], system.step, STOP)


def a_value_off_the_fmus_default(component) -> str:
    """A variable the component binds to something else than its FMU's start value."""
    starts = {v.name: v.start for v in read_model_description(str(component.fmu)).modelVariables}
    return next(name for name, value in initial_values(component).items()
                if not isinstance(value, bool) and float(value) != float(starts[name]))


def test_a_lost_binding_is_refused_with_the_component_and_the_variable(system, tmp_path):
    """A value the archive (or the structure) dropped: the engine runs the FMU's default, and the
    read-back against the system's values says which."""
    name = a_value_off_the_fmus_default(system.component(CONTROLLER))
    archive = write_ssp(system, tmp_path / "ship.ssp")
    resource = parameter_file(CONTROLLER)
    lost = tmp_path / "lost.ssp"
    with zipfile.ZipFile(archive) as original, zipfile.ZipFile(lost, "w") as copy:
        for item in original.infolist():
            data = original.read(item)
            if item.filename == resource:
                text = data.decode()
                data = re.sub(rf'\s*<ssv:Parameter name="{re.escape(name)}">.*?</ssv:Parameter>', "", text).encode()
                assert len(data) < len(text)
            copy.writestr(item, data)
    intended = libcosim_values(system)
    with pytest.raises(ParameterNotApplied, match=rf"{CONTROLLER}: {re.escape(name)} is .* but the system binds"):
        run_libcosim_ssp(lost, GIMBAL, ["alpha"], 2, intended=intended)
    structure = write_osp(system, tmp_path / "osp")
    text = structure.read_text()
    cut = re.sub(rf'\s*<InitialValue variable="{re.escape(name)}">.*?</InitialValue>', "", text)
    assert cut != text
    structure.write_text(cut)
    with pytest.raises(ParameterNotApplied, match=rf"{CONTROLLER}: {re.escape(name)} is .* but the system binds"):
        run_libcosim(structure, GIMBAL, ["alpha"], 2, intended=intended)
