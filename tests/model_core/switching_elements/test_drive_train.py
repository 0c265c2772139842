"""The non-smooth drive train through the FMU, component by component, against the seed's equations."""
import math

import numpy as np
import pytest

from gimbal2axis.fmu import simulate

TIGHT = {"solver.rtol": 1e-10, "solver.atol": 1e-12}
# Rotor 1 on its own: the azimuth gear transmits nothing, and without gravity nothing else moves.
ROTOR1_ALONE = {"gear1.k_s": 0.0, "gear1.c_s": 0.0, "gear1.eta": 0.0, "rotor1.c_visc": 0.0, "g": 0.0}


def start_value(fmu, name):
    return next(float(v.start) for v in fmu.model_description.modelVariables if v.name == name)


# ----------------------------------------------------------------------------- current limiter

def test_current_limiter_holds_and_releases_when_the_voltage_reverses(gimbal_fmu):
    """(2.63-2.69): i is held at +-i_L only while the free circuit would push it further.

    With k_emf = 0 the free current obeys L di/dt = u - R i exactly, so after the reversal at t_r the
    current leaves +i_L at once and reaches -i_L at t_r + (L/R) ln((i_L - u/R)/(-i_L - u/R)).
    """
    i_limit, resistance, inductance = 4.0, 2.0, 2e-3
    params = dict(TIGHT, **ROTOR1_ALONE, **{"rotor1.T_max": 0.0, "rotor1.T_din": 0.0, "motor1.k_emf": 0.0, "motor1.i_L": i_limit, "motor1.R": resistance,
                                            "motor1.L": inductance, "motor1.U_L": 30.0})
    reversal, step = 0.05, 1e-4
    voltage = lambda t, _: {"u_R1": 24.0 if t < reversal - step / 2 else -24.0}
    r = simulate(gimbal_fmu, 0.1, step, params, voltage,
                 ["i_R1", "motor1.limited", "events.current_limit1", "events.last_time", "alpha_m_dot"])
    current, limited, time = r["i_R1"], r["motor1.limited"], r["time"]

    assert np.max(np.abs(current)) <= i_limit * (1 + 1e-12)
    before = (time > 0.01) & (time < reversal)
    assert np.all(limited[before] == 1) and np.all(current[before] == i_limit)
    # Released at the reversal: the first sample after it is already below the limit and falling.
    k = int(round(reversal / step))
    assert limited[k + 1] != 1 and current[k + 1] < i_limit and current[k + 2] < current[k + 1]
    assert np.all(limited[time > reversal + 2e-3] == -1) and current[-1] == -i_limit
    steady = -24.0 / resistance
    expected = reversal + inductance / resistance * math.log((i_limit - steady) / (-i_limit - steady))
    assert r["events.last_time"][-1] == pytest.approx(expected, abs=1e-9)
    assert r["events.current_limit1"][-1] == 3  # engage, release, engage
    # The held current really drives the rotor: torque k_torque * i_L.
    assert r["alpha_m_dot"][k] > 0


# ----------------------------------------------------------------------------- backlash

def backlash_square_wave(t, _):
    return {"u_R2": 6.0 if int(t / 0.05) % 2 == 0 else -6.0}


def test_backlash_state_stays_in_the_gap_and_torque_obeys_the_contact_side(gimbal_fmu):
    eta = start_value(gimbal_fmu, "gear2.eta")
    r = simulate(gimbal_fmu, 0.4, 5e-4, dict(TIGHT, **{"beta_m": 0.0}), backlash_square_wave,
                 ["theta_b2", "T_E2", "gear2.contact", "events.backlash2", "beta"])
    theta_b, torque, contact = r["theta_b2"], r["T_E2"], r["gear2.contact"]
    assert np.max(np.abs(theta_b)) <= eta * (1 + 1e-12)
    # In the gap the shaft transmits nothing, exactly.
    assert np.all(torque[contact == 0] == 0.0)
    # (2.81): contact at +eta is kept while X >= 0, and there T_E = c_s X >= 0; mirrored at -eta.
    assert np.all(torque[contact == 1] >= 0.0) and np.all(torque[contact == -1] <= 0.0)
    assert np.all(np.abs(theta_b[contact == 1] - eta) == 0.0) and np.all(theta_b[contact == -1] == -eta)
    # The scene really crossed the gap both ways.
    assert {-1, 0, 1} <= set(contact.astype(int)) and r["events.backlash2"][-1] >= 4


def test_backlash_traversal_time_matches_the_free_flight_of_the_load(gimbal_fmu):
    """A load coasting through the gap: T_E = 0, so it flies at constant speed. In the gap (2.81) gives
    d(theta_d - theta_b)/dt = -(k_s/c_s)(theta_d - theta_b): starting from theta_b0 = theta_d0 = 0,
    theta_b = theta_d = dtheta_d t, which reaches +eta at t* = eta / dtheta_d."""
    eta, stiffness, damping, speed = 1e-3, 2e4, 5.0, 0.2
    free_load = {
        "g": 0.0, "body2.I_xy": 0.0, "body2.I_xz": 0.0, "body2.I_yz": 0.0,
        "body2.d_bd[1]": 0.0, "body2.d_bd[2]": 0.0, "body2.d_bd[3]": 0.0,
        "body2.c_visc": 0.0, "rotor2.c_visc": 0.0, "rotor2.T_max": 0.0, "rotor2.T_din": 0.0,
        "motor2.k_torque": 0.0, "motor2.k_emf": 0.0,
        "gear2.eta": eta, "gear2.k_s": stiffness, "gear2.c_s": damping,
        "beta_dot": -speed,  # dtheta_d = beta_m_dot / N - beta_dot = +speed
        "gear2.start": 2,    # as_given: beta_m_dot stays 0, the rotor at rest (not in mesh)
    }
    expected = eta / speed
    r = simulate(gimbal_fmu, 0.006, 1e-3, dict(TIGHT, **free_load), None,
                 ["gear2.contact", "events.last_time", "events.backlash2", "beta_dot"])
    assert r["gear2.contact"][-1] == 1 and r["events.backlash2"][-1] == 1
    assert r["events.last_time"][-1] == pytest.approx(expected, abs=1e-9)
    # Free flight before contact: the load kept its speed.
    before = r["time"] < expected
    assert np.max(np.abs(r["beta_dot"][before] + speed)) < 1e-9


# ----------------------------------------------------------------------------- dry friction

def constant_motor_torque(torque, motor=1):
    """Start values that make motor `motor` apply a constant torque from t = 0 (no back-emf, i at steady state)."""
    k_torque, resistance = 0.06 if motor == 1 else 0.04, 2.0 if motor == 1 else 2.5
    current = torque / k_torque
    return {f"motor{motor}.k_emf": 0.0, f"i_R{motor}": current}, {f"u_R{motor}": resistance * current}


@pytest.mark.parametrize("fraction", [0.9, 0.999])
def test_stuck_rotor_holds_below_breakaway_torque(gimbal_fmu, fraction):
    t_max, w_min = start_value(gimbal_fmu, "rotor1.T_max"), start_value(gimbal_fmu, "rotor1.w_min")
    start, inputs = constant_motor_torque(fraction * t_max)
    r = simulate(gimbal_fmu, 1.0, 1e-3, dict(TIGHT, **ROTOR1_ALONE, **start), lambda t, y: inputs,
                 ["alpha_m", "alpha_m_dot", "rotor1.stick_slip", "events.stick_slip"])
    assert np.all(r["rotor1.stick_slip"] == 0)
    assert np.all(np.abs(r["alpha_m"]) <= w_min * r["time"] + 1e-15)
    assert np.max(np.abs(r["alpha_m_dot"])) < w_min


def test_rotor_breaks_away_above_breakaway_torque_then_slips(gimbal_fmu):
    """Above T_max: friction -T_max until |qd| = w_min, then -T_din (2.98, 2.99)."""
    t_din, t_max = start_value(gimbal_fmu, "rotor1.T_din"), start_value(gimbal_fmu, "rotor1.T_max")
    w_min, inertia = start_value(gimbal_fmu, "rotor1.w_min"), start_value(gimbal_fmu, "rotor1.I_zz")
    torque = 1.1 * t_max
    start, inputs = constant_motor_torque(torque)
    r = simulate(gimbal_fmu, 0.2, 1e-3, dict(TIGHT, **ROTOR1_ALONE, **start), lambda t, y: inputs,
                 ["alpha_m_dot", "rotor1.stick_slip", "events.last_time"])
    t_slip = w_min * inertia / (torque - t_max)
    assert r["events.last_time"][-1] == pytest.approx(t_slip, abs=1e-9)
    assert r["rotor1.stick_slip"][-1] == 2
    late = r["time"] > t_slip
    expected = w_min + (torque - t_din) / inertia * (r["time"][late] - t_slip)
    assert np.max(np.abs(r["alpha_m_dot"][late] - expected)) < 1e-8 * np.max(expected)


HANGING = dict(TIGHT, **{"gear2.eta": 0.0, "motor2.k_emf": 0.0})


def preloaded_gear(fmu):
    """Start with the elevation gear already carrying the payload's weight (level base, beta = 0), so
    the rotor feels the gravity torque from t = 0: T_E = m g d_bd[2] (gravity about x of frame 2)."""
    weight_torque = start_value(fmu, "body2.m") * start_value(fmu, "g") * start_value(fmu, "body2.d_bd[2]")
    return {"beta_m": start_value(fmu, "gear2.N") * weight_torque / start_value(fmu, "gear2.k_s")}


def test_payload_off_axis_is_held_by_strong_rotor_friction(gimbal_fmu):
    r = simulate(gimbal_fmu, 1.0, 1e-3, dict(HANGING, **{"rotor2.T_din": 0.02, "rotor2.T_max": 0.03}), None,
                 ["beta", "beta_m", "rotor2.stick_slip", "T_E2"])
    stiffness, w_min = start_value(gimbal_fmu, "gear2.k_s"), start_value(gimbal_fmu, "rotor2.w_min")
    gravity_torque = abs(r["T_E2"][-1])
    assert gravity_torque > 0.5  # the payload really hangs off its axis
    assert r["rotor2.stick_slip"][-1] == 0
    # Only the gear yields (to the static deflection, with some damped overshoot); the rotor creeps at most w_min t.
    assert np.max(np.abs(r["beta"])) < 2.0 * gravity_torque / stiffness + w_min * 1.0
    assert np.all(np.abs(r["beta_m"]) <= w_min * r["time"] + 1e-15)


def test_payload_with_weak_rotor_friction_falls_like_frictionless_plus_slip_torque(gimbal_fmu):
    """With T_max = T_din every low-speed or slipping regime applies +T_din against the fall, which must
    then equal a frictionless fall with a constant motor torque of +T_din on the rotor."""
    t_din = 0.004
    outputs = ["beta", "beta_dot", "beta_m", "beta_m_dot", "rotor2.stick_slip"]
    hanging = dict(HANGING, **preloaded_gear(gimbal_fmu))
    falling = simulate(gimbal_fmu, 0.3, 1e-3, dict(hanging, **{"rotor2.T_din": t_din, "rotor2.T_max": t_din}),
                       None, outputs)
    start, inputs = constant_motor_torque(t_din, motor=2)
    shifted = simulate(gimbal_fmu, 0.3, 1e-3, dict(hanging, **start, **{"rotor2.T_din": 0.0, "rotor2.T_max": 0.0}),
                       lambda t, y: inputs, outputs)
    assert falling["beta"][-1] < -0.05  # it fell
    assert set(falling["rotor2.stick_slip"][1:].astype(int)) <= {-1, -2}  # never held
    for name in outputs[:4]:
        scale = np.max(np.abs(shifted[name]))
        assert np.max(np.abs(falling[name] - shifted[name])) < 1e-7 * scale, name
