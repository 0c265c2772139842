"""Hard cases for the numerical stability of the FMU.

Every test asserts physical or hybrid invariants that a broken integrator would violate, not only that
the run finished. Run on its own with `pytest tests/model_core/integrators/test_hard_cases.py`; each test also records its
measured error and cost (solver.steps, solver.rhs_evaluations, wall time): with HARD_CASES_JSON set,
they are appended to that file as JSON lines (`scripts/hard_cases_table.py` turns them into the table of
docs/hard_cases.md). Reduced versions (shorter horizons) are marked as such in their docstrings.
"""
from __future__ import annotations

import json
import math
import os
import time

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from gimbal2axis.fmu import simulate

from support.expected_names import STATES

COST = ["solver.steps", "solver.rhs_evaluations"]
STORED = ["energy.kinetic", "energy.potential", "energy.spring", "energy.magnetic"]
DISSIPATED = ["energy.resistive", "energy.viscous", "energy.shaft_damping", "energy.dry_friction"]
ENERGY = STORED + ["energy.electrical_in"] + DISSIPATED
METHOD_NAMES = {0: "BDF analytic J", 1: "BDF diff. quotients", 2: "Adams", 3: "explicit RK",
                4: "automatic, default", 5: "Dormand-Prince", 6: "RODAS4"}


def record(case, asserted, error, result=None, wall=None, note=""):
    """Appends one measurement to $HARD_CASES_JSON (if set) and prints it (visible with pytest -s)."""
    entry = {"case": case, "asserted": asserted, "error": error, "note": note,
             "steps": int(result["solver.steps"][-1]) if result is not None else None,
             "rhs": int(result["solver.rhs_evaluations"][-1]) if result is not None else None,
             "wall": wall if wall is not None else (result.get("wall") if result is not None else None)}
    print(json.dumps(entry))
    path = os.environ.get("HARD_CASES_JSON")
    if path:
        with open(path, "a") as f:
            f.write(json.dumps(entry) + "\n")


def timed(fmu, stop, step, start, inputs=None, outputs=("alpha", "beta")):
    t0 = time.perf_counter()
    r = simulate(fmu, stop, step, start, inputs, list(dict.fromkeys(list(outputs) + COST)))
    r["wall"] = time.perf_counter() - t0
    return r


def balance_residual(r):
    stored = sum(r[n] for n in STORED)
    return r["energy.electrical_in"] - (stored - stored[0]) - sum(r[n] for n in DISSIPATED)


def max_diff(a, b, names=("alpha", "beta")):
    return max(float(np.max(np.abs(a[n] - b[n]))) for n in names)


# ====================================================================================================
# 1. Stiff limits: very stiff gears, tiny inductance, tiny shaft damping, against their limit models

def pd_loop(t, y):
    """PD loop with a set-point step at 0.1 s: the drive train carries real, reversing torques."""
    ta, tb = (0.3, -0.1) if t < 0.1 else (-0.2, 0.25)
    return {"u_R1": 40.0 * (ta - y["alpha"]) - 2.0 * y["alpha_dot"],
            "u_R2": 40.0 * (tb - y["beta"]) - 2.0 * y["beta_dot"]}


LOOP_OUT = ["alpha", "beta", "alpha_dot", "beta_dot"]
STIFF_BASE = {"dry_friction": False, "solver.rtol": 1e-8, "solver.atol": 1e-10, "beta": 0.2,
              "base.fixed": True}
SMALL_ROTORS = {"rotor1.I_zz": 1e-6, "rotor2.I_xx": 1e-6}  # 36 and 15 times below the defaults
STOP = 0.2


@pytest.fixture(scope="module")
def rigid_reference(gimbal_fmu):
    return timed(gimbal_fmu, STOP, 1e-3, dict(STIFF_BASE, **SMALL_ROTORS, **{"gear1.model": 0, "gear2.model": 0}),
                 pd_loop, LOOP_OUT)


def stiff_gear(fmu, k_s, method=0):
    return timed(fmu, STOP, 1e-3, dict(STIFF_BASE, **SMALL_ROTORS, **{
        "gear1.model": 1, "gear2.model": 1, "gear1.k_s": k_s, "gear2.k_s": k_s, "beta_m": 60 * 0.2,
        "solver.method": method}), pd_loop, LOOP_OUT)


def test_stiff_gear_error_falls_with_stiffness_towards_the_rigid_gear(gimbal_fmu, rigid_reference):
    errors = {k: max_diff(stiff_gear(gimbal_fmu, k), rigid_reference) for k in (1e6, 1e7)}
    record("k_s 1e6 -> 1e7 vs rigid gear (BDF)", "error falls ~10x per decade of k_s",
           f"{errors[1e6]:.1e} -> {errors[1e7]:.1e} rad", rigid_reference, note="cost column: the rigid model")
    assert errors[1e6] / errors[1e7] > 5, errors


@pytest.mark.parametrize("method", [0, 1, 2, 3, 4, 6])
def test_gear_stiffness_1e8_with_small_rotor_inertia_matches_rigid_gear(gimbal_fmu, rigid_reference, method):
    """k_s = 1e8 N.m/rad on both axes, rotor inertias 1e-6 kg.m2: the shaft mode is near 1e5 rad/s. Every
    integrator must finish, stay within deflection ~ torque / k_s of the rigid gear and keep bounded cost."""
    r = stiff_gear(gimbal_fmu, 1e8, method)
    error = max_diff(r, rigid_reference)
    record(f"k_s = 1e8, rotor I = 1e-6, method {method} ({METHOD_NAMES[method]})",
           "|angle - rigid| < 3e-7 rad; steps < 1000 per comm. step", f"{error:.1e} rad", r)
    assert error < 3e-7
    assert r["solver.steps"][-1] < 1000 * STOP / 1e-3
    assert np.ptp(r["alpha"]) > 0.1  # the loop really slewed


@pytest.fixture(scope="module")
def quasi_static_reference(gimbal_fmu):
    return timed(gimbal_fmu, STOP, 1e-3, dict(STIFF_BASE, **{"motor1.model": 0, "motor2.model": 0, "beta_m": 12.0}),
                 pd_loop, LOOP_OUT + ["i_R1", "i_R2"])


def small_inductance(fmu, inductance, method=0, stop=STOP):
    return timed(fmu, stop, 1e-3, dict(STIFF_BASE, **{"motor1.L": inductance, "motor2.L": inductance,
                                                      "beta_m": 12.0, "solver.method": method}),
                 pd_loop, LOOP_OUT + ["i_R1", "i_R2", "motor1.limited"])


@pytest.mark.parametrize("method", [0, 1, 2, 4, 6])
def test_inductance_1e7_matches_the_quasi_static_motor(gimbal_fmu, quasi_static_reference, method):
    """L = 1e-7 H: electrical time constant 5e-8 s. The error against the algebraic current falls with L."""
    r = small_inductance(gimbal_fmu, 1e-7, method)
    error = max_diff(r, quasi_static_reference)
    record(f"L = 1e-7 H, method {method} ({METHOD_NAMES[method]})", "|angle - quasi-static| < 2e-7 rad",
           f"{error:.1e} rad", r)
    assert error < 2e-7
    assert np.max(np.abs(r["i_R1"])) <= 4.0 and set(r["motor1.limited"]) >= {1.0}
    if method == 0:
        coarse = max_diff(small_inductance(gimbal_fmu, 1e-5), quasi_static_reference)
        assert coarse / error > 30, (coarse, error)  # first-order convergence over two decades


def test_explicit_rk_cost_grows_as_one_over_inductance(gimbal_fmu, quasi_static_reference):
    """Reduced (0.02 s): explicit RK copes with small L only at a cost ~ 1/L (stability-limited steps):
    measured over the full 0.3 s scene, 1.8 million steps and 37 s at L = 1e-7."""
    runs = {L: small_inductance(gimbal_fmu, L, 3, stop=0.02) for L in (1e-5, 1e-6)}
    ratio = runs[1e-6]["solver.steps"][-1] / runs[1e-5]["solver.steps"][-1]
    record("L = 1e-6 H, method 3 (explicit RK), 0.02 s", "finishes; cost ~ 1/L (steps ratio > 5 per decade)",
           f"steps x{ratio:.1f} per decade", runs[1e-6])
    assert ratio > 5


def shaft_damping(fmu, c_s, method=0, extra=None):
    return timed(fmu, STOP, 1e-3, dict(STIFF_BASE, **{"gear1.c_s": c_s, "gear2.c_s": c_s, "beta_m": 12.0,
                                                      "solver.method": method}, **(extra or {})),
                 pd_loop, LOOP_OUT + ["alpha_m", "beta_m", "theta_b1", "theta_b2", "events.backlash1",
                                      "events.backlash2", "gear1.contact"])


@pytest.fixture(scope="module")
def dead_zone(gimbal_fmu):
    return shaft_damping(gimbal_fmu, 0.0)


def test_zero_shaft_damping_is_the_pure_dead_zone(gimbal_fmu, dead_zone):
    """c_s = 0 with eta > 0: theta_b = clamp(theta_d, -eta, eta) exactly, the gears still cross their gaps."""
    eta = 2e-4
    for axis, n in ((1, 80.0), (2, 60.0)):
        q_m, q_l = (dead_zone["alpha_m"], dead_zone["alpha"]) if axis == 1 else (dead_zone["beta_m"], dead_zone["beta"])
        error = np.max(np.abs(dead_zone[f"theta_b{axis}"] - np.clip(q_m / n - q_l, -eta, eta)))
        assert error < 1e-15
        assert dead_zone[f"events.backlash{axis}"][-1] >= 10
    record("c_s = 0 (dead zone), BDF", "theta_b = clamp(theta_d, +-eta) exactly; gaps crossed",
           f"{error:.0e} rad", dead_zone)


# Method 2 (Adams) used to lose theta_b past a stop here: at a gap-to-stop root the contact rule
# trusted sign(X), which at k_s/c_s = 3e10 is round-off; a located outward crossing now always engages.
@pytest.mark.parametrize("method", [0, 1, 2, 4, 6])
def test_shaft_damping_1e6_matches_the_dead_zone(gimbal_fmu, dead_zone, method):
    r = shaft_damping(gimbal_fmu, 1e-6, method)
    error = max_diff(r, dead_zone)
    worst = max(np.max(np.abs(r["theta_b1"])), np.max(np.abs(r["theta_b2"])))
    record(f"c_s = 1e-6, method {method} ({METHOD_NAMES[method]})", "|angle - dead zone| < 2e-7; |theta_b| <= eta",
           f"{error:.1e} rad; max|theta_b| {worst:.3e}", r)
    assert worst <= 2e-4
    assert error < 2e-7
    coarse = max_diff(shaft_damping(gimbal_fmu, 1e-4, method), dead_zone) if method == 0 else None
    if coarse is not None:
        assert coarse > 10 * error  # converges as c_s -> 0


def test_shaft_damping_1e6_with_explicit_rk_is_discarded_not_garbage(gimbal_fmu):
    """k_s/c_s = 3e10 1/s is beyond any explicit method: the step must be discarded with the reason."""
    log = []
    slave = gimbal_fmu.instantiate("rk", log=log)
    t0 = time.perf_counter()
    try:
        slave.setupExperiment(startTime=0.0)
        gimbal_fmu.set_values(slave, dict(STIFF_BASE, **{"gear1.c_s": 1e-6, "gear2.c_s": 1e-6, "beta_m": 12.0,
                                                         "solver.method": 3, "solver.max_steps": 20000}))
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        gimbal_fmu.set_values(slave, {"u_R1": 10.0, "u_R2": -10.0})
        before = gimbal_fmu.get_values(slave, STATES)
        outcome = "completed"
        try:
            for k in range(20):
                slave.doStep(k * 1e-3, 1e-3)
        except FMICallException:
            outcome = "discarded"
        after = gimbal_fmu.get_values(slave, STATES + ["theta_b1", "theta_b2"])
    finally:
        slave.freeInstance()
    wall = time.perf_counter() - t0
    record("c_s = 1e-6, method 3 (explicit RK)", "discarded with ARK_TOO_MUCH_WORK, state finite and in the gap",
           outcome, None, wall, note="explicit RK does not cope")
    if outcome == "discarded":
        assert any(status == 2 and "TOO_MUCH_WORK" in text for status, _, text in log), log
    assert np.all(np.isfinite(after)) and max(abs(after[-1]), abs(after[-2])) <= 2e-4
    del before


# ====================================================================================================
# 2. Backlash extremes

FREE_LOAD = {"g": 0.0, "body2.I_xy": 0.0, "body2.I_xz": 0.0, "body2.I_yz": 0.0, "body2.d_bd[1]": 0.0,
             "body2.d_bd[2]": 0.0, "body2.d_bd[3]": 0.0, "body2.c_visc": 0.0, "rotor2.c_visc": 0.0,
             "rotor2.T_max": 0.0, "rotor2.T_din": 0.0, "motor2.k_torque": 0.0, "motor2.k_emf": 0.0,
             "solver.rtol": 1e-10, "solver.atol": 1e-12,
             "gear2.start": 2}  # as_given: rotor 2 stays at rest while its load coasts (not in mesh)


def test_large_backlash_load_flies_freely_through_the_gap(gimbal_fmu):
    """eta = 0.25 rad: the load coasts at constant speed with T_E = 0 exactly, and meets the stop at
    eta / speed (and rebounds a few ms later, so the run stops 1 ms after the contact)."""
    eta, speed = 0.25, 1.0
    r = timed(gimbal_fmu, 0.251, 1e-3, dict(FREE_LOAD, **{"gear2.eta": eta, "beta_dot": -speed}), None,
              ["beta_dot", "T_E2", "theta_b2", "gear2.contact", "events.backlash2", "events.last_time"])
    t_contact = eta / speed
    before = r["time"] < t_contact
    flight = np.max(np.abs(r["beta_dot"][before] + speed))
    error = abs(r["events.last_time"][-1] - t_contact)
    record("eta = 0.25 rad, free flight", "T_E = 0 and constant speed in the gap; contact at eta/speed",
           f"speed {flight:.0e} rad/s; contact time {error:.0e} s", r)
    assert np.all(r["T_E2"][before] == 0.0) and flight < 1e-12
    assert r["events.backlash2"][-1] == 1 and error < 1e-9
    assert np.max(np.abs(r["theta_b2"])) <= eta


def test_zero_backlash_never_switches_and_equals_the_compliant_gear(gimbal_fmu):
    reversing = lambda t, y: {"u_R1": 20.0 if int(t / 0.02) % 2 == 0 else -20.0, "u_R2": -15.0 if int(t / 0.03) % 2 else 15.0}
    out = LOOP_OUT + ["theta_b1", "theta_b2", "events.backlash1", "events.backlash2"]
    base = {"gear1.eta": 0.0, "gear2.eta": 0.0, "beta_m": 12.0, "beta": 0.2, "solver.rtol": 1e-10, "solver.atol": 1e-12}
    slot = timed(gimbal_fmu, 0.2, 1e-3, base, reversing, out)
    compliant = timed(gimbal_fmu, 0.2, 1e-3, dict(base, **{"gear1.model": 1, "gear2.model": 1}), reversing, out)
    error = max_diff(slot, compliant)
    record("eta = 0 (model 2)", "no backlash event, theta_b = 0, = compliant model", f"{error:.0e} rad", slot)
    assert slot["events.backlash1"][-1] == 0 and slot["events.backlash2"][-1] == 0
    assert np.all(slot["theta_b1"] == 0.0) and np.all(slot["theta_b2"] == 0.0)
    assert error < 1e-8


# ====================================================================================================
# 3. Backlash chatter

def contact_walk_is_consistent(contact, counter):
    """Contact moves on the path -1 - 0 - +1 one event at a time: over every communication step the
    counter rose by at least the distance travelled, with the same parity (the path graph is bipartite).
    A missed or a doubled crossing breaks it."""
    delta = np.diff(counter)
    moved = np.abs(np.diff(contact))
    return bool(np.all(delta >= moved) and np.all((delta - moved) % 2 == 0))


def check_backlash_invariants(r, axis, eta):
    theta_b, torque, contact = r[f"theta_b{axis}"], r[f"T_E{axis}"], r[f"gear{axis}.contact"]
    assert np.max(np.abs(theta_b)) <= eta
    assert np.all(torque[contact == 0] == 0.0)
    assert np.all(torque[contact == 1] >= 0.0) and np.all(torque[contact == -1] <= 0.0)
    assert np.all(theta_b[contact == 1] == eta) and np.all(theta_b[contact == -1] == -eta)
    assert contact_walk_is_consistent(contact, r[f"events.backlash{axis}"])


CHATTER_OUT = ["theta_b1", "T_E1", "gear1.contact", "events.backlash1", "events.zeno_guard", "events.total"]


def test_backlash_chatter_for_10_s_with_closed_energy_balance(gimbal_fmu):
    """Fixed base (so that no base work enters the books), azimuth motor driven by an 80 Hz, 8 V sine
    (zero-order hold, 1 ms): the azimuth gear crosses its gap from stop to stop ~320 times a second
    for 10 s (full length)."""
    eta = 2e-4
    r = timed(gimbal_fmu, 10.0, 1e-3, {"base.fixed": True, "dry_friction": False, "energy_accounting": True,
                                        "solver.rtol": 1e-8, "solver.atol": 1e-10},
              lambda t, y: {"u_R1": 8.0 * math.sin(2 * math.pi * 80.0 * t)}, CHATTER_OUT + ENERGY)
    events = r["events.backlash1"][-1]
    residual = np.max(np.abs(balance_residual(r)))
    throughput = r["energy.electrical_in"][-1] + 0.0
    scale = max(throughput, np.max(r["energy.resistive"]))
    record("backlash chatter 80 Hz, 10 s, fixed base", "every crossing located (walk/parity), |theta_b| <= eta, "
           "no Zeno hold, energy balance", f"{events:.0f} crossings; balance {residual / scale:.1e} of throughput", r)
    assert events / 10.0 > 200  # hundreds of contact changes a second
    assert r["events.zeno_guard"][-1] == 0
    check_backlash_invariants(r, 1, eta)
    assert residual < 1e-6 * scale, (residual, scale)


def test_backlash_chatter_with_a_base_vibrating_near_the_shaft_mode(gimbal_fmu):
    """Reduced (1 s): the carrier yaws at 80 Hz, +-0.5 mrad (exact constant-acceleration arcs, 1 ms);
    the azimuth load rattles in its gap. Invariants only: the base work is not integrated by the FMU."""
    h, f, amp = 1e-3, 80.0, 5e-4
    w = 2 * math.pi * f

    def base(t, y):
        # attitude and rate at t, acceleration held over the step (the arc the FMU integrates)
        return {"base.psi": amp * math.sin(w * t), "base.psi_dot": amp * w * math.cos(w * t),
                "base.psi_ddot": -amp * w * w * math.sin(w * (t + h / 2))}

    r = timed(gimbal_fmu, 1.0, h, {"dry_friction": False, "solver.rtol": 1e-8, "solver.atol": 1e-10}, base,
              CHATTER_OUT)
    record("backlash chatter, yawing base 80 Hz, 1 s", "walk/parity, |theta_b| <= eta, no Zeno hold",
           f"{r['events.backlash1'][-1]:.0f} crossings", r, note="reduced: 1 s")
    assert r["events.backlash1"][-1] > 200
    assert r["events.zeno_guard"][-1] == 0
    check_backlash_invariants(r, 1, 2e-4)


# ====================================================================================================
# 4. Stick-slip at the threshold

ROTOR1_ALONE = {"gear1.k_s": 0.0, "gear1.c_s": 0.0, "gear1.eta": 0.0, "rotor1.c_visc": 0.0, "g": 0.0,
                "base.fixed": True, "solver.rtol": 1e-10, "solver.atol": 1e-12}


def test_rotor_speed_hovering_around_w_min(gimbal_fmu):
    """T_din = 0.00298 just below T_max = 0.003 and u just above the breakaway voltage: the steady slip
    speed is near w_min = 0.01 rad/s, and a 3 Hz ripple makes the rotor stick, break away and slip
    over and over."""
    w_min = 0.01
    r = timed(gimbal_fmu, 2.0, 1e-3, dict(ROTOR1_ALONE, **{"rotor1.T_din": 0.00298, "energy_accounting": True}),
              lambda t, y: {"u_R1": 0.1003 + 0.001 * math.sin(2 * math.pi * 3 * t)},
              ["alpha_m_dot", "rotor1.stick_slip", "events.stick_slip", "events.zeno_guard"] + ENERGY)
    w, mode = r["alpha_m_dot"], r["rotor1.stick_slip"]
    residual = np.max(np.abs(balance_residual(r))) / r["energy.electrical_in"][-1]
    record("speed hovering around w_min, 2 s", "mode agrees with |w| vs w_min; stick/slip cycles; energy balance",
           f"{r['events.stick_slip'][-1]:.0f} switches; balance {residual:.1e}", r)
    assert {0, 1, 2} <= set(mode.astype(int))
    assert r["events.stick_slip"][-1] >= 10 and r["events.zeno_guard"][-1] == 0
    assert np.all(np.abs(w[np.abs(mode) == 2]) >= w_min * (1 - 1e-9))
    assert np.all(np.abs(w[np.abs(mode) <= 1]) <= w_min * (1 + 1e-9))
    assert np.all(w >= -1e-12)  # friction never drives it backwards
    assert residual < 1e-7


def test_tie_at_t_max_breaks_away_and_just_below_holds(gimbal_fmu):
    """k_torque = R = 1, k_emf = 0: a current of exactly T_max gives a motor torque of exactly T_max."""
    t_max = 0.003

    def run(torque):
        start = dict(ROTOR1_ALONE, **{"motor1.k_torque": 1.0, "motor1.R": 1.0, "motor1.k_emf": 0.0, "i_R1": torque})
        return timed(gimbal_fmu, 0.1, 1e-3, start, lambda t, y: {"u_R1": torque},
                     ["alpha_m_dot", "rotor1.stick_slip", "events.stick_slip"])
    tie, below = run(t_max), run(t_max * (1 - 1e-9))
    record("tie |T_outros| = T_max", "breaks away (mode 1, a tie breaks away); 1e-9 below: held (mode 0)",
           f"speed {np.max(np.abs(tie['alpha_m_dot'])):.0e} rad/s", tie)
    assert np.all(tie["rotor1.stick_slip"][1:] == 1)
    assert np.all(below["rotor1.stick_slip"] == 0)
    assert np.max(np.abs(tie["alpha_m_dot"])) < 1e-12 and np.max(np.abs(below["alpha_m_dot"])) < 1e-12


def test_slowly_growing_torque_breaks_away_at_t_max(gimbal_fmu):
    """Voltage ramp held per 1 ms step, k_emf = 0: the current follows exact RL arcs, and the rotor must
    break away at the instant k_torque * i = T_max (computed in closed form)."""
    R, L, kt, t_max, h, slope = 2.0, 2e-3, 0.06, 0.003, 1e-3, 0.5
    r = timed(gimbal_fmu, 0.3, h, dict(ROTOR1_ALONE, **{"motor1.k_emf": 0.0}),
              lambda t, y: {"u_R1": slope * t}, ["i_R1", "rotor1.stick_slip", "events.last_time", "events.stick_slip"])
    k = int(np.argmax(r["rotor1.stick_slip"] != 0))  # first sample after the breakaway
    assert k > 0 and r["events.stick_slip"][k] >= 1
    # exact current at the start of step k-1, then the RL arc within it
    i, tau = 0.0, L / R
    for j in range(k - 1):
        u = slope * j * h
        i = u / R + (i - u / R) * math.exp(-h / tau)
    u = slope * (k - 1) * h
    target = t_max / kt
    t_break = (k - 1) * h + tau * math.log((i - u / R) / (target - u / R))
    first_event = r["events.last_time"][k] if r["events.stick_slip"][k] == 1 else None
    assert first_event is not None
    error = abs(first_event - t_break)
    record("slowly growing torque (0.015 N.m/s)", "breakaway when k_torque i = T_max (closed form)",
           f"{error:.0e} s = {error * 0.015 / t_max:.0e} of T_max", r)
    assert error < 1e-8


def test_several_bodies_stuck_at_once_then_load_breaks_away_at_its_t_max(gimbal_fmu):
    """Dry friction on all four bodies; payload off its axis (gravity torque) and held. All four are
    stuck together; a slow voltage ramp breaks rotor 1 away, winds gear 1, and body 1 (vertical axis, no
    gravity torque) breaks away when the shaft torque T_E1 reaches body1.T_max."""
    t_max1 = 0.4
    start = {"body1.T_max": t_max1, "body1.T_din": 0.3, "body2.T_max": 2.0, "body2.T_din": 1.5,
             "gear1.eta": 0.0, "gear2.eta": 0.0, "base.fixed": True, "motor1.k_emf": 0.0,
             "solver.rtol": 1e-10, "solver.atol": 1e-12, "beta_m": 0.0}
    out = ["T_E1", "T_E2", "alpha", "beta", "body1.stick_slip", "body2.stick_slip", "rotor1.stick_slip",
           "rotor2.stick_slip", "events.stick_slip", "events.zeno_guard"]
    r = timed(gimbal_fmu, 1.0, 1e-3, start, lambda t, y: {"u_R1": 0.0 if t < 0.1 else 1.0 * (t - 0.1)}, out)
    quiet = r["time"] <= 0.1
    modes = ["body1.stick_slip", "body2.stick_slip", "rotor1.stick_slip", "rotor2.stick_slip"]
    assert all(np.all(r[m][quiet][1:] == 0) for m in modes)  # all four held at once
    # The payload hangs off its axis (gravity torque m g d_bd[2] ~ 1 N.m < body2.T_max): held, it creeps
    # at most w_min t.
    assert np.all(np.abs(r["beta"]) <= 1e-3 * r["time"] + 1e-15)
    k = int(np.argmax(r["body1.stick_slip"] != 0))
    assert k > 0
    # The breakaway lies between the two samples around it: judged to the torque growth over one step.
    rate = abs(r["T_E1"][k - 1] - r["T_E1"][k - 2])
    error = abs(abs(r["T_E1"][k - 1]) - t_max1)
    record("4 bodies stuck; body 1 breaks away under growing T_E1", "all held; breakaway when |T_E1| = T_max",
           f"|T_E1| - T_max before event {error:.1e} N.m (step change {rate:.1e})", r)
    assert abs(r["T_E1"][k - 1]) <= t_max1 * (1 + 1e-9) and abs(r["T_E1"][k - 1]) > t_max1 - 2 * rate
    assert np.all(r["body2.stick_slip"] == 0)  # the payload stays held throughout
    assert r["events.zeno_guard"][-1] == 0


# ====================================================================================================
# 5. Current limit and voltage clamp together

def test_current_limit_and_voltage_clamp_with_reversals_while_limited(gimbal_fmu):
    """+-1000 V (clamped to U_L = 24 V) reversing every 20 ms while the limiter holds +-i_L = 4 A: after
    each reversal the current leaves the limit at once and reaches the other limit at
    (L/R) ln((i_L + U_L/R)/(U_L/R - i_L)) = (L/R) ln 2 later - the clamped voltage, not 1000 V."""
    R, L, i_L, U_L, period = 2.0, 2e-3, 4.0, 24.0, 0.02
    voltage = lambda t, y: {"u_R1": (1000.0 if int(round(t / 1e-3)) // 20 % 2 == 0 else -1000.0) if t < 0.19 else 1e9}
    r = timed(gimbal_fmu, 0.2, 1e-3, dict(ROTOR1_ALONE, **{"motor1.k_emf": 0.0, "rotor1.T_max": 0.0, "rotor1.T_din": 0.0}),
              voltage, ["i_R1", "motor1.limited", "events.current_limit1", "events.last_time"])
    assert np.max(np.abs(r["i_R1"])) <= i_L
    delay = L / R * math.log((i_L + U_L / R) / (U_L / R - i_L))
    errors = []
    for n in range(1, 10):
        k = n * 20 + 1  # sample after the reversal step
        errors.append(abs(r["events.last_time"][k] - (n * period + delay)))
        assert r["motor1.limited"][k] == (1 if n % 2 == 0 else -1)
    # engage, then release + engage per reversal; -1000 V -> 1e9 V at 0.19 s is a 10th reversal, while
    # 1000 V -> 1000 V at every other step changes nothing.
    assert r["events.current_limit1"][-1] == 1 + 2 * 10
    record("current limit + voltage clamp, 9 reversals", "|i| <= i_L; re-engagement at the clamped-voltage RL time",
           f"{max(errors):.0e} s", r)
    assert max(errors) < 1e-9


# ====================================================================================================
# 6. Extreme base motion

def constant_field_run(fmu, start, accel_a=(0.0, 0.0, 0.0), gamma=0.0):
    accel = np.array(accel_a)

    def inputs(t, y):
        values = {"base.gamma": gamma, "u_R1": 6.0, "u_R2": -4.0}
        for j in range(3):
            values[f"base.v_a[{j + 1}]"] = accel[j] * t
            values[f"base.a_a[{j + 1}]"] = accel[j]
        return values
    return timed(fmu, 0.3, 1e-3, start, inputs, LOOP_OUT + ["alpha_m", "beta_m", "theta_b1", "theta_b2"])


def test_base_acceleration_is_equivalent_to_tilted_stronger_gravity(gimbal_fmu):
    """Equivalence principle: a level carrier whose point a accelerates by (a_x, 0, a_z) (3 g sideways,
    2 g up) is the same as a carrier at rest, rolled by gamma = atan2(-a_x, g + a_z), under
    g' = |(a_x, g + a_z)|."""
    g, ax, az = 9.81, 3 * 9.81, 2 * 9.81
    start = {"beta": 0.3, "beta_m": 18.0, "solver.rtol": 1e-10, "solver.atol": 1e-12}
    accelerating = constant_field_run(gimbal_fmu, start, (ax, 0.0, az))
    tilted = constant_field_run(gimbal_fmu, dict(start, g=math.hypot(ax, g + az)), gamma=math.atan2(-ax, g + az))
    error = max_diff(accelerating, tilted, LOOP_OUT + ["alpha_m", "beta_m"])
    record("base acceleration 3 g sideways + 2 g up", "= tilted carrier under stronger gravity", f"{error:.0e} rad", accelerating)
    assert np.ptp(accelerating["beta"]) > 0.05
    assert error < 1e-7


def heavy_sea(h_control=0.01):
    """A small craft in heavy sea: roll +-0.6 rad at 0.35 Hz, pitch +-0.25 rad at 0.5 Hz, yaw +-0.15 rad at
    0.2 Hz, heave +-0.8 g at 0.4 Hz, as piecewise-constant accelerations on a 10 ms grid, integrated
    exactly: every master step size sees the very same carrier motion."""
    specs = {"gamma": (0.6, 0.35), "delta": (0.25, 0.5), "psi": (0.15, 0.2)}
    heave = (0.8 * 9.81, 0.4)

    def state(t):
        k = int(math.floor(t / h_control + 1e-9))
        t0, s = k * h_control, t - k * h_control
        values = {}
        for name, (amp, f) in specs.items():
            w = 2 * math.pi * f
            # exact arcs: position/rate at grid points from the analytic sine, acceleration held
            a = -amp * w * w * math.sin(w * (t0 + h_control / 2))
            p0, v0 = amp * math.sin(w * t0), amp * w * math.cos(w * t0)
            # make the arc end on the next grid point's analytic state (its acceleration is the sample above)
            values[f"base.{name}"] = p0 + v0 * s + 0.5 * a * s * s
            values[f"base.{name}_dot"] = v0 + a * s
            values[f"base.{name}_ddot"] = a
        amp, f = heave
        w = 2 * math.pi * f
        values["base.a_a[3]"] = amp * math.cos(w * (t0 + h_control / 2))
        values["base.v_a[3]"] = amp / w * math.sin(w * t0) + values["base.a_a[3]"] * s
        return values
    return state


def test_heavy_sea_results_do_not_depend_on_step_or_jacobian(gimbal_fmu):
    """Reduced (2 s). The gimbal stabilised by a PD loop on a rolling, pitching, yawing, heaving small
    craft (roll rates to 1.3 rad/s, roll accelerations to 2.9 rad/s2): 1 ms and 10 ms communication steps
    and the two BDF Jacobians agree; the hybrid constraints hold; the payload gyro output agrees with
    the kinematics of the outputs."""
    sea = heavy_sea()
    held = {}

    def make_inputs(h):
        per = int(round(0.01 / h))

        def inputs(t, y):
            values = sea(t)
            if int(round(t / h)) % per == 0:
                held["u_R1"] = 30.0 * (0.0 - y["alpha"]) - 2.0 * y["alpha_dot"]
                held["u_R2"] = 30.0 * (0.0 - y["beta"]) - 2.0 * y["beta_dot"]
            values.update(held)
            return values
        return inputs
    out = STATES + ["los.omega[1]", "los.omega[2]", "los.omega[3]", "events.backlash1", "events.backlash2",
                         "events.zeno_guard", "motor1.limited"]
    start = {"solver.rtol": 1e-9, "solver.atol": 1e-11}
    fine = timed(gimbal_fmu, 2.0, 1e-3, start, make_inputs(1e-3), out)
    coarse = timed(gimbal_fmu, 2.0, 1e-2, start, make_inputs(1e-2), out)
    dq = timed(gimbal_fmu, 2.0, 1e-2, dict(start, **{"solver.method": 1}), make_inputs(1e-2), out)
    step_error = max(np.max(np.abs(fine[n][::10] - coarse[n])) for n in ("alpha", "beta"))
    jac_error = max_diff(coarse, dq)
    record("heavy sea, 2 s", "1 ms = 10 ms steps; method 0 = method 1; |theta_b| <= eta; |i| <= i_L",
           f"steps {step_error:.0e} rad; Jacobians {jac_error:.0e} rad", coarse, note="reduced: 2 s")
    for r in (fine, coarse, dq):
        assert np.max(np.abs(r["theta_b1"])) <= 2e-4 and np.max(np.abs(r["theta_b2"])) <= 2e-4
        assert np.max(np.abs(r["i_R1"])) <= 4.0 and np.max(np.abs(r["i_R2"])) <= 3.0
        assert r["events.zeno_guard"][-1] == 0
    assert fine["events.backlash1"][-1] > 4
    assert step_error < 1e-6 and jac_error < 1e-6
    # The payload really rides the sea: its gyro reads the carrier's rates.
    assert np.max(np.abs(fine["los.omega[1]"])) > 0.3


def test_base_shock_step_in_acceleration(gimbal_fmu):
    """A 30 g sideways shock (a_a step up at 0.05 s, down at 0.07 s) throws the loads across their gaps:
    1 ms and 0.1 ms communication steps agree, and the hybrid constraints hold."""
    def shock(t, y):
        a = 30 * 9.81 if 0.05 <= t + 1e-12 < 0.07 else 0.0
        v = 30 * 9.81 * min(max(t - 0.05, 0.0), 0.02)
        return {"base.a_a[1]": a, "base.v_a[1]": v, "base.a_a[2]": 0.5 * a, "base.v_a[2]": 0.5 * v}
    start = {"beta": 0.2, "beta_m": 12.0, "solver.rtol": 1e-9, "solver.atol": 1e-11}
    out = STATES + ["T_E1", "T_E2", "gear1.contact", "gear2.contact", "events.backlash1", "events.backlash2",
                         "events.zeno_guard"]
    coarse = timed(gimbal_fmu, 0.15, 1e-3, start, shock, out)
    fine = timed(gimbal_fmu, 0.15, 1e-4, start, shock, out)
    error = max(np.max(np.abs(fine[n][::10] - coarse[n])) / np.max(np.abs(coarse[n]))
                for n in ("alpha", "beta", "alpha_dot", "beta_dot"))
    record("base shock 30 g step in a_a", "1 ms = 0.1 ms steps; backlash invariants", f"{error:.0e} of range", coarse)
    assert coarse["events.backlash1"][-1] + coarse["events.backlash2"][-1] >= 2
    for r in (coarse, fine):
        check_backlash_invariants(r, 1, 2e-4)
        check_backlash_invariants(r, 2, 2e-4)
    assert error < 1e-5  # measured 1.3e-6 at rtol 1e-9


# ====================================================================================================
# 7. Communication steps, events on communication points, a long run

COMM_SCENE = {"beta": 0.2, "beta_m": 12.0, "solver.rtol": 1e-10, "solver.atol": 1e-12}
COMM_OUT = STATES + ["events.backlash1", "events.backlash2", "events.current_limit1", "events.current_limit2",
                          "events.stick_slip"] + COST


def final_state(fmu, stop, step):
    slave = fmu.instantiate("comm")
    try:
        slave.setupExperiment(startTime=0.0)
        fmu.set_values(slave, COMM_SCENE)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        fmu.set_values(slave, {"u_R1": 30.0, "u_R2": -30.0})
        n = int(round(stop / step))
        for k in range(n):
            slave.doStep(k * step, step)
        return dict(zip(COMM_OUT, fmu.get_values(slave, COMM_OUT)))
    finally:
        slave.freeInstance()


def test_communication_steps_from_1e6_to_0_1_give_the_same_result(gimbal_fmu):
    """Constant (clamped) voltages over 0.1 s: limiters engage and release, gears cross their gaps, rotors
    break away. From 1e-6 s (100 000 steps) to one 0.1 s step, the same events and the same states."""
    results, walls = {}, {}
    for h in (1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1):
        t0 = time.perf_counter()
        results[h] = final_state(gimbal_fmu, 0.1, h)
        walls[h] = time.perf_counter() - t0
    ref = results[1e-1]
    worst = 0.0
    for h, r in results.items():
        for name in ("events.backlash1", "events.backlash2", "events.current_limit1", "events.current_limit2",
                     "events.stick_slip"):
            assert r[name] == ref[name], (h, name, r[name], ref[name])
        for name in STATES:
            scale = 2e-4 if name.startswith("theta_b") else max(1.0, abs(ref[name]))
            worst = max(worst, abs(r[name] - ref[name]) / scale)
    fine = {"solver.steps": [results[1e-6]["solver.steps"]], "solver.rhs_evaluations": [results[1e-6]["solver.rhs_evaluations"]]}
    record("comm. steps 1e-6 ... 0.1 s", "same event counts, same final states", f"{worst:.0e} relative",
           fine, walls[1e-6], note="cost: the 1e-6 s run")
    assert ref["events.current_limit1"] >= 1 and ref["events.backlash1"] >= 1
    assert worst < 1e-6


def test_events_exactly_on_communication_points(gimbal_fmu):
    """The master steps exactly to the analytic contact time of a load coasting through the gap, then on:
    the contact is counted once, located at that time, and the trajectory equals the unaligned run."""
    eta, speed = 1e-3, 0.2
    t_star = eta / speed
    start = dict(FREE_LOAD, **{"gear2.eta": eta, "gear2.k_s": 2e4, "gear2.c_s": 5.0, "beta_dot": -speed})
    out = ["beta", "beta_dot", "gear2.contact", "events.backlash2", "events.last_time"] + COST
    slave = gimbal_fmu.instantiate("aligned")
    try:
        slave.setupExperiment(startTime=0.0)
        gimbal_fmu.set_values(slave, start)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.doStep(0.0, t_star)
        at_event = dict(zip(out, gimbal_fmu.get_values(slave, out)))
        t = t_star
        for h in (1e-3, 2e-3):  # on to 0.008 s, before the load rebounds off the stop
            slave.doStep(t, h)
            t += h
        aligned = dict(zip(out, gimbal_fmu.get_values(slave, out)))
    finally:
        slave.freeInstance()
    plain = timed(gimbal_fmu, 0.008, 1e-3, start, None, out)
    error = abs(aligned["beta"] - plain["beta"][-1])
    record("event exactly on a communication point", "counted once, at t*, same trajectory as unaligned",
           f"{error:.0e} rad", {k: [v] for k, v in aligned.items()})
    assert at_event["events.backlash2"] <= 1 and aligned["events.backlash2"] == 1
    assert abs(aligned["events.last_time"] - t_star) < 1e-12 and aligned["gear2.contact"] == 1
    assert error < 1e-10 and plain["events.backlash2"][-1] == 1


def test_one_hour_run_has_bounded_energy_drift(gimbal_fmu):
    """Reduced fidelity (rigid gears, quasi-static motors, no dry friction, fixed base), a quiet scene
    (constant voltages: the azimuth turns steadily against its viscous friction, the payload is pushed
    against gravity), 0.1 s steps: after 1 h the energy balance is closed (no accumulating drift)."""
    r = timed(gimbal_fmu, 3600.0, 0.1, {"gear1.model": 0, "gear2.model": 0, "motor1.model": 0, "motor2.model": 0,
                                         "dry_friction": False, "base.fixed": True, "energy_accounting": True,
                                         "solver.rtol": 1e-8, "solver.atol": 1e-10},
              lambda t, y: {"u_R1": 2.0, "u_R2": 0.5} if t == 0.0 else None, ["alpha", "beta"] + ENERGY)
    residual = np.abs(balance_residual(r))
    throughput = r["energy.resistive"][-1] + r["energy.viscous"][-1]
    first, last = np.max(residual[: len(residual) // 10]), np.max(residual)
    assert last < 20 * max(first, 1e-12 * throughput)  # the drift does not grow without bound
    record("1 h, reduced fidelity, 0.1 s steps", "energy balance < 1e-6 of throughput", f"{last / throughput:.1e}", r)
    assert throughput > 10.0
    assert last < 1e-6 * throughput
    assert np.all(np.isfinite(r["alpha"]))
    del first


# ====================================================================================================
# 8. Degenerate but valid parameters

DEGENERATE = {"g": 0.0, "gear1.N": 1.0, "gear2.N": 1.0, "gear1.eta": 0.0, "gear2.eta": 0.0,
              "gear1.c_s": 0.0, "gear2.c_s": 0.0, "dry_friction": False, "base.fixed": True,
              "motor1.k_torque": 0.0, "motor1.k_emf": 0.0, "motor2.k_torque": 0.0, "motor2.k_emf": 0.0,
              "solver.rtol": 1e-11, "solver.atol": 1e-13}
for _body, _vec in (("body1", "d_bc"), ("body2", "d_bd"), ("rotor1", "d_be"), ("rotor2", "d_bf")):
    for _p in ("I_xy", "I_xz", "I_yz", "c_visc"):
        DEGENERATE[f"{_body}.{_p}"] = 0.0
    for _j in (1, 2, 3):
        DEGENERATE[f"{_body}.{_vec}[{_j}]"] = 0.0


def test_degenerate_parameters_conserve_energy(gimbal_fmu):
    """Zero products of inertia, centres of mass on the axes, g = 0, no viscous friction, N = 1, an undamped
    spring gear (k_s = 100), motors decoupled: nothing dissipates, the energy must stay constant up to the
    integration error, which falls with the tolerance (BDF damps an undamped oscillation numerically: with
    the default k_s = 3e4 and N = 1 the shaft mode is at 3e4 rad/s and the drift is 7e-6 in 0.3 s at
    rtol 1e-11, for 5e5 steps)."""
    drifts = {}
    for rtol in (1e-10, 1e-11):
        start = dict(DEGENERATE, **{"alpha_dot": 1.0, "beta_dot": 0.7, "alpha_m_dot": 1.3, "beta_m_dot": 0.2,
                                    "beta": 0.4, "gear1.k_s": 100.0, "gear2.k_s": 100.0, "solver.rtol": rtol,
                                    "gear2.start": 2,  # as_given: beta_m stays 0, gear 2 wound up
                                    "solver.atol": rtol * 1e-2})
        r = timed(gimbal_fmu, 0.3, 1e-2, start, None, LOOP_OUT + ["energy.kinetic", "energy.spring"])
        energy = r["energy.kinetic"] + r["energy.spring"]
        drifts[rtol] = np.max(np.abs(energy - energy[0])) / energy[0]
        assert np.ptp(r["energy.spring"]) > 1e-3 * energy[0]  # the gears really exchange energy
    record("degenerate: products 0, CoM on axes, g 0, c 0, N 1", "energy conserved to integration error",
           f"{drifts[1e-11]:.0e} relative (rtol 1e-11)", r)
    assert drifts[1e-11] < 1e-6
    assert drifts[1e-10] > 3 * drifts[1e-11]


def test_degenerate_parameters_keep_the_principal_axis_spin_exact(gimbal_fmu):
    """With diagonal inertias and everything on the axes, spinning the azimuth with the payload level is
    a relative equilibrium: beta must stay exactly 0, the spin constant."""
    start = dict(DEGENERATE, **{"alpha_dot": 2.0, "alpha_m_dot": 2.0})
    r = timed(gimbal_fmu, 1.0, 1e-2, start, None, LOOP_OUT)
    record("degenerate: principal-axis spin", "beta = 0, spin constant", f"{np.max(np.abs(r['beta'])):.0e} rad", r)
    assert np.max(np.abs(r["beta"])) < 1e-14 and np.max(np.abs(r["alpha_dot"] - 2.0)) < 1e-12


# ====================================================================================================
# 9. Hostile inputs

def stepped(fmu, inputs, log=None, steps=20, start=None):
    """Runs `steps` 1 ms steps setting `inputs(k)`; returns (states, exception or None)."""
    slave = fmu.instantiate("hostile", log=log)
    try:
        slave.setupExperiment(startTime=0.0)
        fmu.set_values(slave, dict({"beta": 0.2, "beta_m": 12.0}, **(start or {})))
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        error = None
        for k in range(steps):
            try:
                fmu.set_values(slave, inputs(k))
                slave.doStep(k * 1e-3, 1e-3)
            except FMICallException as e:
                error = e
                break
        return np.array(fmu.get_values(slave, STATES + ["T_E1", "energy.kinetic"])), error
    finally:
        slave.freeInstance()


MOVING = lambda k: {"base.gamma_dot": 0.5, "base.gamma": 0.5e-3 * k, "base.psi_dot": 0.3, "base.psi": 0.3e-3 * k,
                    "base.delta_ddot": 2.0, "base.delta_dot": 2e-3 * k, "base.delta": 1e-6 * k * k, "u_R1": 3.0}


@pytest.mark.parametrize("name", ["u_R1", "base.gamma_dot", "base.a_a[3]", "base.v_a[1]"])
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_non_finite_inputs_are_refused_and_the_state_kept(gimbal_fmu, name, value):
    log = []
    states, error = stepped(gimbal_fmu, lambda k: dict(MOVING(k), **({name: value} if k == 10 else {})), log)
    reference, _ = stepped(gimbal_fmu, MOVING, steps=10)
    assert isinstance(error, FMICallException)
    assert any(status == 3 and name in text for status, _, text in log), log
    assert np.array_equal(states, reference)  # nothing of the refused value leaked into the state


def test_huge_voltage_is_clamped_exactly_to_the_limit(gimbal_fmu):
    huge, _ = stepped(gimbal_fmu, lambda k: dict(MOVING(k), u_R1=1e9, u_R2=-1e300))
    limit, _ = stepped(gimbal_fmu, lambda k: dict(MOVING(k), u_R1=24.0, u_R2=-24.0))
    record("voltage 1e9 / -1e300", "identical to +-U_L", "bit for bit" if np.array_equal(huge, limit) else "differs")
    assert np.array_equal(huge, limit)


def test_attitude_of_1e6_rad_is_the_same_attitude(gimbal_fmu):
    """1e6 rad is a valid (if odd) angle: the carrier attitude is periodic, so the run must equal the one
    at 1e6 mod 2 pi (the reduction itself costs ~1e6 * eps = 1e-10 rad)."""
    big = 1e6
    reduced = math.fmod(big, 2 * math.pi)
    a, ea = stepped(gimbal_fmu, lambda k: dict(MOVING(k), **{"base.gamma": big + 0.5e-3 * k, "base.delta": -big}))
    b, eb = stepped(gimbal_fmu, lambda k: dict(MOVING(k), **{"base.gamma": reduced + 0.5e-3 * k, "base.delta": -reduced}))
    error = float(np.max(np.abs(a[:8] - b[:8])))
    record("attitude 1e6 rad", "= attitude mod 2 pi", f"{error:.0e}")
    assert ea is None and eb is None
    assert error < 1e-7


def test_base_velocity_1e300_is_refused_and_1e150_changes_nothing(gimbal_fmu):
    """Galilean invariance makes any finite v_a harmless for the motion, but the inertial kinetic energy
    output overflows at 1e300: the FMU must refuse the step (fmi2Error, named cause, state rolled back),
    and at 1e150 (energy still representable) the motion must be exactly that at v_a = 0."""
    log = []
    states, error = stepped(gimbal_fmu, lambda k: dict(MOVING(k), **({"base.v_a[1]": 1e300} if k >= 5 else {})), log)
    before, _ = stepped(gimbal_fmu, MOVING, steps=5)
    record("base velocity 1e300", "refused with fmi2Error, state rolled back", "refused" if error else "accepted")
    assert isinstance(error, FMICallException)
    assert any(status == 3 and "beyond what the model can represent" in text for status, _, text in log), log
    assert np.array_equal(states, before)
    fast, _ = stepped(gimbal_fmu, lambda k: dict(MOVING(k), **{"base.v_a[1]": 1e150}))
    still, _ = stepped(gimbal_fmu, MOVING)
    assert np.array_equal(fast[:12], still[:12])
