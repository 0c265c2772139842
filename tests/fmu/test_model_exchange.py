"""FMI 2.0 Model Exchange: the same FMU integrated by the host.

- CVode at a tight tolerance against the Co-Simulation FMU at a tight tolerance: fixed base with
  piecewise-constant voltages, and a moving base (the same carrier motion in both);
- a smooth carrier motion, which Co-Simulation approximates by constant accelerations over each step:
  its results converge to Model Exchange's as the step shrinks;
- a coarse forward-Euler host: outputs stay physical (limits, play, finite) and converge;
- the event iteration ends after one fmi2NewDiscreteStates, and a naive host that repeats it changes
  nothing, on every scene's parameters;
- FMU states, refusals and the model description's Model Exchange parts.
"""
from __future__ import annotations

import ctypes
import math
import pathlib
import tomllib

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from support import declared_counts
from support.model_exchange_host import ModelExchangeInstance, simulate_model_exchange
from gimbal2axis.fmu import simulate

REPO = pathlib.Path(__file__).resolve().parents[2]
ANGLES = ["alpha", "alpha_m", "beta", "beta_m"]
COUNTERS = ["events.total", "events.backlash1", "events.backlash2", "events.current_limit1",
            "events.current_limit2", "events.stick_slip"]
TIGHT = 1e-10


def angle_errors(fmu, a: dict, b: dict) -> dict:
    """Largest differences of the angles, the rotors' referred to the load side (divided by the gear
    ratio): a rotor turns N times the load's angle, and so does its share of the tolerance."""
    ratio = {"alpha": 1.0, "beta": 1.0, "alpha_m": fmu.start("gear1.N"), "beta_m": fmu.start("gear2.N")}
    return {name: float(np.max(np.abs(a[name] - b[name]))) / ratio[name] for name in ANGLES}


def square_wave(amplitude: float, half_period: float):
    """Voltages switching every half_period (which is not a power of two of the 1 ms step)."""
    def voltages(t: float) -> dict:
        # Right-continuous, and not early: a switch a few ulp before its time would be a state event.
        k = int(math.floor(t / half_period * (1.0 + 1e-14)))
        sign = 1.0 if k % 2 == 0 else -1.0
        return {"u_R1": amplitude * sign, "u_R2": -0.6 * amplitude * sign}
    return voltages


def test_cvode_matches_co_simulation_on_a_fixed_base_with_switching_voltages(gimbal_fmu):
    # Voltages that reverse every 30 ms: the limiter, the backlash and stick-slip all switch.
    voltages = square_wave(12.0, 0.03)
    start = {"base.fixed": True, "beta": 0.3}
    # Ends between two switches: at a switch the two interfaces report before and after it.
    me = simulate_model_exchange(gimbal_fmu, 0.31, start, voltages, input_events=np.arange(1, 11) * 0.03,
                                 outputs=ANGLES + COUNTERS, rtol=TIGHT)
    cs = simulate(gimbal_fmu, 0.31, 1e-3, dict(start, **{"solver.rtol": TIGHT}), lambda t, _: voltages(t),
                  outputs=ANGLES + COUNTERS)
    errors = angle_errors(gimbal_fmu, me, cs)
    assert max(errors.values()) < 1e-7, errors
    assert me["events.current_limit1"][-1] > 0 and me["events.backlash2"][-1] > 0
    for name in COUNTERS:
        assert me[name][-1] == cs[name][-1], name


def carrier(t: float) -> dict:
    amplitude = {"delta": 0.05, "psi": 0.03, "gamma": 0.04}
    omega = {"delta": 2 * math.pi * 0.7, "psi": 2 * math.pi * 0.5, "gamma": 2 * math.pi * 0.9}
    values = {}
    for axis, a in amplitude.items():
        w = omega[axis]
        values[f"base.{axis}"] = a * math.sin(w * t)
        values[f"base.{axis}_dot"] = a * w * math.cos(w * t)
        values[f"base.{axis}_ddot"] = -a * w * w * math.sin(w * t)
    values.update({"base.v_a[1]": 0.3 * math.cos(2 * t), "base.a_a[1]": -0.6 * math.sin(2 * t),
                   "base.v_a[3]": 0.2 * math.sin(3 * t), "base.a_a[3]": 0.6 * math.cos(3 * t)})
    return values


def held_carrier(step: float):
    """The carrier motion a Co-Simulation step sees: from each step start, constant accelerations."""
    def motion(t: float) -> dict:
        k = math.floor(t / step + 1e-9)
        t0 = k * step
        tau = t - t0
        start = carrier(t0)
        values = dict(start)
        for axis in ("delta", "psi", "gamma"):
            a, r, acc = start[f"base.{axis}"], start[f"base.{axis}_dot"], start[f"base.{axis}_ddot"]
            values[f"base.{axis}"] = a + r * tau + 0.5 * acc * tau * tau
            values[f"base.{axis}_dot"] = r + acc * tau
        for j in (1, 3):
            values[f"base.v_a[{j}]"] = start[f"base.v_a[{j}]"] + start[f"base.a_a[{j}]"] * tau
        values.update({"u_R1": 2.0, "u_R2": -1.0})
        return values
    return motion


def test_cvode_matches_co_simulation_on_a_moving_base(gimbal_fmu):
    step = 1e-3
    motion = held_carrier(step)
    start = {"beta": 0.1}
    me = simulate_model_exchange(gimbal_fmu, 0.5, start, motion, input_events=np.arange(1, 500) * step,
                                 outputs=ANGLES + COUNTERS, rtol=TIGHT)
    cs = simulate(gimbal_fmu, 0.5, step, dict(start, **{"solver.rtol": TIGHT}),
                  lambda t, _: dict(carrier(t), u_R1=2.0, u_R2=-1.0), outputs=ANGLES + COUNTERS)
    errors = angle_errors(gimbal_fmu, me, cs)
    assert max(errors.values()) < 1e-7, errors
    assert me["events.total"][-1] > 10
    for name in COUNTERS:
        assert me[name][-1] == cs[name][-1], name


def test_co_simulation_of_a_smooth_carrier_converges_to_model_exchange(gimbal_fmu):
    """Model Exchange takes the carrier's motion as set at every instant; a Co-Simulation step holds
    its accelerations from the step start, an error of first order in the step."""
    start = {"beta": 0.1}
    inputs = lambda t: dict(carrier(t), u_R1=2.0, u_R2=-1.0)  # noqa: E731
    me = simulate_model_exchange(gimbal_fmu, 0.5, start, inputs, outputs=["alpha", "beta"], rtol=TIGHT)
    errors = []
    for step in (1e-3, 5e-4, 2.5e-4):
        cs = simulate(gimbal_fmu, 0.5, step, dict(start, **{"solver.rtol": TIGHT}), lambda t, _: inputs(t),
                      outputs=["alpha", "beta"])
        k = int(round(1e-3 / step))
        errors.append(max(np.max(np.abs(me[n] - cs[n][::k])) for n in ("alpha", "beta")))
    assert errors[0] > 1e-7  # the held accelerations make a visible difference ...
    for coarse, fine in zip(errors, errors[1:]):
        assert 1.6 < coarse / fine < 2.5  # ... of first order in the step


BOUNDS = {"motor1.i_L": "i_R1", "motor2.i_L": "i_R2", "gear1.eta": "theta_b1", "gear2.eta": "theta_b2"}


def test_a_coarse_euler_host_gets_physical_outputs_and_converges(gimbal_fmu):
    voltages = square_wave(12.0, 0.03)
    start = {"base.fixed": True, "beta": 0.3}
    names = ANGLES + list(BOUNDS.values())
    reference = simulate(gimbal_fmu, 0.12, 1e-3, dict(start, **{"solver.rtol": TIGHT}), lambda t, _: voltages(t),
                         outputs=names)
    limits = {output: gimbal_fmu.start(parameter) for parameter, output in BOUNDS.items()}
    errors = []
    for euler_step in (4e-5, 2e-5, 1e-5):
        me = simulate_model_exchange(gimbal_fmu, 0.12, start, voltages, input_events=np.arange(1, 4) * 0.03,
                                     outputs=names, solver="Euler", euler_step=euler_step)
        for name in names:
            assert np.all(np.isfinite(me[name])), name
        for output, limit in limits.items():
            assert np.max(np.abs(me[output])) <= limit, output
        errors.append(max(np.max(np.abs(me[n] - reference[n])) for n in ANGLES))
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.6 * errors[0]


def scene_model(path: pathlib.Path) -> dict:
    """The FMU values a scene file sets (fidelity, parameters, initial state)."""
    scene = tomllib.loads(path.read_text())
    values = {}
    for table in ("fidelity", "parameters", "initial"):
        values.update(scene.get(table, {}))
    return values


@pytest.mark.parametrize("scene", sorted(p.name for p in (REPO / "scenes").glob("*.toml")))
def test_the_event_iteration_ends_at_once_and_a_repeat_changes_nothing(gimbal_fmu, scene):
    start = scene_model(REPO / "scenes" / scene)
    fixed = bool(start.get("base.fixed", False))
    voltages = square_wave(8.0, 0.02)
    inputs = voltages if fixed else (lambda t: dict(carrier(t), **voltages(t)))
    me = simulate_model_exchange(gimbal_fmu, 0.1, start, inputs, input_events=np.arange(1, 5) * 0.02,
                                 outputs=ANGLES + ["events.total"], rtol=1e-8, repeats=3)
    assert me["events.total"][-1] > 0
    assert set(me["event_calls"]) == {1}


def test_backlash_chatter_of_a_stiff_undamped_gear_ends_every_event_iteration(gimbal_fmu):
    """Backlash chatter of a very stiff, nearly undamped gear (a hard case of docs/hard_cases.md): about
    2,000 events in 20 ms, each iteration settled by one call; a chattering hold (50 events within 1 ns
    each; none occurs here) would be said in the log as often as events.zeno_guard counts."""
    log = []
    # gear2.start = as_given (2): beta_m stays at 0, the gear twisted by 0.3 rad on purpose.
    start = {"base.fixed": True, "gear2.k_s": 1e8, "gear2.c_s": 1e-6, "beta": 0.3, "dry_friction": False,
             "gear2.start": 2}
    me = simulate_model_exchange(gimbal_fmu, 0.02, start, square_wave(12.0, 0.005),
                                 input_events=np.arange(1, 4) * 0.005, outputs=["beta", "events.zeno_guard",
                                                                                "events.total"],
                                 rtol=1e-6, log=log)
    assert np.all(np.isfinite(me["beta"]))
    assert me["events.total"][-1] > 1000 and set(me["event_calls"]) == {1}
    holds = me["events.zeno_guard"][-1]
    said = [entry for entry in log if "chattering" in entry.text]
    assert len(said) == holds


def me_instance(gimbal_fmu, start=None, log=None, name="me"):
    return ModelExchangeInstance(gimbal_fmu, start or {"beta": 0.4}, lambda t: {"u_R1": 3.0}, log=log, name=name)


def derivatives(instance):
    dx = np.zeros(instance.nx)
    instance.model.getDerivatives(dx.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), instance.nx)
    return dx


def indicators(instance):
    z = np.zeros(instance.nz)
    instance.model.getEventIndicators(z.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), instance.nz)
    return z


def set_states(instance, x):
    x = np.ascontiguousarray(x, dtype=float)
    instance.model.setContinuousStates(x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), instance.nx)


def states(instance):
    x = np.zeros(instance.nx)
    instance.model.getContinuousStates(x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), instance.nx)
    return x


def test_states_derivatives_and_variables_agree(gimbal_fmu):
    md = gimbal_fmu.model_description
    instance = me_instance(gimbal_fmu)
    try:
        x = states(instance)
        state_names = [d.variable.derivative.name for d in md.derivatives]
        derivative_names = [d.variable.name for d in md.derivatives]
        assert state_names[:4] == ANGLES and derivative_names[0] == "der(alpha)"
        assert np.array_equal(x, instance.values(state_names))
        dx = derivatives(instance)
        assert np.array_equal(dx, instance.values(derivative_names))
        # der(angle) is the rate state, and the model is not at rest (the payload hangs at 0.4 rad).
        assert np.array_equal(dx[:4], x[4:8])
        assert np.any(dx[4:8] != 0.0)
        nominals = np.zeros(instance.nx)
        instance.model.getNominalsOfContinuousStates(nominals.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                                                     instance.nx)
        assert nominals[10] == gimbal_fmu.start("gear1.eta") and np.all(nominals > 0)
    finally:
        instance.free()


def test_fmu_states_restore_the_point_and_refuse_the_other_interface(gimbal_fmu):
    instance = me_instance(gimbal_fmu)
    other = me_instance(gimbal_fmu, name="other")
    try:
        instance.set_time(0.01)
        x = states(instance) + 1e-3
        set_states(instance, x)
        saved = instance.model.getFMUstate()
        dx, z = derivatives(instance), indicators(instance)
        set_states(instance, x + 0.1)
        instance.set_time(0.02)
        instance.model.setFMUstate(saved)
        assert np.array_equal(derivatives(instance), dx) and np.array_equal(indicators(instance), z)
        blob = instance.model.serializeFMUstate(saved)
        copy = other.model.deSerializeFMUstate(blob)
        other.model.setFMUstate(copy)
        assert np.array_equal(derivatives(other), dx) and np.array_equal(indicators(other), z)
        instance.model.freeFMUstate(saved)
        other.model.freeFMUstate(copy)
    finally:
        instance.free()
        other.free()
    log = []
    slave = gimbal_fmu.instantiate("cs", log=log)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        with pytest.raises(FMICallException):
            slave.setFMUstate(slave.deSerializeFMUstate(blob))
        assert any("continuous-time (Model Exchange)" in e.text for e in log)
    finally:
        slave.freeInstance()


def test_refusals_name_the_function_and_the_culprit(gimbal_fmu):
    log = []
    instance = me_instance(gimbal_fmu, log=log)
    model = instance.model
    try:
        def refused(call, *fragments):
            del log[:]
            with pytest.raises(FMICallException):
                call()
            text = " ".join(e.text for e in log)
            for fragment in fragments:
                assert fragment in text, (fragment, text)

        small = np.zeros(3)
        refused(lambda: model.getDerivatives(small.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), 3),
                "fmi2GetDerivatives", "nx = 3", str(gimbal_fmu.model_description.numberOfContinuousStates))
        refused(lambda: model.getEventIndicators(small.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), 3),
                "fmi2GetEventIndicators", "ni = 3", str(gimbal_fmu.model_description.numberOfEventIndicators))
        refused(lambda: model.getDerivatives(None, gimbal_fmu.model_description.numberOfContinuousStates),
                "fmi2GetDerivatives", "derivatives", "null")
        bad = states(instance)
        bad[9] = float("nan")
        refused(lambda: set_states(instance, bad), "fmi2SetContinuousStates", "i_R2", "finite")
        refused(lambda: model.setTime(float("inf")), "fmi2SetTime", "finite")
        refused(lambda: model.setTime(-1e-3), "fmi2SetTime", "before the start time 0")
        # States the model cannot represent: the outputs are refused, not handed out as inf, and an FMU
        # state taken there can still be serialized and read back (found by fuzz_model_exchange).
        huge = states(instance)
        huge[4] = 1e300
        set_states(instance, huge)
        refused(lambda: instance.values(["energy.kinetic"]), "fmi2GetReal", "not finite", "beyond what the model can represent")
        saved = model.getFMUstate()
        model.freeFMUstate(model.deSerializeFMUstate(model.serializeFMUstate(saved)))
        model.freeFMUstate(saved)
        refused(lambda: model.newDiscreteStates(), "fmi2NewDiscreteStates", "continuous-time mode")
        del log[:]
        do_step = model.dll.fmi2DoStep
        do_step.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int]
        assert do_step(model.component, 0.0, 1e-3, 1) == 3  # fmi2Error
        assert any("fmi2DoStep is not allowed in state 'continuous-time mode'" in e.text for e in log)
        model.enterEventMode()
        refused(lambda: set_states(instance, states(instance)), "fmi2SetContinuousStates", "event mode")
        model.enterContinuousTimeMode()
    finally:
        instance.free()


def test_the_model_description_declares_model_exchange(gimbal_fmu):
    md = gimbal_fmu.model_description
    assert md.modelExchange is not None and md.coSimulation is not None
    assert md.modelExchange.modelIdentifier == md.coSimulation.modelIdentifier
    # The indicators: every switching element's guards, as declared once (switching_elements.def), whose
    # sum gimbal_c_api.h's GIMBAL_EVENT_INDICATORS is.
    guards = declared_counts.event_indicators()
    states = declared_counts.continuous_states()
    assert md.numberOfContinuousStates == states and md.numberOfEventIndicators == guards >= 36
    header = (REPO / "model_core" / "include" / "gimbal" / "gimbal_c_api.h").read_text()
    assert '#include "gimbal/switching_elements.def"' in header
    assert f"#define GIMBAL_CONTINUOUS_STATES {states}\n" in header
    states = [d.variable.derivative.name for d in md.derivatives]
    assert states == ANGLES + ["alpha_dot", "alpha_m_dot", "beta_dot", "beta_m_dot", "i_R1", "i_R2", "theta_b1",
                               "theta_b2", "energy.electrical_in", "energy.resistive", "energy.viscous",
                               "energy.shaft_damping", "energy.dry_friction", "amplifier1.x_I", "amplifier2.x_I"]
    initial_unknowns = {u.variable.name for u in md.initialUnknowns}
    assert {d.variable.name for d in md.derivatives} <= initial_unknowns


# Both cables and both cogging torques on (docs/physics.md section 4.5): their analytic derivatives in
# the Jacobian, also through a rigid gear's q_m = N q_l.
DISTURBANCES = {"cable1.k": 3.0, "cable1.c": 0.02, "cable1.angle_0": 0.1,
                "cable2.k": 1.5, "cable2.c": 0.01, "cable2.angle_0": -0.2,
                "motor1.T_cogging": 0.004, "motor1.cogging_periods": 24, "motor1.cogging_phase": 0.3,
                "motor2.T_cogging": 0.003, "motor2.cogging_periods": 18, "motor2.cogging_phase": -1.1}


@pytest.mark.parametrize("point", ["rich", "rigid", "rich with disturbances", "rigid with disturbances"])
def test_directional_derivatives_match_the_linear_model_of_the_core(gimbal_fmu, build_dir, point):
    """d der(x) / d(x, u) and d y / d(x, u) by fmi2GetDirectionalDerivative against A, B, C, D of the
    core's linearization at the same point, column by column. d der(x) / dx is the analytic Jacobian
    the implicit integrators use (equal to rounding); the rest are central differences along the seed,
    and the analytic part is checked against a central difference of fmi2GetDerivatives."""
    from gimbal2axis.analysis.linearization import linearize
    from test_linearization import RICH_POINT, RIGID_POINT, split, with_contact

    values = with_contact(gimbal_fmu, RICH_POINT) if point.startswith("rich") else dict(RIGID_POINT)
    if point.endswith("with disturbances"):
        values.update(DISTURBANCES)
    values = {k: v for k, v in values.items() if not k.startswith("solver.")}
    linear = linearize(values, build_dir)
    start, inputs = split(gimbal_fmu, values)
    instance = ModelExchangeInstance(gimbal_fmu, start, lambda t: inputs)
    try:
        vr = gimbal_fmu.vr
        derivative_vrs = [vr(f"der({s})") for s in linear.states]
        outputs = [vr(o) for o in linear.outputs]
        for j, known in enumerate(linear.states + linear.inputs):
            got = np.array(instance.model.getDirectionalDerivative(derivative_vrs + outputs, [vr(known)], [1.0]))
            expected = np.concatenate([linear.A[:, j], linear.C[:, j]] if j < len(linear.states) else
                                      [linear.B[:, j - len(linear.states)], linear.D[:, j - len(linear.states)]])
            scale = max(1.0, float(np.max(np.abs(expected))))
            assert np.max(np.abs(got - expected)) <= 2e-6 * scale, (known, got - expected)  # measured 3e-7
            if j < len(linear.states):
                rows = len(linear.states)
                assert np.max(np.abs(got[:rows] - expected[:rows])) <= 1e-12 * scale, (known, got[:rows] - expected[:rows])
        # The analytic columns against differences of the derivatives themselves.
        x0 = states(instance)
        index = {d.variable.derivative.name: k for k, d in enumerate(gimbal_fmu.model_description.derivatives)}
        for name in linear.states:
            k = index[name]
            column = np.array(instance.model.getDirectionalDerivative(derivative_vrs, [vr(name)], [1.0]))
            h = 1e-6 * max(1.0, abs(x0[k]))
            sides = []
            for sign in (1.0, -1.0):
                x = x0.copy()
                x[k] += sign * h
                set_states(instance, x)
                sides.append(derivatives(instance)[[index[s] for s in linear.states]])
            set_states(instance, x0)
            difference = (sides[0] - sides[1]) / (2.0 * h)
            scale = max(1.0, float(np.max(np.abs(column))))
            assert np.max(np.abs(column - difference)) <= 1e-5 * scale, (name, column - difference)
        # A seed is linear: two knowns at once give the sum of their columns.
        pair = [vr(linear.states[0]), vr(linear.inputs[0])]
        both = np.array(instance.model.getDirectionalDerivative(derivative_vrs, pair, [2.0, -1.0]))
        assert np.allclose(both, 2.0 * linear.A[:, 0] - linear.B[:, 0], rtol=1e-5, atol=1e-5 * np.max(np.abs(both)))
    finally:
        instance.free()


# The hard cases' stiff and switching extremes (tests/model_core/integrators/test_hard_cases.py, docs/hard_cases.md).
HARD_CASES = {
    "gear k_s 1e8, small rotors": {"gear1.k_s": 1e8, "gear2.k_s": 1e8, "rotor1.I_zz": 1e-6, "rotor2.I_xx": 1e-6},
    "inductance 1e-7 H": {"motor1.L": 1e-7, "motor2.L": 1e-7},
    "shaft damping 1e-6": {"gear1.c_s": 1e-6, "gear2.c_s": 1e-6},
    "pure dead zone (c_s = 0)": {"gear1.c_s": 0.0, "gear2.c_s": 0.0},
    "wide backlash, free load": {"gear1.eta": 0.05, "gear2.eta": 0.05, "g": 0.0},
    "rotor friction near w_min": {"rotor1.T_max": 0.02, "rotor1.T_din": 0.015, "rotor2.T_max": 0.02,
                                  "rotor2.T_din": 0.015},
}


@pytest.mark.parametrize("case", sorted(HARD_CASES))
def test_the_event_iteration_ends_at_once_on_the_hard_cases(gimbal_fmu, case):
    start = dict(HARD_CASES[case], **{"base.fixed": True, "beta": 0.2, "beta_m": 12.0})
    me = simulate_model_exchange(gimbal_fmu, 0.05, start, square_wave(10.0, 0.01),
                                 input_events=np.arange(1, 5) * 0.01, outputs=["alpha", "beta", "events.total"],
                                 rtol=1e-7, repeats=2)
    assert np.all(np.isfinite(me["alpha"])) and np.all(np.isfinite(me["beta"]))
    assert me["events.total"][-1] > 0
    assert set(me["event_calls"]) == {1}


def test_states_and_indicators_in_initialization_mode_are_those_of_the_start(gimbal_fmu):
    """FMI 2.0 lets a host read the continuous states and event indicators in initialization mode:
    they are those of the start values, and equal what the instance has right after initialization
    (a rigid gear's rotor angle already N times its load's)."""
    from fmpy.fmi2 import FMU2Model

    md = gimbal_fmu.model_description
    model = FMU2Model(guid=md.guid, unzipDirectory=gimbal_fmu.unzipdir, modelIdentifier="Gimbal2Axis",
                      instanceName="init")
    model.instantiate()
    try:
        model.setupExperiment(startTime=0.0)
        gimbal_fmu.set_values(model, {"gear1.model": 0, "alpha": 0.2, "alpha_m": 5.0, "beta": 0.3, "i_R2": 0.5})
        model.enterInitializationMode()
        gimbal_fmu.set_values(model, {"u_R1": 30.0})
        indicators, states = md.numberOfEventIndicators, md.numberOfContinuousStates
        x0, z0 = np.zeros(states), np.zeros(indicators)
        pointer = lambda a: a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))  # noqa: E731
        model.getContinuousStates(pointer(x0), states)
        model.getEventIndicators(pointer(z0), indicators)
        model.exitInitializationMode()
        x1, z1 = np.zeros(states), np.zeros(indicators)
        model.getContinuousStates(pointer(x1), states)
        model.getEventIndicators(pointer(z1), indicators)
        assert np.array_equal(x0, x1) and np.array_equal(z0, z1)
        assert x0[0] == 0.2 and x0[1] == 0.2 * gimbal_fmu.start("gear1.N") and x0[9] == 0.5
        assert z0[0] == 1.0 and z0[1] == 1.0  # gear 1 is rigid: no backlash guards
        assert z0[4] == 1.0  # no voltage ramp: the clamp's guards are constant
    finally:
        model.terminate()
        model.freeInstance()


def test_model_exchange_functions_refuse_a_co_simulation_instance(gimbal_fmu):
    log = []
    slave = gimbal_fmu.instantiate("cs", log=log)
    try:
        get_nominals = slave.dll.fmi2GetNominalsOfContinuousStates
        get_nominals.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_double), ctypes.c_size_t]
        states = gimbal_fmu.model_description.numberOfContinuousStates
        nominals = np.zeros(states)
        assert get_nominals(slave.component, nominals.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), states) == 3
        assert any("fmi2GetNominalsOfContinuousStates is a Model Exchange function" in e.text for e in log)
    finally:
        slave.freeInstance()
