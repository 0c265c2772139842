"""A system as an SSP archive (System Structure and Parameterization 1.0, a zip read by FMPy,
libcosim and OMSimulator): SystemStructure.ssd (the components, their connectors, the connections,
the communication step), resources/<FMU>.fmu, and each component's start values as an SSP parameter
set, resources/<component>.ssv (names of the component's variables, as SSP 1.0 names a set bound on a
component), bound on the component; every bound variable is declared as a connector of the component
too. The component names are checked against every variable's name first (structure.naming_conflicts):
an importer that strips a component's name from a bound name would otherwise lose values.

SSP 1.0 has no attribute for the communication step: the importers read it from their own
annotations, which the SSD carries both of. OMSimulator's (`org.openmodelica`, on the system) also
tells it the system's type: a fixed-step master over co-simulation FMUs ("weakly coupled"); without
it OMSimulator cannot import the system at all. libcosim's (`com.opensimulationplatform`, on the
DefaultExperiment) is the fixed-step algorithm and its base step. Parameter sets are bound on each
component, not once on the system, because libcosim applies only a component's own bindings."""
from __future__ import annotations

import pathlib
import tempfile
import zipfile
from xml.sax.saxutils import quoteattr

from fmpy import read_model_description

from .structure import System, check_component_names, write_fmu

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
# the namespaces the two importers' own annotations are written in (OMSimulator's schema, OSP's)
OMS = "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd"
OSP = "http://opensimulationplatform.com/SSP/OSPAnnotations"
TYPES = {"Real": "<ssc:Real/>", "Integer": "<ssc:Integer/>", "Boolean": "<ssc:Boolean/>",
         "Enumeration": "<ssc:Integer/>"}


# SSD connector kinds of the FMU causalities a connection or a binding uses
KINDS = {"input": "input", "output": "output", "parameter": "parameter", "calculatedParameter": "calculatedParameter"}


def _connectors(fmu: pathlib.Path, used: set) -> str:
    """The FMU's variables that a connection or a binding uses, as SSD connectors. A bound variable is a
    connector too: OMSimulator's Python SSP API looks a bound name up among the component's connectors
    by its whole name before it falls back on splitting it into segments (docs/systems.md)."""
    rows = []
    for variable in read_model_description(str(fmu)).modelVariables:
        if variable.name in used and variable.causality in KINDS:
            rows.append(f'          <ssd:Connector name={quoteattr(variable.name)} kind="{KINDS[variable.causality]}">'
                        f'{TYPES[variable.type]}</ssd:Connector>')
    return "\n".join(rows)


def _parameter(name: str, value) -> str:
    if isinstance(value, bool):
        element = f'<ssv:Boolean value="{str(value).lower()}"/>'
    elif isinstance(value, int):
        element = f'<ssv:Integer value="{value}"/>'
    else:
        element = f'<ssv:Real value="{float(value)!r}"/>'
    return f'    <ssv:Parameter name={quoteattr(name)}>{element}</ssv:Parameter>'


def parameter_set(name: str, start_values: dict) -> str:
    """One component's start values as an SSV parameter set (names relative to the component)."""
    rows = [_parameter(variable, value) for variable, value in start_values.items()]
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n<ssv:ParameterSet xmlns:ssv="{SSV}" version="1.0" '
            f'name={quoteattr(name)}>\n  <ssv:Parameters>\n' + "\n".join(rows) + "\n  </ssv:Parameters>\n</ssv:ParameterSet>\n")


def read_parameter_set(text: bytes | str) -> dict:
    """An SSV parameter set's values by name (float, int or bool): what parameter_set wrote."""
    import xml.etree.ElementTree as ET

    values = {}
    for parameter in ET.fromstring(text).iter(f"{{{SSV}}}Parameter"):
        for element in parameter:
            kind, value = element.tag.split("}")[-1], element.get("value")
            parse = {"Real": float, "Integer": int}.get(kind, lambda text: text in ("true", "1"))
            values[parameter.get("name")] = parse(value)
    return values


def archive_parameters(archive: pathlib.Path) -> dict:
    """{component: {variable: value}} of the parameter sets an archive binds on its components."""
    import xml.etree.ElementTree as ET

    with zipfile.ZipFile(archive) as contents:
        root = ET.fromstring(contents.read("SystemStructure.ssd"))
        bound = {}
        for component in root.iter(f"{{{SSD}}}Component"):
            values = bound.setdefault(component.get("name"), {})
            for binding in component.iter(f"{{{SSD}}}ParameterBinding"):
                values.update(read_parameter_set(contents.read(binding.get("source"))))
    return bound


def parameter_file(component_name: str) -> str:
    """Where a component's parameter set is in the archive."""
    return f"resources/{component_name}.ssv"


def _system_annotations(step: float) -> str:
    """OMSimulator's: a fixed-step master ("oms-ma") with the communication step, which makes the system a
    co-simulation ("weakly coupled") one. The master reads a missing relativeTolerance as 0; the value
    written is OMSimulator's own default (it is not the FMUs' tolerance, which their parameters set)."""
    return ('    <ssd:Annotations>\n      <ssc:Annotation type="org.openmodelica">\n        <oms:Annotations>\n'
            '          <oms:SimulationInformation>\n'
            f'            <oms:FixedStepMaster description="oms-ma" stepSize="{step!r}" relativeTolerance="0.0001"/>\n'
            '          </oms:SimulationInformation>\n        </oms:Annotations>\n      </ssc:Annotation>\n'
            '    </ssd:Annotations>\n')


def _default_experiment(system: System) -> str:
    """Start and stop time, and libcosim's fixed-step algorithm with the communication step."""
    return (f'  <ssd:DefaultExperiment startTime="0.0" stopTime="{system.stop_time!r}">\n    <ssd:Annotations>\n'
            '      <ssc:Annotation type="com.opensimulationplatform">\n        <osp:Algorithm>\n'
            f'          <osp:FixedStepAlgorithm baseStepSize="{system.step!r}"/>\n'
            '        </osp:Algorithm>\n      </ssc:Annotation>\n    </ssd:Annotations>\n  </ssd:DefaultExperiment>\n')


def _component(system: System, component) -> str:
    used = {c.output for c in system.connections if c.source == component.name} | \
           {c.input for c in system.connections if c.target == component.name} | set(component.start_values)
    bindings = ""
    if component.start_values:
        bindings = ('        <ssd:ParameterBindings>\n'
                    f'          <ssd:ParameterBinding source={quoteattr(parameter_file(component.name))}/>\n'
                    '        </ssd:ParameterBindings>\n')
    return (f'      <ssd:Component name={quoteattr(component.name)} type="application/x-fmu-sharedlibrary" '
            f'source={quoteattr("resources/" + component.fmu.name)}>\n        <ssd:Connectors>\n'
            f'{_connectors(component.fmu, used)}\n        </ssd:Connectors>\n{bindings}      </ssd:Component>')


def system_structure(system: System) -> str:
    """SystemStructure.ssd."""
    connections = [f'      <ssd:Connection startElement={quoteattr(c.source)} startConnector={quoteattr(c.output)} '
                   f'endElement={quoteattr(c.target)} endConnector={quoteattr(c.input)}/>' for c in system.connections]
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n<ssd:SystemStructureDescription xmlns:ssd="{SSD}" '
            f'xmlns:ssc="{SSC}" xmlns:oms="{OMS}" xmlns:osp="{OSP}" version="1.0" name={quoteattr(system.name)}>\n'
            f'  <ssd:System name={quoteattr(system.name)}>\n    <ssd:Elements>\n' +
            "\n".join(_component(system, component) for component in system.components) +
            '\n    </ssd:Elements>\n    <ssd:Connections>\n' + "\n".join(connections) +
            '\n    </ssd:Connections>\n' + _system_annotations(system.step) + '  </ssd:System>\n' +
            _default_experiment(system) + '</ssd:SystemStructureDescription>\n')


def write_ssp(system: System, path: pathlib.Path) -> pathlib.Path:
    """Writes the archive at `path`; its path. A component name an importer would confuse with a
    segment of a bound name is refused (ValueError) before anything is written."""
    check_component_names(system)
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("SystemStructure.ssd", system_structure(system))
        for component in system.components:
            if component.start_values:
                archive.writestr(parameter_file(component.name),
                                 parameter_set(f"{system.name}.{component.name}", component.start_values))
            if component.resources:
                with tempfile.TemporaryDirectory() as folder:
                    fmu = pathlib.Path(folder) / component.fmu.name
                    write_fmu(component, fmu)
                    archive.write(fmu, f"resources/{component.fmu.name}")
            else:
                archive.write(component.fmu, f"resources/{component.fmu.name}")
    return path
