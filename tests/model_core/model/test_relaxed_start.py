"""Starts that mean what they say (gear<j>.start, docs/physics.md section 3.3): a host that sets only the
load angles and rates gets relaxed gears, the rotors in mesh with their loads, under FMI 2.0 and 3.0,
Co-Simulation and Model Exchange alike (fmpy drives all four); a start twisted on purpose is kept and
said once in the log; the README's fmpy example, exactly as written, releases the payload."""
import contextlib
import io
import re

import fmpy
import fmpy.validation
import numpy as np
import pytest

from conftest import REPO_ROOT
from support.model_exchange_host import simulate_model_exchange
from gimbal2axis.fmu import simulate

INTERFACES = [("fmi2", "CoSimulation"), ("fmi2", "ModelExchange"), ("fmi3", "CoSimulation"), ("fmi3", "ModelExchange")]
ROTORS = ["alpha_m", "alpha_m_dot", "beta_m", "beta_m_dot"]
# Only the loads: both axes displaced and moving, so every rotor angle and rate has to follow.
LOADS_ONLY = {"alpha": 0.3, "beta": 0.5, "alpha_dot": 0.2, "beta_dot": -0.1, "base.fixed": True}
# A relaxed gear carries what the bodies' own dynamics ask of it: nothing while the drive stays in its
# backlash (the first milliseconds here), then at most what its motor can give through it, N k_torque i_L
# (19 N.m, 7 N.m). The twisted start of the same loads gave -6252 N.m on gear 2 one millisecond in.
RELAXED_TORQUE = 1.0  # N.m
AS_GIVEN, IN_MESH = 2, 1  # items of GearStart


def motor_torque_through_gear(fmu, axis):
    """The most motor `axis` puts through its gear: at its current limit, times the ratio."""
    return abs(fmu.start(f"gear{axis}.N")) * fmu.start(f"motor{axis}.k_torque") * fmu.start(f"motor{axis}.i_L")


@pytest.fixture(scope="module")
def fmu_paths(build_dir):
    return {"fmi2": build_dir / "Gimbal2Axis.fmu", "fmi3": build_dir / "Gimbal2Axis-fmi3.fmu"}


def run(path, fmi_type, start, stop=0.01, outputs=("T_E1", "T_E2")):
    """fmpy's simulate_fmu, its own master, at its defaults."""
    return fmpy.simulate_fmu(str(path), fmi_type=fmi_type, stop_time=stop, output_interval=1e-3, start_values=start,
                             output=list(outputs))


def run_with_log(gimbal_fmu, path, version, fmi_type, start, outputs, stop=0.01):
    """A run with logging on; returns the results and [(status, category, text)] the FMU logged. FMI 2's
    messages come through the package's own callbacks (fmpy's logger proxy for FMI 2 keeps one
    process-wide target, which would outlive the callback of a run: the tests' FMI 2 hosts bypass it)."""
    log = []
    if version == "fmi3":
        def logger(environment, status, category, message):
            log.append((int(status), category.decode(), message.decode()))
        result = fmpy.simulate_fmu(str(path), fmi_type=fmi_type, stop_time=stop, output_interval=1e-3,
                                   start_values=start, output=list(outputs), debug_logging=True, logger=logger)
        return result, log
    entries = []
    if fmi_type == "ModelExchange":
        result = simulate_model_exchange(gimbal_fmu, stop, start, outputs=outputs, output_interval=1e-3, log=entries)
    else:
        slave = gimbal_fmu.instantiate("logged", log=entries, logging_on=True)
        rows = []
        try:
            slave.setupExperiment(startTime=0.0)
            gimbal_fmu.set_values(slave, start)
            slave.enterInitializationMode()
            slave.exitInitializationMode()
            rows.append(gimbal_fmu.get_values(slave, outputs))
            for k in range(int(round(stop / 1e-3))):
                slave.doStep(k * 1e-3, 1e-3)
                rows.append(gimbal_fmu.get_values(slave, outputs))
        finally:
            slave.freeInstance()
        result = {name: np.array([row[j] for row in rows]) for j, name in enumerate(outputs)}
    return result, [(entry.status, entry.category, entry.text) for entry in entries]


@pytest.mark.parametrize("version, fmi_type", INTERFACES)
def test_a_host_setting_only_the_loads_gets_relaxed_gears(fmu_paths, gimbal_fmu, version, fmi_type):
    r = run(fmu_paths[version], fmi_type, LOADS_ONLY, outputs=["T_E1", "T_E2"] + ROTORS)
    n1, n2 = gimbal_fmu.start("gear1.N"), gimbal_fmu.start("gear2.N")
    # In mesh: the rotors start N times their loads (the backlash states centred), angles and rates.
    assert r["alpha_m"][0] == n1 * LOADS_ONLY["alpha"] and r["beta_m"][0] == n2 * LOADS_ONLY["beta"]
    assert r["alpha_m_dot"][0] == n1 * LOADS_ONLY["alpha_dot"] and r["beta_m_dot"][0] == n2 * LOADS_ONLY["beta_dot"]
    # At the start and after the first step: the torques of relaxed gears; through the first 10 ms, no
    # more than the motors can give (the rotors' speed brakes on the shorted armatures).
    for axis, gear in ((1, "T_E1"), (2, "T_E2")):
        assert r[gear][0] == 0.0 and abs(r[gear][1]) < RELAXED_TORQUE, (gear, r[gear][:4])
        assert np.max(np.abs(r[gear])) < motor_torque_through_gear(gimbal_fmu, axis), (gear, r[gear])


@pytest.mark.parametrize("version, fmi_type", INTERFACES)
def test_a_twisted_start_on_purpose_is_kept_and_said_once(fmu_paths, gimbal_fmu, version, fmi_type):
    twisted = {"beta": 0.5, "beta_m": 1.0, "base.fixed": True}
    r, log = run_with_log(gimbal_fmu, fmu_paths[version], version, fmi_type, twisted, outputs=["beta_m", "T_E2"])
    assert r["beta_m"][0] == 1.0
    assert np.max(np.abs(r["T_E2"])) > 1000.0  # the twist is real: the gear snaps back
    said = [(category, text) for status, category, text in log if "starts twisted" in text]
    assert len(said) == 1, log
    category, text = said[0]
    # Which gear, by how much, the torque it gives; a warning, from the end of initialization.
    twist = 1.0 / gimbal_fmu.start("gear2.N") - 0.5 + gimbal_fmu.start("gear2.eta")
    torque = gimbal_fmu.start("gear2.k_s") * twist
    assert category == "logStatusWarning"
    assert text.startswith(f"{version}ExitInitializationMode: gear2 starts twisted"), text
    assert f"twisted by {twist:.6g} rad" in text and f"a torque of {torque:.6g} N.m" in text, text
    assert not any("gear1 starts" in text for _, _, text in log), "gear 1 starts relaxed: nothing to say"


def test_a_rotor_at_zero_twisted_on_purpose_needs_as_given(fmu_paths, gimbal_fmu):
    """A rotor angle of exactly 0 under a displaced load is the default rule's "not given": the explicit
    item as_given keeps it (the behaviour of every start before gear<j>.start)."""
    r, log = run_with_log(gimbal_fmu, fmu_paths["fmi2"], "fmi2", "CoSimulation",
                          {"beta": 0.5, "base.fixed": True, "gear2.start": AS_GIVEN}, outputs=["beta_m", "T_E2"])
    assert r["beta_m"][0] == 0.0 and np.min(r["T_E2"]) < -1000.0
    said = [text for _, _, text in log if "starts twisted" in text]
    assert len(said) == 1 and "gear2.start = as_given" in said[0], log


def test_in_mesh_replaces_given_rotor_values_and_says_so(fmu_paths, gimbal_fmu):
    r, log = run_with_log(gimbal_fmu, fmu_paths["fmi3"], "fmi3", "CoSimulation",
                          {"beta": 0.5, "beta_m": 1.0, "base.fixed": True, "gear2.start": IN_MESH},
                          outputs=["beta_m", "T_E2"])
    assert r["beta_m"][0] == 0.5 * gimbal_fmu.start("gear2.N")
    assert r["T_E2"][0] == 0.0 and abs(r["T_E2"][1]) < RELAXED_TORQUE
    assert np.max(np.abs(r["T_E2"])) < motor_torque_through_gear(gimbal_fmu, 2)
    said = [text for _, _, text in log if "not used" in text]
    assert len(said) == 1 and "gear2.start = in_mesh" in said[0] and "beta_m = 1 rad" in said[0], log


@pytest.mark.parametrize("version, fmi_type", INTERFACES)
def test_an_untwisted_start_says_nothing(fmu_paths, gimbal_fmu, version, fmi_type):
    _, log = run_with_log(gimbal_fmu, fmu_paths[version], version, fmi_type, LOADS_ONLY, outputs=["T_E2"])
    assert log, "logging was on: the run said something (its events)"
    assert not any("twist" in text or "not used" in text for _, _, text in log), log


@pytest.mark.parametrize("gear_model", [1, 2])
def test_in_mesh_means_the_shaft_untwisted_with_the_backlash_state_as_given(gimbal_fmu, gear_model):
    """q_m = N (q_l + theta_b): with backlash (model 2) the shaft's end where the start puts it in the play;
    a compliant gear without backlash (model 1) has no backlash state (theta_b = 0)."""
    theta_b = 0.5 * gimbal_fmu.start("gear2.eta")
    start = {"beta": 0.5, "beta_dot": 0.1, "theta_b2": theta_b, "base.fixed": True, "gear2.model": gear_model}
    r = simulate(gimbal_fmu, 0.002, 1e-3, start, outputs=["beta_m", "beta_m_dot", "T_E2"])
    n2 = gimbal_fmu.start("gear2.N")
    assert r["beta_m"][0] == n2 * (0.5 + (theta_b if gear_model == 2 else 0.0))
    assert r["beta_m_dot"][0] == n2 * 0.1
    assert r["T_E2"][0] == 0.0 and abs(r["T_E2"][1]) < RELAXED_TORQUE


def test_a_rigid_gear_has_its_rotor_in_mesh_whatever_is_given(gimbal_fmu):
    log = []
    slave = gimbal_fmu.instantiate("rigid", log=log, logging_on=True)
    try:
        slave.setupExperiment(startTime=0.0)
        gimbal_fmu.set_values(slave, {"gear2.model": 0, "beta": 0.5, "beta_m": 1.0, "base.fixed": True})
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        assert gimbal_fmu.get_values(slave, ["beta_m"]) == [0.5 * gimbal_fmu.start("gear2.N")]
    finally:
        slave.freeInstance()
    said = [entry.text for entry in log if "rigid gear 2" in entry.text]
    assert len(said) == 1 and "beta_m = 1" in said[0] and "not used" in said[0], log


def test_setting_every_default_start_value_changes_nothing(fmu_paths):
    """Importers differ: fmpy sets only the values given, others set every start value of the model
    description. The rotors' default 0 is "not given" either way, so both see the same start."""
    md = fmpy.read_model_description(str(fmu_paths["fmi2"]))
    defaults = {v.name: (v.start == "true" if v.type == "Boolean" else float(v.start)) for v in md.modelVariables
                if v.start is not None and v.causality in ("parameter", "output") and v.initial in ("exact", "approx")}
    only_given = run(fmu_paths["fmi2"], "CoSimulation", LOADS_ONLY, outputs=["T_E2", "beta_m"])
    everything = run(fmu_paths["fmi2"], "CoSimulation", dict(defaults, **LOADS_ONLY), outputs=["T_E2", "beta_m"])
    assert "beta_m" in defaults and "gear2.start" in defaults
    assert np.array_equal(only_given["beta_m"], everything["beta_m"])
    assert np.array_equal(only_given["T_E2"], everything["T_E2"])


def test_the_rotors_are_computed_in_initialization_mode(gimbal_fmu):
    """initial="approx": settable before initialization, read back in Initialization Mode where they will
    start (an InitialUnknown), the start value the host set kept for the rule."""
    slave = gimbal_fmu.instantiate("initialization", log=[])
    try:
        slave.setupExperiment(startTime=0.0)
        gimbal_fmu.set_values(slave, {"beta": 0.5, "alpha_m": 7.0})
        slave.enterInitializationMode()
        assert gimbal_fmu.get_values(slave, ["beta_m", "alpha_m"]) == [30.0, 7.0]
        gimbal_fmu.set_values(slave, {"beta": 0.25})  # read again after a change: not the earlier start
        assert gimbal_fmu.get_values(slave, ["beta_m"]) == [15.0]
        slave.exitInitializationMode()
        assert gimbal_fmu.get_values(slave, ["beta_m", "alpha_m"]) == [15.0, 7.0]
    finally:
        slave.freeInstance()


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_the_model_description_declares_the_rule(fmu_paths, version):
    md = fmpy.read_model_description(str(fmu_paths[version]))
    by_name = {v.name: v for v in md.modelVariables}
    assert [name for name in ROTORS if by_name[name].initial == "approx"] == ROTORS
    assert all(by_name[name].start is not None and float(by_name[name].start) == 0.0 for name in ROTORS)
    initial_unknowns = {u.variable.name for u in md.initialUnknowns}
    assert set(ROTORS) <= initial_unknowns
    for gear in ("gear1.start", "gear2.start"):
        v = by_name[gear]
        assert v.type == "Enumeration" and v.causality == "parameter" and v.variability == "fixed"
        assert v.declaredType.name == "GearStart" and int(v.start) == 0
        assert [(item.name, int(item.value)) for item in v.declaredType.items] == [
            ("in_mesh_unless_given", 0), ("in_mesh", 1), ("as_given", 2)]
    assert fmpy.validation.validate_fmu(str(fmu_paths[version])) == []


def test_an_invalid_rule_is_refused_naming_it(gimbal_fmu):
    log = []
    slave = gimbal_fmu.instantiate("refused", log=log)
    try:
        slave.setupExperiment(startTime=0.0)
        gimbal_fmu.set_values(slave, {"gear1.start": 3})
        slave.enterInitializationMode()
        with pytest.raises(Exception):
            slave.exitInitializationMode()
    finally:
        slave.freeInstance()
    assert any("gear1.start = 3 is invalid: it must be an item of GearStart" in entry.text for entry in log), log


def readme_fmpy_example() -> tuple[str, str]:
    """The README's fmpy example (its code block) and the output the README shows for it."""
    readme = (REPO_ROOT / "README.md").read_text()
    match = re.search(r"\*\*From any FMI host\.\*\*.*?```python\n(.*?)```\n(.*?)```text\n(.*?)```", readme, re.S)
    assert match, "README.md: the fmpy example (a python block, then its printed output) not found"
    return match.group(1), match.group(3).strip()


def test_the_readme_fmpy_example_releases_the_payload(fmu_paths, gimbal_fmu):
    code, shown = readme_fmpy_example()
    assert 'start_values={"beta": 0.5, "base.fixed": True}' in code
    code = code.replace('"build/Gimbal2Axis.fmu"', repr(str(fmu_paths["fmi2"])))  # the tests' build
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(code, "README.md", "exec"), {})
    printed = printed.getvalue().strip()
    assert printed == shown, f"the README shows {shown}, the example prints {printed}"
    # Released: the same as a start whose elevation rotor is put in mesh by hand, bit for bit.
    by_hand = fmpy.simulate_fmu(str(fmu_paths["fmi2"]), stop_time=0.5, output_interval=1e-3,
                                start_values={"beta": 0.5, "beta_m": 0.5 * gimbal_fmu.start("gear2.N"),
                                              "base.fixed": True}, output=["beta", "T_E2"])
    assert float(printed) == by_hand["beta"][-1]
    assert np.max(np.abs(by_hand["T_E2"][:2])) < RELAXED_TORQUE


def test_the_scene_runner_keeps_its_own_rotor_starts(fmu_paths, gimbal_fmu, tmp_path):
    """The scene runner puts a rotor it is not given in mesh itself and keeps one it is given, 0 included
    (a scene's start is what it says): for a rotor at 0 under a displaced load it asks the FMU for
    gear<j>.start = as_given, and only then (libcosim cannot set an Enumeration)."""
    from gimbal2axis import load_scene
    from gimbal2axis.scene.scene import start_values

    path = tmp_path / "twisted_on_purpose.toml"
    path.write_text('name = "twisted_on_purpose"\nstop_time = 0.01\nstep_size = 1e-3\n'
                    '[fidelity]\n"base.fixed" = true\n[initial]\nalpha = 0.2\nbeta = 0.5\nbeta_m = 0.0\n'
                    '[base_motion]\ntype = "fixed"\n[controller]\ntype = "none"\n')
    values = start_values(load_scene(path), gimbal_fmu, np.zeros(15))
    assert values["alpha_m"] == 0.2 * gimbal_fmu.start("gear1.N") and values["beta_m"] == 0.0
    assert "gear1.start" not in values and values["gear2.start"] == AS_GIVEN
    r = run(fmu_paths["fmi2"], "CoSimulation", values, outputs=["alpha_m", "beta_m"])
    assert r["alpha_m"][0] == values["alpha_m"] and r["beta_m"][0] == 0.0
