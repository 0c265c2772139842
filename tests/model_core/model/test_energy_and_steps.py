"""The hybrid drive train under load: the energy books balance, and the communication step changes nothing.

Both scenes drive the non-smooth parts on purpose (backlash traversals, current limiter engaging and
releasing, rotor stick-slip, voltage clamp) and assert that they did, since a balance or an agreement
over a scene that never switches a mode would prove little about the hybrid integrator.

They run their own small fmpy master loop rather than `gimbal2axis.fmu.simulate`, which returns every
output as a float: the Integer event counters stay integers here, and inputs are chosen by step index.
"""
import numpy as np

from support.expected_names import STATES

STORED = ["energy.kinetic", "energy.potential", "energy.spring", "energy.magnetic"]
DISSIPATED = ["energy.resistive", "energy.viscous", "energy.shaft_damping", "energy.dry_friction"]
ENERGY = STORED + ["energy.electrical_in"] + DISSIPATED
COUNTERS = ["events.total", "events.backlash1", "events.backlash2", "events.current_limit1",
            "events.current_limit2", "events.stick_slip", "events.zeno_guard", "solver.steps"]
MODES = ["gear1.contact", "gear2.contact", "motor1.limited", "motor2.limited", "rotor1.stick_slip",
         "rotor2.stick_slip"]


def run(fmu, stop_time, step_size, start_values, step_inputs, reals, integers=(), booleans=None):
    """Fixed-step co-simulation; `step_inputs(k, t, latest_reals)` gives the Reals to set before step k.

    Returns {name: array over the communication points} for `reals` and `integers`, plus 'time'.
    """
    slave = fmu.instantiate("energy_and_steps")
    try:
        slave.setupExperiment(startTime=0.0)
        slave.setReal([fmu.vr(n) for n in start_values], [float(v) for v in start_values.values()])
        if booleans:
            slave.setBoolean([fmu.vr(n) for n in booleans], [bool(v) for v in booleans.values()])
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        real_vrs, integer_vrs = [fmu.vr(n) for n in reals], [fmu.vr(n) for n in integers]
        n_steps = int(round(stop_time / step_size))
        real_rows = [slave.getReal(real_vrs)]
        integer_rows = [slave.getInteger(integer_vrs) if integers else []]
        for k in range(n_steps):
            t = k * step_size
            values = step_inputs(k, t, dict(zip(reals, real_rows[-1])))
            if values:
                slave.setReal([fmu.vr(n) for n in values], [float(v) for v in values.values()])
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=step_size)
            real_rows.append(slave.getReal(real_vrs))
            integer_rows.append(slave.getInteger(integer_vrs) if integers else [])
        slave.terminate()
    finally:
        slave.freeInstance()
    real_rows, integer_rows = np.array(real_rows, dtype=float), np.array(integer_rows, dtype=int)
    result = {"time": np.arange(n_steps + 1) * step_size}
    result.update({n: real_rows[:, j] for j, n in enumerate(reals)})
    result.update({n: integer_rows[:, j] for j, n in enumerate(integers)})
    return result


# ----------------------------------------------------------------------------------------------------
# 1. Energy balance of a hard-driven run

# A reversing voltage program beyond U_L = 24 V (so the clamp acts too): the stall currents (u/R = 12 A
# and 9.6 A) are far above i_L (4 A, 3 A), so each reversal drives both limiters into +-i_L, and they
# release as the back-emf builds up; each torque reversal carries the gears across their backlash.
# The last 0.8 s at zero voltage let the rotors brake (short-circuited motors) and stick.
VOLTAGE_PROGRAM = [(0.3, 30.0, -30.0), (0.6, -30.0, 30.0), (0.9, 20.0, -8.0), (1.2, -24.0, 24.0), (2.0, 0.0, 0.0)]


def program_voltages(t):
    for end, u1, u2 in VOLTAGE_PROGRAM:
        if t < end:
            return u1, u2
    return VOLTAGE_PROGRAM[-1][1:]


def powered_run(fmu, rtol, parameters=None, reals=()):
    start = {
        # A lossless converter, so that every watt taken at the terminals and not burnt in R or stored
        # in L becomes shaft power (these are also the defaults; set them so the scene says so).
        "motor1.k_emf": 0.06, "motor1.k_torque": 0.06, "motor2.k_emf": 0.04, "motor2.k_torque": 0.04,
        # Fixed base (all base inputs stay 0), default backlash eta, default rotor dry friction.
        "solver.rtol": rtol, "solver.atol": rtol * 1e-2,
        **(parameters or {}),
    }
    return run(fmu, 2.0, 0.01, start,
               lambda k, t, y: dict(zip(("u_R1", "u_R2"), program_voltages(t))),
               STATES + ENERGY + list(reals), COUNTERS + MODES, booleans={"energy_accounting": True})


def balance_residual(r, stored_names=STORED):
    """electrical_in - (change of the stored energy) - dissipated, at every communication point."""
    stored = sum(r[n] for n in stored_names)
    return r["energy.electrical_in"] - (stored - stored[0]) - sum(r[n] for n in DISSIPATED)


def test_energy_balance_closes_in_a_powered_run_with_backlash_limiter_and_stick_slip(gimbal_fmu):
    r = powered_run(gimbal_fmu, 1e-10)

    # The scene exercises every non-smooth part, both ways.
    for counter in ("events.backlash1", "events.backlash2", "events.current_limit1", "events.current_limit2"):
        assert r[counter][-1] >= 4, (counter, r[counter][-1])  # engaged and released repeatedly
    assert r["events.stick_slip"][-1] >= 4, r["events.stick_slip"][-1]
    assert r["events.zeno_guard"][-1] == 0  # no mode was frozen by the chattering guard
    for mode in ("gear1.contact", "gear2.contact", "motor1.limited", "motor2.limited"):
        assert set(r[mode]) == {-1, 0, 1}, (mode, set(r[mode]))  # both stops / both limits, and free
    for rotor in ("rotor1.stick_slip", "rotor2.stick_slip"):
        assert {-2, 0, 2} <= set(r[rotor]), (rotor, set(r[rotor]))  # slips both ways, and sticks
    # The hybrid constraints hold at every point: |i| <= i_L (= i_L while limited), |theta_b| <= eta.
    for current, limited, limit in (("i_R1", "motor1.limited", 4.0), ("i_R2", "motor2.limited", 3.0)):
        assert np.max(np.abs(r[current])) <= limit
        held = r[limited] != 0
        assert np.array_equal(r[current][held], r[limited][held] * limit)
    for backlash in ("theta_b1", "theta_b2"):
        assert np.max(np.abs(r[backlash])) <= 2e-4
    # Every dissipation is a non-decreasing integral of a square, and each is large enough to matter
    # against the tolerance below (shaft damping, the smallest, is ~5e-4 of the input).
    for name in ("energy.resistive", "energy.viscous", "energy.shaft_damping"):
        assert np.all(np.diff(r[name]) >= -1e-12), name
    electrical_in = r["energy.electrical_in"]
    scale = np.max(np.abs(electrical_in))  # about 56 J
    assert scale > 10.0
    for name in DISSIPATED:
        assert r[name][-1] > 1e-4 * scale, (name, r[name][-1])
    assert np.ptp(r["energy.potential"]) > 1e-2 * scale  # the payload swings up and down (~2 J)

    # The balance. Scale: the electrical energy delivered, i.e. the energy throughput of the run: every
    # dissipation is a part of it, and the stored energies enter only through their changes (the
    # potential energy has an arbitrary zero, so its absolute value is no scale). Measured residual at
    # rtol 1e-10: 1.3e-8 J, 2.4e-10 of the throughput; the bound leaves a factor of 40.
    residual = balance_residual(r)
    relative = np.max(np.abs(residual)) / scale
    assert relative < 1e-8, f"energy balance residual {np.max(np.abs(residual)):.3e} J = {relative:.3e} relative"

    # The residual is integration error, not a modelling inconsistency: it shrinks with the tolerance
    # (measured 7.5e-7 J at rtol 1e-8, 57 times the value at 1e-10), while the event sequence is the same.
    coarse = powered_run(gimbal_fmu, 1e-8)
    coarse_relative = np.max(np.abs(balance_residual(coarse))) / scale
    assert coarse_relative > 10.0 * relative, (coarse_relative, relative)
    for counter in COUNTERS[:-1]:
        assert coarse[counter][-1] == r[counter][-1], counter


# The disturbance elements (docs/physics.md section 4.5): both cable restraints and both motors' cogging.
# Their springs and potentials are stored energies of their own outputs, the cable dampers' loss is
# counted in energy.viscous.
DISTURBED = {"cable1.k": 2.0, "cable1.c": 0.05, "cable1.angle_0": 0.2,
             "cable2.k": 1.0, "cable2.c": 0.02, "cable2.angle_0": -0.1,
             "motor1.T_cogging": 0.004, "motor1.cogging_periods": 12, "motor1.cogging_phase": 0.5,
             "motor2.T_cogging": 0.003, "motor2.cogging_periods": 18, "motor2.cogging_phase": -0.7}
DISTURBANCE_ENERGY = ["energy.cable", "energy.cogging"]


def test_energy_balance_closes_with_cable_restraints_and_cogging(gimbal_fmu):
    r = powered_run(gimbal_fmu, 1e-10, DISTURBED, DISTURBANCE_ENERGY)
    scale = np.max(np.abs(r["energy.electrical_in"]))
    assert scale > 10.0
    # Each new store really fills and empties: the cables wind up with the swings, the rotors pass
    # many cogging periods (the largest cogging energy is 2 T_c / n = 6.7e-4 J and 3.3e-4 J).
    assert np.ptp(r["energy.cable"]) > 1e-3 * scale, np.ptp(r["energy.cable"])
    assert np.ptp(r["energy.cogging"]) > 2e-4, np.ptp(r["energy.cogging"])
    assert np.min(r["energy.cable"]) >= 0.0 and np.min(r["energy.cogging"]) >= 0.0
    residual = balance_residual(r, STORED + DISTURBANCE_ENERGY)
    relative = np.max(np.abs(residual)) / scale
    assert relative < 1e-8, f"energy balance residual {np.max(np.abs(residual)):.3e} J = {relative:.3e} relative"
    # Each store is needed to close the books: a sign error in an element's torque, or its energy left out,
    # would leave a residual far above the bound.
    for name in DISTURBANCE_ENERGY:
        without = balance_residual(r, STORED + [n for n in DISTURBANCE_ENERGY if n != name])
        assert np.max(np.abs(without)) / scale > 100 * 1e-8, name


# ----------------------------------------------------------------------------------------------------
# 2. Independence of the communication step

CONTROL_PERIOD = 0.01  # the controller samples and holds its voltages on this grid in every run
KP, KD = 60.0, 3.0     # V/rad, V.s/rad: large steps saturate the current limiters
# Base motion with constant attitude accelerations and a constant acceleration of point a over the whole
# run: it is exactly the constant-acceleration arc the FMU integrates inside a step, whatever the step,
# so the 1 ms and 10 ms masters feed the FMU the same carrier motion (sampled at their step starts).
ATTITUDE0 = np.array([0.02, 0.3, -0.03])      # delta, psi, gamma
ATTITUDE_RATE0 = np.array([0.05, 0.1, 0.08])
ATTITUDE_ACCEL = np.array([0.1, 0.0, -0.05])
VELOCITY_A0 = np.array([2.0, 0.0, 0.0])
ACCEL_A = np.array([0.3, -0.2, 0.5])


def base_motion(t):
    attitude = ATTITUDE0 + ATTITUDE_RATE0 * t + 0.5 * ATTITUDE_ACCEL * t * t
    rate = ATTITUDE_RATE0 + ATTITUDE_ACCEL * t
    velocity = VELOCITY_A0 + ACCEL_A * t
    values = {}
    for j, angle in enumerate(("delta", "psi", "gamma")):
        values[f"base.{angle}"] = attitude[j]
        values[f"base.{angle}_dot"] = rate[j]
        values[f"base.{angle}_ddot"] = ATTITUDE_ACCEL[j]
    for j in range(3):
        values[f"base.v_a[{j + 1}]"] = velocity[j]
        values[f"base.a_a[{j + 1}]"] = ACCEL_A[j]
    return values


def setpoints(t):
    return (0.6, 0.4) if t < 0.6 else (-0.2, -0.3)


def closed_loop_run(fmu, step_size, rtol, stop_time=1.5):
    """PD on alpha and beta, updated every CONTROL_PERIOD and held in between; states on that grid."""
    per_sample = int(round(CONTROL_PERIOD / step_size))
    held = {}

    def step_inputs(k, t, y):
        values = base_motion(t)
        if k % per_sample == 0:  # in the 1 ms run, the controller acts only at every 10th step
            alpha_ref, beta_ref = setpoints(t)
            held["u_R1"] = KP * (alpha_ref - y["alpha"]) - KD * y["alpha_dot"]
            held["u_R2"] = KP * (beta_ref - y["beta"]) - KD * y["beta_dot"]
        values.update(held)
        return values

    r = run(fmu, stop_time, step_size, {"solver.rtol": rtol, "solver.atol": rtol * 1e-2}, step_inputs,
            STATES, COUNTERS)
    return {n: v[::per_sample] for n, v in r.items()}


ETA = 2e-4  # default gear1.eta = gear2.eta


def step_differences(fine, coarse):
    """Largest |difference| per state over the 10 ms grid, as a fraction of that state's bound.

    The bound is 1e-6 of the state's scale, the largest |value| it takes in the run, except for
    theta_b: it follows the gear deflection q_m/N - q_l, a difference of two angles of ~0.5 rad, so it
    inherits their absolute error (~1e-9 rad at rtol 1e-10) and cannot agree to a smaller fraction of
    its own range eta = 2e-4 rad than that; it is held to 1e-5 of eta (2e-9 rad).
    """
    assert np.allclose(fine["time"], coarse["time"], rtol=0.0, atol=1e-12)
    fraction = {}
    for name in STATES:
        bound = 1e-5 * ETA if name.startswith("theta_b") else 1e-6 * np.max(np.abs(coarse[name]))
        fraction[name] = np.max(np.abs(fine[name] - coarse[name])) / bound
    return fraction


def test_results_do_not_depend_on_the_communication_step(gimbal_fmu):
    runs = {h: closed_loop_run(gimbal_fmu, h, 1e-10) for h in (1e-3, 1e-2)}
    fine, coarse = runs[1e-3], runs[1e-2]

    # The loop moves both axes over large angles, and the hybrid parts switch repeatedly, in both runs.
    for r in runs.values():
        assert np.ptp(r["alpha"]) > 0.5 and np.ptp(r["beta"]) > 0.5
        for counter in ("events.backlash1", "events.backlash2", "events.current_limit1",
                        "events.current_limit2", "events.stick_slip"):
            assert r[counter][-1] >= 4, (counter, r[counter][-1])
        assert r["events.zeno_guard"][-1] == 0
    # The same switches happen in both runs (only their located times may differ, within tolerance).
    for counter in COUNTERS[:-1]:
        assert fine[counter][-1] == coarse[counter][-1], (counter, fine[counter][-1], coarse[counter][-1])
    # The 1 ms run really ran a different integration (CVODE stopped at every 1 ms point).
    assert fine["solver.steps"][-1] != coarse["solver.steps"][-1]

    # All 12 states agree on the 10 ms grid. Measured at rtol 1e-10: at most 4.9e-8 of the scale
    # (i_R2), 1.3e-6 of eta (theta_b2): at most 0.13 of the bound.
    fraction = step_differences(fine, coarse)
    worst = max(fraction, key=fraction.get)
    assert fraction[worst] < 1.0, {n: f"{v:.2e}" for n, v in fraction.items()}

    # What difference there is comes from the integrator tolerance, not from the step: it grows as the
    # tolerance is loosened (measured: about 80 times larger at rtol 1e-8).
    loose = step_differences(closed_loop_run(gimbal_fmu, 1e-3, 1e-8), closed_loop_run(gimbal_fmu, 1e-2, 1e-8))
    assert max(loose.values()) > 10.0 * fraction[worst], (max(loose.values()), fraction[worst])
