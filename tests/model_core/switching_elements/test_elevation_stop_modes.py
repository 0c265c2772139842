"""The elevation end stop's mode output, from its one declaration (model_core/include/gimbal/switching_elements.def)
to the scene runner: the model description lists the switching elements' mode outputs (a tool annotation
the generator writes), gimbal2axis.FMU.mode_outputs reads them, and a run records the stop's only in a
scene that switches the stop on, so that every other scene records what it did before (the golden
digests, tests/package/test_golden_results.py). The stop's physics: tests/model_core/switching_elements/test_elevation_stop.cpp."""
import pathlib
import re

import numpy as np
import pytest

from gimbal2axis import FMU, load_scene, run

REPO = pathlib.Path(__file__).resolve().parents[3]

SWING = """name = "stop_swing"
stop_time = 1.0
step_size = 1e-3
[fidelity]
"base.fixed" = true
[parameters]
{stop}
"motor2.k_torque" = 0.0
"motor2.k_emf" = 0.0
"elevation_stop.beta_min" = 0.2
"elevation_stop.beta_max" = 0.6
"elevation_stop.e" = 0.0
[initial]
beta = 0.5235987755982988
beta_m = 31.41592653589793
[base_motion]
type = "fixed"
[controller]
type = "none"
"""


@pytest.fixture(scope="module")
def fmu(fmu_path):
    with FMU(fmu_path) as f:
        yield f


def test_the_mode_outputs_are_the_declared_ones(fmu):
    declared = (REPO / "model_core" / "include" / "gimbal" / "switching_elements.def").read_text()
    switches = {element: switch for element, switch in
                re.findall(r'^ELEMENT\((\w+), \d+, \d+, "([\w.<>]*)", \w+\)', declared, re.MULTILINE)}
    rows = re.findall(r"^MODE_OUTPUT\((\w+), (\w+), -?\d+, -?\d+\)", declared, re.MULTILINE)
    names = {v.name.replace(".", "_").replace("[", "_").replace("]", ""): v.name for v in fmu.variables.values()}
    # "<j>" in a switch is the instance's number: the element's mode outputs are in instance order.
    expected = []
    for k, (element, output) in enumerate(rows):
        instance = sum(1 for e, _ in rows[:k] if e == element) + 1
        expected.append((names[output], element, switches[element].replace("<j>", str(instance))))
    assert [(m.name, m.element, m.switch or "") for m in fmu.mode_outputs] == expected
    assert ("motor2.amplifier_saturated", "amplifier_saturation", "motor2.drive") in fmu.mode_outputs
    assert ("elevation_stop.contact", "elevation_stop", "elevation_stop") in fmu.mode_outputs
    for mode in fmu.mode_outputs:
        assert fmu.variables[mode.name].causality == "output" and fmu.variables[mode.name].type == "Integer"


def scene(tmp_path, stop: bool):
    path = tmp_path / f"swing_{stop}.toml"
    path.write_text(SWING.format(stop='"elevation_stop" = true' if stop else ""))
    return load_scene(path)


def test_a_run_records_the_stop_only_where_it_is_on(fmu, tmp_path):
    without = run(scene(tmp_path, False), fmu)
    assert "elevation_stop.contact" not in without.signals
    assert without.signals["beta"].min() < 0.2  # the payload swings through where the stop would be
    with_stop = run(scene(tmp_path, True), fmu)
    contact, beta = with_stop.signals["elevation_stop.contact"], with_stop.signals["beta"]
    # It falls onto beta_min (e = 0: no rebound) and rests there, held by the stop against gravity.
    assert beta.min() >= 0.2 - 1e-12 and beta[-1] == 0.2
    assert contact[0] == 0 and contact[-1] == -1 and set(np.unique(contact)) == {0.0, -1.0}
    assert {k for k in without.signals} | {"elevation_stop.contact"} == set(with_stop.signals)


def test_the_linear_model_holds_beta_at_rest_on_the_stop(build_dir):
    """At rest on a stop, the linear model keeps beta there (docs/physics.md (5.5c)): beta_dot's row of A
    and B is zero, the mode is reported, and a transfer function to beta names it as what holds it."""
    from gimbal2axis.analysis.linearization import linearize

    values = {"elevation_stop": True, "elevation_stop.beta_min": -0.2, "elevation_stop.beta_max": 0.2,
              "base.fixed": True, "dry_friction": False}
    resting = linearize({**values, "beta": -0.2}, build_dir=build_dir)  # gravity pushes it onto beta_min
    free = linearize({**values, "elevation_stop": False, "beta": -0.2}, build_dir=build_dir)
    row = resting.states.index("beta_dot")
    assert resting.modes["elevation_stop.contact"] == -1 and free.modes["elevation_stop.contact"] == 0
    assert not resting.A[row].any() and not resting.B[row].any()
    assert free.A[row].any()  # (B: the voltage reaches beta_dot only through the current and the gear)
    assert ("elevation_stop.contact", -1) in [held[:2] for held in resting.held_modes_on("u_R2", "beta")]
    assert "elevation_stop.contact" not in [held[0] for held in free.held_modes_on("u_R2", "beta")]
