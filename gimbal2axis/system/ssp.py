"""A system as an SSP archive (System Structure and Parameterization 1.0, a zip read by FMPy,
libcosim and OMSimulator): SystemStructure.ssd (the components, their connectors, the connections,
the communication step), resources/<FMU>.fmu, and each component's start values as an SSP parameter
set, resources/<component>.ssv (names of the component's variables), bound on the component.

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

from .structure import System, write_fmu

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
# the namespaces the two importers' own annotations are written in (OMSimulator's schema, OSP's)
OMS = "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd"
OSP = "http://opensimulationplatform.com/SSP/OSPAnnotations"
TYPES = {"Real": "<ssc:Real/>", "Integer": "<ssc:Integer/>", "Boolean": "<ssc:Boolean/>",
         "Enumeration": "<ssc:Integer/>"}


def _connectors(fmu: pathlib.Path, used: set) -> str:
    """The FMU's inputs and outputs that a connection uses, as SSD connectors."""
    rows = []
    for variable in read_model_description(str(fmu)).modelVariables:
        if variable.name in used and variable.causality in ("input", "output"):
            rows.append(f'          <ssd:Connector name={quoteattr(variable.name)} kind="{variable.causality}">'
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
           {c.input for c in system.connections if c.target == component.name}
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
