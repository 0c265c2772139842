"""The default integration core (solver.method = 4): what it must keep while it runs fast.

Snapshots do not disturb the trajectory, results do not depend on where time starts, a quasi-static
motor's limiter is decided again at every input change, the method switches to RODAS4 when the model
turns stiff and back when it stops being so, and the first stage is refreshed after every input jump.
"""
import numpy as np
import pytest

from gimbal2axis.fmu import simulate

RECORDED = ["alpha", "beta", "alpha_dot", "beta_dot", "i_R1", "i_R2", "theta_b1", "theta_b2", "T_E1",
            "los.omega[1]", "los.omega[2]", "los.omega[3]", "events.total", "solver.steps",
            "solver.rhs_evaluations", "solver.jacobian_evaluations", "solver.method_switches"]


def ship_inputs(t, y):
    """A moving base, a PD loop with a jump at every step: events, restarts and both methods."""
    return {"u_R1": 60.0 * (0.2 - y["alpha"]) - 1.5 * y["alpha_dot"],
            "u_R2": 80.0 * (-0.1 - y["beta"]) - 2.0 * y["beta_dot"],
            "base.gamma": 0.08 * np.sin(1.3 * t), "base.gamma_dot": 0.104 * np.cos(1.3 * t),
            "base.gamma_ddot": -0.1352 * np.sin(1.3 * t),
            "base.delta": 0.03 * np.sin(0.7 * t), "base.delta_dot": 0.021 * np.cos(0.7 * t),
            "base.delta_ddot": -0.0147 * np.sin(0.7 * t)}


def run_loop(fmu, stop_time, step, start_values, inputs, start_time=0.0, snapshot=None, clock="product"):
    """Like gimbal2axis.fmu.simulate, with a start time and an optional FMU-state action at every step:
    'get' (take and free a state), 'get-set' (take it, set it back, free it). The master's clock is
    start + k h ('product') or a running sum t += h ('sum')."""
    slave = fmu.instantiate()
    try:
        slave.setupExperiment(startTime=start_time)
        fmu.set_values(slave, start_values)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        n = int(round(stop_time / step))
        record = np.empty((n + 1, len(RECORDED)))
        record[0] = fmu.get_values(slave, RECORDED)
        latest = dict(zip(RECORDED, record[0]))
        master_time = start_time
        for k in range(n):
            t = k * step
            fmu.set_values(slave, inputs(t, latest))
            if snapshot is not None:
                state = slave.getFMUstate()
                if snapshot == "get-set":
                    slave.setFMUstate(state)
                slave.freeFMUstate(state)
            slave.doStep(currentCommunicationPoint=start_time + t if clock == "product" else master_time,
                         communicationStepSize=step)
            master_time += step
            record[k + 1] = fmu.get_values(slave, RECORDED)
            latest = dict(zip(RECORDED, record[k + 1]))
        slave.terminate()
    finally:
        slave.freeInstance()
    return {name: record[:, j] for j, name in enumerate(RECORDED)}


@pytest.mark.parametrize("method", [4, 5, 6, 7])
@pytest.mark.parametrize("action", ["get", "get-set"])
def test_snapshots_at_every_step_leave_the_trajectory_bit_identical(gimbal_fmu, method, action):
    start = {"solver.method": method}
    never = run_loop(gimbal_fmu, 0.3, 1e-3, start, ship_inputs)
    always = run_loop(gimbal_fmu, 0.3, 1e-3, start, ship_inputs, snapshot=action)
    assert never["events.total"][-1] > 5
    for name in RECORDED:
        assert np.array_equal(never[name], always[name]), name


def square_wave(t, y):
    return {"u_R1": 12.0 if int(t / 0.05) % 2 == 0 else -12.0, "u_R2": -12.0 if int(t / 0.03) % 2 == 0 else 12.0}


def motor1_square_wave(t, y):
    """+-12 V on motor 1, 25 steps of 1 ms each way (the step index, not t / h, decides the sign)."""
    return {"u_R1": 12.0 if int(round(t / 1e-3)) // 25 % 2 == 0 else -12.0}


@pytest.mark.parametrize("clock", ["product", "sum"])
@pytest.mark.parametrize("wave", ["motor 1", "both motors"])
def test_results_do_not_depend_on_the_start_time(gimbal_fmu, clock, wave):
    """Free swing under a +-12 V square wave, steps of 1 ms: at a start time of 1.7e9 the doubles lie
    2.4e-7 s apart, so the master's times (start + k h, or a running sum) carry the step only to about
    2e-4 of itself. The instance integrates each communicationStepSize on its own clock, the time since
    the start: every start time gives the same trajectory bit for bit, whichever way the master counts."""
    start = {"beta": 0.5, "base.fixed": True}
    inputs = motor1_square_wave if wave == "motor 1" else square_wave
    runs = [run_loop(gimbal_fmu, 0.5, 1e-3, start, inputs, start_time=t0, clock=clock)
            for t0 in (0.0, 123.456, 1e7, 1.7e9)]
    assert runs[0]["events.total"][-1] > 10
    for other in runs[1:]:
        for name in RECORDED:
            assert np.array_equal(other[name], runs[0][name]), name


def test_quasi_static_limiter_holds_the_current_and_matches_the_inductive_limit(gimbal_fmu):
    """+-24 V reversals with i_L = 2 A: the quasi-static current never exceeds the limit, and the motion
    is the L -> 0 limit of the inductive motor (first-order convergence in L)."""
    def reversals(t, y):
        return {"u_R1": 24.0 if int(t / 0.1) % 2 == 0 else -24.0}

    common = {"motor1.i_L": 2.0, "base.fixed": True, "dry_friction": False, "gear1.model": 0}
    outputs = ["alpha", "i_R1", "motor1.limited"]
    quasi = simulate(gimbal_fmu, 0.6, 1e-3, {**common, "motor1.model": 0}, reversals, outputs)
    assert np.max(np.abs(quasi["i_R1"])) <= 2.0 * (1 + 1e-12)
    # Held at the limit whenever the free current lies beyond it (here: right after every reversal).
    assert np.all(quasi["motor1.limited"][1:] != 0)
    errors = []
    for inductance in (1e-4, 1e-5):
        inductive = simulate(gimbal_fmu, 0.6, 1e-3, {**common, "motor1.L": inductance, "solver.rtol": 1e-8,
                                                    "solver.atol": 1e-10}, reversals, outputs)
        errors.append(np.max(np.abs(inductive["alpha"] - quasi["alpha"])))
    assert errors[1] < errors[0] / 5, errors  # converging as L -> 0
    assert errors[1] < 1e-3, errors


def gap_slews(t, y):
    return {"u_R2": 4.0 * np.sin(2 * np.pi * 2 * t) - 0.5 * y["beta_dot"]}


GAP_OUTPUTS = ["beta", "beta_dot", "theta_b2", "gear2.contact", "solver.method_switches",
               "solver.jacobian_evaluations", "events.backlash2"]


@pytest.mark.parametrize("damping", [0.5, 1e-6])
def test_the_free_play_relaxation_is_taken_exactly_and_does_not_make_the_model_stiff(gimbal_fmu, damping):
    """Little shaft damping makes the free-play state relax fast in the gap (eigenvalue -k_s/c_s: -4e4
    and -2e10 1/s here), but there it acts on nothing and its solution is known
    (theta_d - theta_b decays as exp(-k_s t / c_s), docs/physics.md 4.2): the explicit method takes it
    exactly and stays explicit, and agrees with CVODE BDF at a tight tolerance."""
    start = {"gear2.c_s": damping, "gear2.eta": 2e-3, "base.fixed": True, "dry_friction": False}
    fast = simulate(gimbal_fmu, 1.0, 1e-3, start, gap_slews, GAP_OUTPUTS)
    reference = simulate(gimbal_fmu, 1.0, 1e-3, {**start, "solver.method": 0, "solver.rtol": 1e-11,
                                                  "solver.atol": 1e-13}, gap_slews, GAP_OUTPUTS)
    assert reference["events.backlash2"][-1] >= 40  # the gear leaves its stops and comes back
    assert np.array_equal(fast["events.backlash2"], reference["events.backlash2"])
    assert fast["solver.method_switches"][-1] == 0
    assert np.max(np.abs(fast["beta"] - reference["beta"])) < 1e-6
    assert np.max(np.abs(fast["theta_b2"] - reference["theta_b2"])) < 1e-6
    # Dormand-Prince alone does the same: the exact relaxation is its own, not the switch's.
    alone = simulate(gimbal_fmu, 1.0, 1e-3, {**start, "solver.method": 5}, gap_slews, GAP_OUTPUTS)
    assert np.max(np.abs(alone["theta_b2"] - reference["theta_b2"])) < 1e-6


def reversing_voltage(t, y):
    """+-12 V on motor 2, reversed every 50 ms."""
    return {"u_R2": 12.0 if int(t / 0.05) % 2 == 0 else -12.0}


def test_a_run_that_turns_stiff_and_back_switches_methods_and_stays_accurate(gimbal_fmu):
    """A 1 uH armature (L/R = 4e-7 s) under a reversing voltage, its current limited to 1 A: held at the
    limit the current is no state and the model is not stiff; released at each reversal it is, for the
    microseconds the current takes to reach the other limit. The default switches to RODAS4 and back,
    does less work than either method alone, and agrees with CVODE BDF at a tight tolerance."""
    start = {"motor2.L": 1e-6, "motor2.i_L": 1.0, "base.fixed": True, "dry_friction": False}
    outputs = GAP_OUTPUTS + ["solver.rhs_evaluations", "events.total"]
    runs = {method: simulate(gimbal_fmu, 1.0, 1e-3, {**start, "solver.method": method}, reversing_voltage, outputs)
            for method in (4, 5, 6)}
    reference = simulate(gimbal_fmu, 1.0, 1e-3, {**start, "solver.method": 0, "solver.rtol": 1e-11,
                                                  "solver.atol": 1e-13}, reversing_voltage, outputs)
    fast = runs[4]
    assert fast["solver.method_switches"][-1] >= 2, fast["solver.method_switches"][-1]
    assert fast["events.total"][-1] == reference["events.total"][-1]
    assert np.max(np.abs(fast["beta"] - reference["beta"])) < 1e-6

    def work(run):  # right-hand sides, and a Jacobian with its LU as about 17 of them
        return run["solver.rhs_evaluations"][-1] + 17 * run["solver.jacobian_evaluations"][-1]
    assert work(fast) < min(work(runs[5]), work(runs[6])), [work(r) for r in runs.values()]


@pytest.mark.parametrize("rtol", [1e-5, 1e-6])
def test_rodas4_does_not_locate_an_event_inside_a_boundary_layer_it_passed_over(gimbal_fmu, rtol):
    """A 1 uH armature under +-12 V reversals: at each reversal the current crosses from one limit to the
    other within a microsecond. RODAS4's filtered error estimate lets a step pass over that boundary
    layer, but the limit reached inside it must not be located on the step's interpolant: the released
    current's torque over the layer and the event's time would be wrong (beta was 3e-3 rad off at
    rtol 1e-5 and 1.4e-4 at 1e-6, with backlash events that did not happen). RODAS4 alone, at default
    and looser tolerances, agrees with CVODE BDF at a tight one, event for event."""
    outputs = ["beta", "beta_dot", "events.total", "events.backlash2", "events.current_limit2"]
    for limit in (1.0, 3.0):
        start = {"motor2.L": 1e-6, "motor2.i_L": limit, "base.fixed": True, "dry_friction": False}
        reference = simulate(gimbal_fmu, 0.2, 1e-3, {**start, "solver.method": 0, "solver.rtol": 1e-11,
                                                      "solver.atol": 1e-13}, reversing_voltage, outputs)
        rodas = simulate(gimbal_fmu, 0.2, 1e-3, {**start, "solver.method": 6, "solver.rtol": rtol,
                                                  "solver.atol": 1e-2 * rtol}, reversing_voltage, outputs)
        for counter in outputs[2:]:
            assert rodas[counter][-1] == reference[counter][-1], (limit, counter)
        assert np.max(np.abs(rodas["beta"] - reference["beta"])) < rtol, limit


# At the edge of stiffness: rigid gears, a motor of 2 uH (L/R about 1e-6 s) under a PD loop whose
# voltage jumps at every step. RODAS4 takes steps of about 0.2 ms, the explicit method could only take
# ones of about 1 us; after each jump both take short steps through the transient, at which the
# explicit method is stable. The rule that switched by votes alone handed over to the explicit method in
# every transient and back at its stability limit: 122 switches in 300 steps (424 at rtol 1e-8).
EDGE = {"gear1.model": 0, "gear2.model": 0, "motor1.model": 1, "motor2.model": 1, "motor1.L": 2e-6,
        "motor2.L": 7e-3, "motor1.i_L": 3.5, "motor2.i_L": 4.8, "dry_friction": True}


def square_wave_loop(t, y):
    reference = 0.2 * np.sign(np.sin(2 * np.pi * 2 * t))
    return {"u_R1": 100.0 * (reference - y["alpha"]) - 2 * y["alpha_dot"],
            "u_R2": 100.0 * (-reference - y["beta"]) - 2 * y["beta_dot"]}


def test_at_the_edge_of_stiffness_the_method_switches_by_predicted_cost(gimbal_fmu):
    """The switch rule compares the two methods' predicted costs: a few switches, no more work than
    RODAS4 alone, and the accuracy of either method (against CVODE BDF at rtol 1e-11)."""
    outputs = ["alpha", "beta", "alpha_dot", "beta_dot", "solver.method_switches", "solver.rhs_evaluations",
               "solver.jacobian_evaluations"]
    run = lambda extra: simulate(gimbal_fmu, 0.3, 1e-3, {**EDGE, **extra}, square_wave_loop, outputs)  # noqa: E731
    reference = run({"solver.method": 0, "solver.rtol": 1e-11, "solver.atol": 1e-13})
    automatic, rosenbrock = run({}), run({"solver.method": 6})
    tight = run({"solver.rtol": 1e-8, "solver.atol": 1e-10})
    assert automatic["solver.method_switches"][-1] <= 10, automatic["solver.method_switches"][-1]
    assert tight["solver.method_switches"][-1] <= 10, tight["solver.method_switches"][-1]
    for name in ("solver.rhs_evaluations", "solver.jacobian_evaluations"):
        assert automatic[name][-1] <= 1.05 * rosenbrock[name][-1], (name, automatic[name][-1], rosenbrock[name][-1])
    for name in ("alpha", "beta"):
        assert np.max(np.abs(automatic[name] - reference[name])) < 1e-8, name
        assert np.max(np.abs(tight[name] - reference[name])) < 1e-10, name


def test_snapshots_carry_the_switch_rule_memory(gimbal_fmu):
    """The switch rule remembers steps across communication points (the accuracy step, the explicit
    method's stable step, the last input jump): an FMU state taken and set back at every step must
    leave a run that switches methods bit for bit as it was."""
    never = run_loop(gimbal_fmu, 0.1, 1e-3, EDGE, square_wave_loop)
    always = run_loop(gimbal_fmu, 0.1, 1e-3, EDGE, square_wave_loop, snapshot="get-set")
    assert never["solver.method_switches"][-1] >= 1
    for name in RECORDED:
        assert np.array_equal(never[name], always[name]), name


def test_input_jumps_refresh_the_first_stage(gimbal_fmu):
    """Voltages that jump at every step: Dormand-Prince alone (FSAL) against a tight reference. A first
    stage left over from the previous step's voltage would err by about h * L^-1 * jump in the current."""
    def jumps(t, y):
        return {"u_R1": 10.0 * (-1) ** int(t / 1e-3), "u_R2": -6.0 * (-1) ** int(t / 2e-3)}

    outputs = ["i_R1", "i_R2", "alpha", "beta"]
    fast = simulate(gimbal_fmu, 0.05, 1e-3, {"solver.method": 5}, jumps, outputs)
    reference = simulate(gimbal_fmu, 0.05, 1e-3, {"solver.method": 0, "solver.rtol": 1e-11,
                                                  "solver.atol": 1e-13}, jumps, outputs)
    for name in ("i_R1", "i_R2"):
        assert np.max(np.abs(fast[name] - reference[name])) < 1e-5, name


def test_a_ramp_starting_exactly_on_the_voltage_clamp_leaves_it(gimbal_fmu):
    """u_R1 = U_L exactly, ramping down: the clamp's guard starts at zero, and the mode must be the one
    the ramp leaves to (following the ramp), as it is for a start a hair below U_L."""
    def current_after_ramp(start_voltage):
        slave = gimbal_fmu.instantiate()
        try:
            slave.setupExperiment(startTime=0.0)
            gimbal_fmu.set_values(slave, {"motor1.i_L": 1e3})
            slave.enterInitializationMode()
            slave.exitInitializationMode()
            gimbal_fmu.set_values(slave, {"u_R1": 5.0})
            for k in range(100):
                slave.doStep(currentCommunicationPoint=k * 1e-3, communicationStepSize=1e-3)
            gimbal_fmu.set_values(slave, {"u_R1": start_voltage})
            slave.setRealInputDerivatives([gimbal_fmu.vr("u_R1")], [1], [-2000.0])
            slave.doStep(currentCommunicationPoint=0.1, communicationStepSize=0.01)
            current = gimbal_fmu.get_values(slave, ["i_R1"])[0]
            slave.terminate()
            return current
        finally:
            slave.freeInstance()

    on_clamp, below = current_after_ramp(24.0), current_after_ramp(24.0 - 1e-12)
    assert abs(on_clamp - below) < 1e-6 * max(1.0, abs(below)), (on_clamp, below)
