"""modelDescription.xml as importers read it: Enumeration types for the structural selectors, display
units, the default experiment, the header (author, licence, version, tool, date), and one version
number across CMake, the Python package, the FMU, the README and the changelog."""
import datetime
import importlib.metadata
import math
import os
import pathlib
import re
import shutil
import subprocess
import tomllib
import zipfile

import pytest

from support import declared_counts

REPO = pathlib.Path(__file__).resolve().parents[2]

ENUMERATIONS = {  # name: (declared type, value reference, item names by value)
    "gear1.model": ("GearModel", 20, ["rigid", "compliant", "backlash"]),
    "gear2.model": ("GearModel", 21, ["rigid", "compliant", "backlash"]),
    "motor1.model": ("MotorModel", 22, ["quasi_static", "inductive"]),
    "motor2.model": ("MotorModel", 23, ["quasi_static", "inductive"]),
    "solver.method": ("IntegrationMethod", 24, ["cvode_bdf", "cvode_bdf_dq", "cvode_adams", "arkode_erk", "automatic",
                                                "dormand_prince", "rodas4", "real_time"]),
    "motor1.drive": ("DriveMode", 32, ["voltage", "current"]),
    "motor2.drive": ("DriveMode", 33, ["voltage", "current"]),
}
DISPLAY_UNITS = {"rad": "deg", "rad/s": "deg/s", "rad/s2": "deg/s2"}


def cmake_version() -> str:
    match = re.search(r"project\(\s*Gimbal2Axis\s+VERSION\s+([0-9]+\.[0-9]+\.[0-9]+)", (REPO / "CMakeLists.txt").read_text())
    assert match, "CMakeLists.txt: project(Gimbal2Axis VERSION x.y.z ...) not found"
    return match.group(1)


@pytest.fixture(scope="module")
def md(gimbal_fmu):
    return gimbal_fmu.model_description


@pytest.fixture(scope="module")
def by_name(md):
    return {v.name: v for v in md.modelVariables}


# --- types -------------------------------------------------------------------------------------

def test_selectors_are_enumerations_with_named_items(md, by_name):
    types = {t.name: t for t in md.typeDefinitions}
    for name, (declared, vr, items) in ENUMERATIONS.items():
        v = by_name[name]
        assert v.type == "Enumeration", name
        assert v.valueReference == vr, f"{name}: the value reference users set with fmi2SetInteger moved"
        assert v.declaredType is types[declared]
        assert [(item.name, int(item.value)) for item in v.declaredType.items] == list(zip(items, range(len(items))))
        assert all(item.description for item in v.declaredType.items)
        assert int(v.start) in range(len(items))
    assert len(types) == 5  # and GearStart, of gear1.start and gear2.start: tests/model_core/model/test_relaxed_start.py


def test_other_discrete_variables_keep_their_types(by_name):
    for name in ("solver.max_steps", "gear1.contact", "motor2.limited", "body1.stick_slip", "events.total",
                 "solver.steps", "solver.method_switches"):
        assert by_name[name].type == "Integer", name
    for name in ("energy_accounting", "dry_friction", "base.fixed"):
        assert by_name[name].type == "Boolean", name


def test_enumerations_are_set_and_read_as_integers(gimbal_fmu):
    """In FMI 2.0 an Enumeration goes through fmi2SetInteger/fmi2GetInteger, by its value reference."""
    slave = gimbal_fmu.instantiate("enumerations")
    try:
        slave.setupExperiment(startTime=0.0)
        vrs = [vr for _, vr, _ in ENUMERATIONS.values()]
        slave.setInteger(vrs, [0, 1, 0, 1, 6, 0, 0])
        slave.enterInitializationMode()
        assert slave.getInteger(vrs) == [0, 1, 0, 1, 6, 0, 0]
        slave.exitInitializationMode()
        slave.doStep(0.0, 1e-3)
        assert slave.getInteger([gimbal_fmu.vr("solver.states")]) == [7]   # rigid gear 1, quasi-static motor 1
    finally:
        slave.freeInstance()
    assert gimbal_fmu.start("solver.method") == 4
    values = {"gear1.model": 1, "solver.method": 5, "u_R1": 1.0, "dry_friction": False}
    slave = gimbal_fmu.instantiate("set_values")
    try:
        slave.setupExperiment(startTime=0.0)
        gimbal_fmu.set_values(slave, values)
        slave.enterInitializationMode()
        assert gimbal_fmu.get_values(slave, list(values)) == [1.0, 5.0, 1.0, 0.0]
    finally:
        slave.freeInstance()


# --- display units -----------------------------------------------------------------------------

def test_every_angle_rate_and_acceleration_has_its_display_unit(md):
    units = {u.name: u for u in md.unitDefinitions}
    for unit, display in DISPLAY_UNITS.items():
        (shown,) = units[unit].displayUnits
        assert shown.name == display
        assert math.isclose(shown.factor, 180 / math.pi, rel_tol=1e-15) and shown.offset == 0
    checked = 0
    for v in md.modelVariables:
        if v.type == "Real" and v.unit in DISPLAY_UNITS:
            assert v.displayUnit == DISPLAY_UNITS[v.unit], f"{v.name} ({v.unit}) has displayUnit {v.displayUnit!r}"
            checked += 1
        else:
            assert v.displayUnit is None, v.name
    # Every Real variable of real_variables.def in those units (the angles, rates and accelerations, the
    # derivatives of angles and rates among them) is in the model description with its display unit.
    declared = sum(1 for unit in declared_counts.real_units() if unit in DISPLAY_UNITS)
    assert checked == declared >= 45
    for name in ("body1.w_min", "rotor2.w_min", "gear1.eta", "base.delta_ddot", "base.gamma_ddot"):
        assert next(v for v in md.modelVariables if v.name == name).displayUnit is not None, name


# --- default experiment ------------------------------------------------------------------------

def test_default_experiment(md, by_name):
    e = md.defaultExperiment
    assert float(e.startTime) == 0.0 and float(e.stopTime) == 2.0
    assert float(e.stepSize) == 1e-3   # the 1 kHz loop of the scenes
    assert float(e.tolerance) == float(by_name["solver.rtol"].start)


def test_default_experiment_tolerance_gives_the_default_run(gimbal_fmu):
    """A master that hands the default tolerance to fmi2SetupExperiment gets the FMU's default run."""
    runs = []
    for tolerance in (None, float(gimbal_fmu.model_description.defaultExperiment.tolerance)):
        slave = gimbal_fmu.instantiate("tolerance")
        try:
            slave.setupExperiment(tolerance=tolerance, startTime=0.0)
            gimbal_fmu.set_values(slave, {"beta": 0.3, "beta_m": 18.0, "u_R1": 3.0})
            slave.enterInitializationMode()
            slave.exitInitializationMode()
            for k in range(50):
                slave.doStep(k * 1e-3, 1e-3)
            runs.append(gimbal_fmu.get_values(slave, ["alpha", "beta", "i_R1"]))
        finally:
            slave.freeInstance()
    assert runs[0] == runs[1]


# --- header ------------------------------------------------------------------------------------

def test_header_attributes(md):
    version = cmake_version()
    assert md.fmiVersion == "2.0"
    assert md.version == version
    assert md.generationTool == f"Gimbal2Axis {version} (model_description_generator)"
    assert md.author == "the Gimbal2Axis authors"
    assert re.fullmatch(r"Copyright \(c\) 20[0-9]{2} the Gimbal2Axis authors", md.copyright)
    assert md.license.startswith("BSD-3-Clause")
    assert re.fullmatch(r"[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}Z", md.generationDateAndTime)


def _configure(build_dir, tmp_path, environment):
    """Runs the build's last step (the template filled with the generator's fragments) again."""
    fragments = build_dir / "model_description_fragments"
    output = tmp_path / "modelDescription.xml"
    git = shutil.which("git") or ""
    subprocess.run(["cmake", f"-DTEMPLATE={REPO / 'modelDescription.xml.in'}", f"-DOUTPUT={output}",
                    f"-DFRAGMENTS={fragments}", "-DMODEL_IDENTIFIER=Gimbal2Axis", "-DGIMBAL_GUID={x}",
                    "-DPROJECT_NAME=Gimbal2Axis", "-DPROJECT_VERSION=0", f"-DSOURCE_DIR={REPO}",
                    f"-DGIT_EXECUTABLE={git}", "-P", str(REPO / "scripts" / "configure_model_description.cmake")],
                   check=True, capture_output=True, env=environment)
    return re.search(r'generationDateAndTime="([^"]*)"', output.read_text()).group(1)


def test_generation_date_is_source_date_epoch_else_the_last_commit(build_dir, tmp_path):
    environment = {k: v for k, v in os.environ.items() if k != "SOURCE_DATE_EPOCH"}
    assert _configure(build_dir, tmp_path, {**environment, "SOURCE_DATE_EPOCH": "1700000000"}) == "2023-11-14T22:13:20Z"
    commit = subprocess.run(["git", "-C", str(REPO), "log", "-1", "--format=%ct"], capture_output=True, text=True)
    if commit.returncode != 0 or not commit.stdout.strip():
        pytest.skip("not a git checkout: the date is the build time")
    expected = datetime.datetime.fromtimestamp(int(commit.stdout), datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    assert _configure(build_dir, tmp_path, environment) == expected


# --- one version -------------------------------------------------------------------------------

def test_one_version_everywhere(md):
    version = cmake_version()
    pyproject = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert "version" not in pyproject and "version" in pyproject["dynamic"], \
        "pyproject.toml takes its version from CMakeLists.txt (setup.py), it does not state one"
    installed = importlib.metadata.version("gimbal2axis")
    assert installed == version, f"the installed package says {installed}: run scripts/setup.sh again"
    assert md.version == version
    assert f"Version {version}" in (REPO / "README.md").read_text()
    changelog = (REPO / "CHANGELOG.md").read_text()
    releases = re.findall(r"^## \[([0-9]+\.[0-9]+\.[0-9]+)\] - ([0-9]{4}-[0-9]{2}-[0-9]{2})$", changelog, re.M)
    assert releases and releases[0][0] == version, "CHANGELOG.md's latest release is the project's version"


def test_licence_file():
    text = (REPO / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License")
    assert "the Gimbal2Axis authors" in text
    assert "Neither the name of the copyright holder nor the names of its" in text


def test_packaged_description_is_the_staged_one(fmu_path, build_dir):
    packaged = zipfile.ZipFile(fmu_path).read("modelDescription.xml").decode()
    assert packaged == (build_dir / "fmu_staging" / "modelDescription.xml").read_text()


def test_the_native_benchmark_driver_sets_the_enumerations(build_dir):
    """benchmarks/bench_driver.cpp reads modelDescription.xml itself: an Enumeration is an Integer to it."""
    bench = build_dir / "benchmarks" / "gimbal_bench"
    if not bench.is_file():
        pytest.skip("gimbal_bench is not built (sanitizer builds leave it out)")
    so = build_dir / "fmu_staging" / "binaries" / "linux64" / "Gimbal2Axis.so"
    done = subprocess.run([str(bench), "--fmu", str(so), "--duration", "0.01", "--method", "5", "--fidelity", "reduced"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "fidelity reduced, method 5" in done.stdout and "(4 states)" in done.stdout, done.stdout


def test_the_model_description_is_valid_against_the_fmi_2_schema(build_dir):
    """xmllint against FMI 2.0's XSD (as fmpy ships it), and fmpy's own checks: both clean."""
    import fmpy
    from fmpy.validation import validate_fmu

    xmllint = shutil.which("xmllint")
    assert xmllint, "xmllint is missing: scripts/setup.sh installs libxml2-utils"
    schema = pathlib.Path(fmpy.__file__).parent / "schema" / "fmi2" / "fmi2ModelDescription.xsd"
    description = build_dir / "fmu_staging" / "modelDescription.xml"
    done = subprocess.run([xmllint, "--noout", "--schema", str(schema), str(description)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    assert validate_fmu(str(build_dir / "Gimbal2Axis.fmu")) == []
