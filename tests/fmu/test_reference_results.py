"""The FMU's reference results (FMI-LS-REF, extra/org.fmi-standard.fmi-ls-ref/, made by
scripts/reference_results.py): the manifest as the layered standard asks, every file it lists present
with its checksum, and every experiment replayed through fmpy from the FMU under test, its outputs
within the stated tolerance of the references (and to the bit on this platform, in the release
build that made them)."""
import hashlib
import io
import os
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.ssp.ssd import read_ssv
from fmpy.util import read_csv

EXTRA = "extra/org.fmi-standard.fmi-ls-ref/"
LS = "{http://fmi-standard.org/fmi-ls-manifest}"
ABSOLUTE_TOLERANCE, RELATIVE_TOLERANCE = 1e-6, 1e-6   # as the manifest and documentation/fmi-ls-ref.txt state


@pytest.fixture(scope="module")
def archive(fmu_path):
    with zipfile.ZipFile(fmu_path) as fmu:
        yield {name: fmu.read(name) for name in fmu.namelist() if name.startswith(EXTRA) and not name.endswith("/")}


def test_the_manifest_names_the_layered_standard_and_lists_files_that_are_there(archive):
    manifest = ET.fromstring(archive[EXTRA + "fmi-ls-manifest.xml"])
    assert manifest.tag == "fmiReferences"
    assert manifest.get(LS + "fmi-ls-name") == "org.fmi-standard.fmi-ls-ref"
    assert manifest.get(LS + "fmi-ls-version") == "1.0.0-alpha.1"
    related = manifest.findall("Related")
    roles = {r.get("role") for r in related}
    assert {"experiment/smoke-test", "parameter", "result"} <= roles
    for r in related:
        content = archive[EXTRA + r.get("source")]
        assert r.get("checksumType") == "SHA-256" and hashlib.sha256(content).hexdigest() == r.get("checksum")
        assert r.get("type") and r.get("description")


def experiments(archive):
    root = ET.fromstring(archive[EXTRA + "experiments.xml"])
    return [(e.get("name"), e) for e in root.findall("Experiment")]


def replay(fmu_path, archive, tmp_path, experiment):
    """(outputs of the FMU under test, references) of one experiment, as an importer would run it."""
    parameters = experiment.find("Parameters").get("source")
    (tmp_path / parameters).write_bytes(archive[EXTRA + parameters])
    start_values = {}
    for parameter in read_ssv(str(tmp_path / parameters)).parameters:
        start_values[parameter.name] = parameter.value == "true" if parameter.type == "Boolean" else float(parameter.value)
    stimuli = experiment.find("Stimuli")
    inputs = None
    if stimuli is not None:
        (tmp_path / "in.csv").write_bytes(archive[EXTRA + stimuli.get("source")])
        inputs = read_csv(str(tmp_path / "in.csv"))
    reference = np.genfromtxt(io.BytesIO(archive[EXTRA + experiment.find("References").get("source")]),
                              delimiter=",", names=True, deletechars="")
    step = float(experiment.get("stepSize"))
    result = simulate_fmu(str(fmu_path), fmi_type="CoSimulation", start_time=float(experiment.get("startTime")),
                          stop_time=float(experiment.get("stopTime")), output_interval=step,
                          start_values=start_values, input=inputs,
                          output=[n for n in reference.dtype.names if n != "time"])
    return result, reference


def test_there_are_experiments_for_a_still_and_a_moving_carrier(archive):
    names = [name for name, _ in experiments(archive)]
    assert len(names) >= 3 and "rolling_carrier" in names and "free_swing" in names


@pytest.mark.parametrize("index", range(3))
def test_each_experiment_replays_within_its_tolerance(fmu_path, archive, tmp_path, index):
    name, experiment = experiments(archive)[index]
    result, reference = replay(fmu_path, archive, tmp_path, experiment)
    assert len(result) == len(reference) and np.array_equal(result["time"], reference["time"])
    moved = False
    for column in reference.dtype.names[1:]:
        expected, got = reference[column], result[column]
        allowed = ABSOLUTE_TOLERANCE + RELATIVE_TOLERANCE * np.abs(expected)
        worst = np.max(np.abs(got - expected) - allowed)
        assert worst <= 0, f"{name}: {column} is off by {worst:.3g} beyond the tolerance"
        moved |= np.ptp(expected) > 1e-3
        if os.environ.get("GIMBAL_SANITIZED") != "1":
            assert np.array_equal(got, expected), f"{name}: {column} differs from the reference in the last bits"
    assert moved, f"{name}: nothing moves, the experiment checks nothing"
