"""A system as an SSP archive (System Structure and Parameterization 1.0, a zip read by FMPy,
libcosim and OMSimulator): SystemStructure.ssd (the components, their connectors, the connections),
resources/<FMU>.fmu, and the start values as an SSP parameter set, resources/parameters.ssv, whose
names are <component>.<variable> (bound to the system)."""
from __future__ import annotations

import pathlib
import zipfile
from xml.sax.saxutils import quoteattr

from fmpy import read_model_description

from .structure import System

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
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


def parameter_set(system: System) -> str:
    rows = [_parameter(f"{c.name}.{name}", value) for c in system.components for name, value in c.start_values.items()]
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n<ssv:ParameterSet xmlns:ssv="{SSV}" version="1.0" '
            f'name={quoteattr(system.name)}>\n  <ssv:Parameters>\n' + "\n".join(rows) + "\n  </ssv:Parameters>\n</ssv:ParameterSet>\n")


def write_ssp(system: System, path: pathlib.Path) -> pathlib.Path:
    elements = []
    for component in system.components:
        used = {c.output for c in system.connections if c.source == component.name} | \
               {c.input for c in system.connections if c.target == component.name}
        elements.append(f'      <ssd:Component name={quoteattr(component.name)} type="application/x-fmu-sharedlibrary" '
                        f'source={quoteattr("resources/" + component.fmu.name)}>\n        <ssd:Connectors>\n'
                        f'{_connectors(component.fmu, used)}\n        </ssd:Connectors>\n      </ssd:Component>')
    connections = [f'      <ssd:Connection startElement={quoteattr(c.source)} startConnector={quoteattr(c.output)} '
                   f'endElement={quoteattr(c.target)} endConnector={quoteattr(c.input)}/>' for c in system.connections]
    ssd = (f'<?xml version="1.0" encoding="UTF-8"?>\n<ssd:SystemStructureDescription xmlns:ssd="{SSD}" '
           f'xmlns:ssc="{SSC}" version="1.0" name={quoteattr(system.name)}>\n  <ssd:System name={quoteattr(system.name)}>\n'
           f'    <ssd:ParameterBindings>\n      <ssd:ParameterBinding source="resources/parameters.ssv"/>\n'
           f'    </ssd:ParameterBindings>\n    <ssd:Elements>\n' + "\n".join(elements) +
           '\n    </ssd:Elements>\n    <ssd:Connections>\n' + "\n".join(connections) +
           f'\n    </ssd:Connections>\n  </ssd:System>\n  <ssd:DefaultExperiment startTime="0.0" '
           f'stopTime="{system.stop_time!r}"/>\n</ssd:SystemStructureDescription>\n')
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("SystemStructure.ssd", ssd)
        archive.writestr("resources/parameters.ssv", parameter_set(system))
        for component in system.components:
            archive.write(component.fmu, f"resources/{component.fmu.name}")
    return path
