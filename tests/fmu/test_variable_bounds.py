"""The min and max of modelDescription.xml against what the FMU enforces (the parameter validation,
model_core/src/simulation/parameter_building.cpp): a value just outside a bound is refused with fmi2Error at
fmi2ExitInitializationMode, naming the variable; the bound itself is accepted (FMI's bounds are
inclusive). The same for the items of every Enumeration. And the other way round: each parameter
rule the validation applies to one variable alone is declared as a bound."""
import math

import pytest
from fmpy.fmi1 import FMICallException

from support import declared_counts

ERROR = 3

# A bound alone may not be enough to make a set of values valid: rules that tie variables together
# stay in force. These are the values that keep them at a bound.
COMPANIONS = {
    # T_din <= T_max: a breakaway torque of 0 needs a slip torque of 0.
    "T_max": lambda prefix: {f"{prefix}.T_din": 0.0},
}

# Every Real parameter on which the validation enforces a rule of its own, and the bound that states
# it; the test below refuses a table that drops one or adds one the validation does not know.
# (kAboveZero: a rule "> 0", written as the least positive normal double.)
ABOVE_ZERO = 2.2250738585072014e-308
EXPECTED_REAL_BOUNDS = {
    **{f"{b}.{p}": (0.0, None) for b in ("body1", "rotor1", "body2", "rotor2")
       for p in ("m", "c_visc", "T_din", "T_max", "mu")},
    "g": (0.0, None),
    **{f"motor{j}.{p}": (ABOVE_ZERO, None) for j in (1, 2) for p in ("R", "L", "i_L", "U_L")},
    **{f"motor{j}.{p}": (0.0, None) for j in (1, 2) for p in ("k_torque", "k_emf")},
    **{f"gear{j}.{p}": (0.0, None) for j in (1, 2) for p in ("k_s", "c_s", "eta")},
    **{f"cable{j}.{p}": (0.0, None) for j in (1, 2) for p in ("k", "c")},
    **{f"motor{j}.T_cogging": (0.0, None) for j in (1, 2)},
    "solver.rtol": (ABOVE_ZERO, math.nextafter(1.0, 0.0)),
    # Every axis stop's restitution in [0, 1] and rest rate > 0 (its AXIS_STOP row of switching_elements.def).
    **{declared_counts.real_name(stop["restitution"]): (0.0, 1.0) for stop in declared_counts.axis_stops()},
    **{declared_counts.real_name(stop["rest_rate"]): (ABOVE_ZERO, None) for stop in declared_counts.axis_stops()},
    **{f"amplifier{j}.{p}": (0.0, None) for j in (1, 2) for p in ("K_p", "K_i")},
    "amplifier1.f_c": (ABOVE_ZERO, None),
    "amplifier2.f_c": (ABOVE_ZERO, None),
    "solver.atol": (ABOVE_ZERO, None),
}


def _bounded(md):
    """(variable, side, bound) of every declared min and max."""
    cases = []
    for v in md.modelVariables:
        for side in ("min", "max"):
            text = getattr(v, side)
            if text is not None:
                cases.append((v, side, float(text) if v.type == "Real" else int(text)))
    return cases


def _outside(v, side, bound):
    if v.type == "Real":
        return math.nextafter(bound, -math.inf if side == "min" else math.inf)
    return bound - 1 if side == "min" else bound + 1


def _companions(name):
    prefix, _, last = name.rpartition(".")
    rule = COMPANIONS.get(last)
    return rule(prefix) if rule else {}


def _exit_initialization(fmu, values, log):
    """fmi2Status-like outcome of initializing with `values`: 0 when accepted, ERROR when refused."""
    slave = fmu.instantiate("bounds", log=log)
    try:
        slave.setupExperiment(startTime=0.0)
        fmu.set_values(slave, values)
        slave.enterInitializationMode()
        try:
            slave.exitInitializationMode()
        except FMICallException as exc:
            return exc.status
        return 0
    finally:
        slave.freeInstance()


def test_declared_bounds_are_the_validation_rules_of_single_variables(gimbal_fmu):
    md = gimbal_fmu.model_description
    declared = {}
    for v, side, bound in _bounded(md):
        if v.type == "Real":
            low, high = declared.get(v.name, (None, None))
            declared[v.name] = (bound, high) if side == "min" else (low, bound)
    assert declared == EXPECTED_REAL_BOUNDS
    integers = {v.name: (v.min, v.max) for v in md.modelVariables if v.type == "Integer" and (v.min or v.max)}
    assert integers == {"solver.max_steps": ("1", None), "solver.substeps": ("1", "10000"),
                        "motor1.cogging_periods": ("1", None), "motor2.cogging_periods": ("1", None)}
    for v in md.modelVariables:
        if v.causality != "parameter":
            assert v.min is None and v.max is None, f"{v.name}: bounds are declared for parameters only"


def test_a_value_just_outside_a_bound_is_refused(gimbal_fmu):
    cases = _bounded(gimbal_fmu.model_description)
    assert len(cases) > 30
    for v, side, bound in cases:
        log = []
        value = _outside(v, side, bound)
        status = _exit_initialization(gimbal_fmu, {v.name: value}, log)
        assert status == ERROR, f"{v.name} = {value!r} (just beyond {side} = {bound!r}) was accepted"
        errors = [text for level, _, text in log if level == ERROR]
        assert any(v.name in text for text in errors), (v.name, errors)


def test_a_value_at_a_bound_is_accepted(gimbal_fmu):
    for v, side, bound in _bounded(gimbal_fmu.model_description):
        log = []
        values = {**_companions(v.name), v.name: bound}
        status = _exit_initialization(gimbal_fmu, values, log)
        assert status == 0, f"{values} refused: {[text for _, _, text in log]}"


def test_strict_bounds_refuse_zero_and_subnormals(gimbal_fmu):
    """'> 0' is declared as min = the least positive normal double, and enforced as that: 0 and the
    subnormal numbers below it are refused (a C parser reports a subnormal min as out of range)."""
    for name in ("motor1.R", "motor2.L", "motor1.i_L", "motor2.U_L", "solver.rtol", "solver.atol"):
        for value in (0.0, 5e-324, math.nextafter(ABOVE_ZERO, 0.0), -1.0):
            assert _exit_initialization(gimbal_fmu, {name: value}, []) == ERROR, (name, value)
    assert _exit_initialization(gimbal_fmu, {"solver.rtol": 1.0}, []) == ERROR


@pytest.mark.parametrize("name", ["gear1.model", "gear2.model", "motor1.model", "motor2.model", "solver.method"])
def test_enumeration_items_are_the_accepted_values(gimbal_fmu, name):
    v = gimbal_fmu.variable(name)
    assert v.type == "Enumeration"
    values = sorted(int(item.value) for item in v.declaredType.items)
    assert values == list(range(values[0], values[-1] + 1)), "items without gaps"
    for value in values:
        log = []
        assert _exit_initialization(gimbal_fmu, {name: value}, log) == 0, (name, value, log)
    for value in (values[0] - 1, values[-1] + 1):
        log = []
        assert _exit_initialization(gimbal_fmu, {name: value}, log) == ERROR, (name, value)
        assert any(level == ERROR and name in text for level, _, text in log), log


def test_an_enumeration_refusal_lists_the_items_of_the_model_description(gimbal_fmu):
    """The refusal of a value outside an Enumeration is made from the same table as modelDescription.xml's
    items: every item, by value and name, the start value marked as the default."""
    for name in ("gear1.model", "motor2.model", "solver.method"):
        v = gimbal_fmu.variable(name)
        log = []
        assert _exit_initialization(gimbal_fmu, {name: 99}, log) == ERROR
        text = next(text for level, _, text in log if level == ERROR and name in text)
        for item in v.declaredType.items:
            default = ", the default" if int(item.value) == int(v.start) else ""
            assert f"{item.value} ({item.name}{default})" in text, (item.name, text)
