"""The packaged FMU: valid for fmpy, a well-behaved guest in the host process."""
import os
import re
import subprocess
import sys
import textwrap
import zipfile

import fmpy
import pytest
from fmpy.validation import validate_fmu


def test_fmu_validates(fmu_path):
    problems = validate_fmu(str(fmu_path))
    assert problems == [], problems


def test_fmu_contains_description_and_linux64_binary(fmu_path):
    names = set(zipfile.ZipFile(fmu_path).namelist())
    assert "modelDescription.xml" in names
    assert "binaries/linux64/Gimbal2Axis.so" in names


@pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                    reason="a sanitizer build links the sanitizer runtimes dynamically by design")
def test_shared_object_exports_only_fmi2_and_links_only_libc(build_dir):
    so = build_dir / "fmu_staging" / "binaries" / "linux64" / "Gimbal2Axis.so"
    exported = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True)
    symbols = [line.split()[-1] for line in exported.stdout.splitlines() if line.strip()]
    assert symbols, "no exported symbols at all"
    foreign = [s for s in symbols if not s.startswith("fmi2")]
    assert foreign == [], f"symbols other than fmi2*: {foreign[:10]}"
    assert {"fmi2Instantiate", "fmi2DoStep", "fmi2GetReal", "fmi2SetReal"} <= set(symbols)

    ldd = subprocess.run(["ldd", str(so)], capture_output=True, text=True, check=True).stdout
    libraries = [line.split()[0] for line in ldd.splitlines() if line.strip()]
    allowed = re.compile(r"^(linux-vdso\.so\.1|libc\.so\.6|libm\.so\.6|/lib64/ld-linux-x86-64\.so\.2)$")
    assert [lib for lib in libraries if not allowed.match(lib)] == []


def test_every_variable_has_description_and_unit(fmu_path):
    md = fmpy.read_model_description(str(fmu_path))
    units = {u.name for u in md.unitDefinitions}
    for v in md.modelVariables:
        assert v.description, f"{v.name} has no description"
        if v.type == "Real":
            assert v.unit in units, f"{v.name} has unit {v.unit!r} not in <UnitDefinitions>"
    names = [v.name for v in md.modelVariables]
    assert len(names) == len(set(names))
    for angle in ("alpha", "beta", "base.delta", "theta_b1"):
        assert next(v for v in md.modelVariables if v.name == angle).displayUnit == "deg"


def test_interface_names_of_the_contract_exist(fmu_path):
    md = fmpy.read_model_description(str(fmu_path))
    by_name = {v.name: v for v in md.modelVariables}
    inputs = ["u_R1", "u_R2"] + [f"base.{a}{d}" for a in ("delta", "psi", "gamma") for d in ("", "_dot", "_ddot")] + \
             [f"base.{v}[{i}]" for v in ("v_a", "a_a") for i in (1, 2, 3)]
    outputs = ["alpha", "alpha_m", "beta", "beta_m", "alpha_dot", "alpha_m_dot", "beta_dot", "beta_m_dot",
               "i_R1", "i_R2", "theta_b1", "theta_b2", "T_E1", "T_E2", "los.omega[1]", "los.omega[2]", "los.omega[3]"]
    for name in inputs:
        assert by_name[name].causality == "input", name
    for name in outputs:
        assert by_name[name].causality == "output", name
    for name in outputs[:12]:
        # Set before initialization: exact, or approx for the rotors, which gear<j>.start may start in
        # mesh with their loads instead (docs/physics.md section 3.3).
        assert by_name[name].initial == ("approx" if name.endswith(("_m", "_m_dot")) else "exact"), name


def test_simulate_fmu_runs_and_stays_silent(fmu_path, tmp_path):
    """Runs in a separate process so that anything the FMU writes to stdout/stderr is caught."""
    script = textwrap.dedent(f"""
        import fmpy
        r = fmpy.simulate_fmu({str(fmu_path)!r}, stop_time=0.2, output_interval=0.001,
                              start_values={{"beta": 0.3, "beta_m": 18.0}}, output=["beta", "beta_dot"])
        import sys
        sys.stderr.write("RESULT %d %.17g\\n" % (len(r), r["beta"][-1]))
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("RESULT"), f"unexpected output: {done.stderr!r}"
    count, beta_end = lines[0].split()[1:]
    assert int(count) == 201
    # The payload's centre of mass is off the elevation axis: released at rest, it must move.
    assert abs(float(beta_end) - 0.3) > 1e-4
