"""The disturbance elements of docs/physics.md section 4.5 in the integrated FMU: static equilibria
against hand calculations (a payload off balance held by the elevation cable, a rotor at a cogging
detent in every fidelity), energy conservation with the elements on and no losses, and each element
off: the same bits as a model that never had it."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from gimbal2axis.fmu import simulate

from support.expected_names import STATES

# A level, still base and nothing that could hold a coordinate but the element under test: no dry
# friction (a stuck rotor could carry a gear torque), motors at 0 V.
STILL = {"base.fixed": True, "dry_friction": False, "solver.rtol": 1e-10, "solver.atol": 1e-12}


def test_payload_off_balance_settles_where_the_elevation_cable_holds_its_weight(gimbal_fmu):
    # Centre of mass d along the line of sight (y2), rotor R2's on its axis: gravity's moment about the
    # elevation axis is -m g d cos(beta) (the payload's height is d sin(beta)). The cable answers with
    # -k (beta - beta_0). At rest the gear carries nothing (a free rotor at 0 V, no friction), so
    #   m g d cos(beta) + k (beta - beta_0) = 0.
    m, g, d, k, beta_0 = 5.0, 9.81, 0.04, 3.0, 0.5
    start = dict(STILL, **{"body2.m": m, "g": g, "body2.d_bd[1]": 0.0, "body2.d_bd[2]": d, "body2.d_bd[3]": 0.0,
                           "cable2.k": k, "cable2.c": 0.2, "cable2.angle_0": beta_0})
    beta_hand = brentq(lambda b: m * g * d * math.cos(b) + k * (b - beta_0), -1.0, 1.0)
    assert 0.5 < beta_0 - beta_hand < 1.0  # the weight pulls the payload well below the cable's neutral
    # The motor's back-emf, shorted at 0 V, damps the swing (overdamped, time constant about 0.6 s).
    r = simulate(gimbal_fmu, 20.0, 0.05, start, outputs=STATES + ["energy.cable"])
    assert abs(r["beta_dot"][-1]) < 1e-7
    assert abs(r["beta"][-1] - beta_hand) < 1e-7, (r["beta"][-1], beta_hand)
    assert r["energy.cable"][-1] == pytest.approx(0.5 * k * (beta_hand - beta_0) ** 2, rel=1e-6)


def test_the_azimuth_cable_pulls_the_housing_back_to_its_neutral_angle(gimbal_fmu):
    # Level base: gravity has no moment about the vertical azimuth axis, so only the cable holds alpha.
    start = dict(STILL, **{"cable1.k": 20.0, "cable1.c": 0.3, "cable1.angle_0": -0.4, "alpha": 0.3,
                           "alpha_m": 0.3 * gimbal_fmu.start("gear1.N")})
    r = simulate(gimbal_fmu, 20.0, 0.05, start, outputs=STATES)
    assert abs(r["alpha"][-1] - (-0.4)) < 1e-7, r["alpha"][-1]


def detent_start(fidelity, ratio, rotor_angle):
    """Start values that put the rotor at `rotor_angle` with its gear relaxed (load at rotor_angle / N)."""
    values = {"alpha": rotor_angle / ratio}
    if fidelity.get("gear1.model", 2) != 0:
        values["alpha_m"] = rotor_angle
    return values


@pytest.mark.parametrize("fidelity", [
    {},                                                   # compliant gear with backlash, inductive motor
    {"gear1.model": 1, "motor1.model": 0},                # compliant without backlash, quasi-static motor
    {"gear1.model": 0},                                   # rigid: q_m = N alpha has no state of its own
    {"gear1.model": 0, "motor1.model": 0},
], ids=["full", "compliant quasi-static", "rigid", "rigid quasi-static"])
def test_the_rotor_settles_at_a_cogging_detent(gimbal_fmu, fidelity):
    # T = -T_c sin(n q_m + phase) is zero at n q_m + phase = k pi; only the even k are stable (the
    # potential (T_c / n)(1 - cos(n q_m + phase)) has its minima there). Start 0.3 of a period past the
    # detent at 6 pi: the rotor returns to (6 pi - phase) / n, not on to the unstable 7 pi. A sign
    # error in the torque would make 7 pi the detent instead.
    n, phase, T_c = 12, 0.7, 0.02
    ratio = gimbal_fmu.start("gear1.N")
    detent = (2.0 * math.pi * 3 - phase) / n
    start = dict(STILL, **fidelity, **{"motor1.T_cogging": T_c, "motor1.cogging_periods": n,
                                       "motor1.cogging_phase": phase},
                 **detent_start(fidelity, ratio, detent + 0.3 * 2.0 * math.pi / n))
    r = simulate(gimbal_fmu, 10.0, 0.05, start, outputs=["alpha", "alpha_m", "alpha_dot", "energy.cogging"])
    assert abs(r["alpha_m"][-1] - detent) < 1e-6, (r["alpha_m"][-1], detent)
    # The load follows through the gear; with backlash it may rest anywhere within the play.
    play = gimbal_fmu.start("gear1.eta") if fidelity.get("gear1.model", 2) == 2 else 0.0
    assert abs(r["alpha"][-1] - detent / ratio) < play + 1e-6 / ratio
    assert r["energy.cogging"][0] == pytest.approx(T_c / n * (1.0 - math.cos(0.6 * math.pi)), rel=1e-9)
    assert r["energy.cogging"][-1] < 1e-10


CONSERVATIVE = {
    # The elements' springs and potentials with everything lossless (as in test_physics_invariants.py):
    # fixed base, no friction or damping, motors that exert no torque, the gears a lossless dead zone.
    "base.fixed": True, "dry_friction": False,
    "body1.c_visc": 0.0, "rotor1.c_visc": 0.0, "body2.c_visc": 0.0, "rotor2.c_visc": 0.0,
    "gear1.c_s": 0.0, "gear2.c_s": 0.0, "motor1.k_torque": 0.0, "motor2.k_torque": 0.0,
    "solver.rtol": 1e-12, "solver.atol": 1e-14,
    "cable1.k": 1.5, "cable1.angle_0": 0.2, "cable2.k": 0.8, "cable2.angle_0": -0.3,
    "motor1.T_cogging": 0.01, "motor1.cogging_periods": 8, "motor1.cogging_phase": 0.4,
    "motor2.T_cogging": 0.008, "motor2.cogging_periods": 6, "motor2.cogging_phase": -0.9,
    "alpha_dot": 0.8, "beta": 0.6, "beta_dot": -0.5, "alpha_m": 0.02, "beta_m": 60.0 * 0.6 - 0.03,
    "alpha_m_dot": 80.0 * 0.8 + 1.0,
}
STORED = ["energy.kinetic", "energy.potential", "energy.spring", "energy.cable", "energy.cogging"]


def test_energy_is_conserved_with_the_cables_and_cogging_on(gimbal_fmu):
    r = simulate(gimbal_fmu, 5.0, 0.01, CONSERVATIVE, outputs=STATES + STORED)
    kinetic_scale = np.max(r["energy.kinetic"])
    # Both new stores exchange energy with the others, by more than the drift allowed below...
    assert np.ptp(r["energy.cable"]) > 0.1 * kinetic_scale
    assert np.ptp(r["energy.cogging"]) > 1e-4 * kinetic_scale
    total = sum(r[n] for n in STORED)
    drift = np.max(np.abs(total - total[0])) / kinetic_scale
    assert drift < 1e-7, f"relative energy drift {drift:.3e}"
    # ...and each is needed: without it (or with its torque's sign wrong) the sum is not constant.
    for name in ("energy.cable", "energy.cogging"):
        partial = total - r[name]
        assert np.max(np.abs(partial - partial[0])) / kinetic_scale > 100 * 1e-7, name


# Each element switched off by its own parameters, with its other parameters far from their start
# values: a model that never had the element computes the same bits.
OFF = {
    "cable": {"cable1.angle_0": 0.7, "cable2.angle_0": -0.5},
    "cogging": {"motor1.cogging_periods": 24, "motor1.cogging_phase": 1.3, "motor2.cogging_periods": 18,
                "motor2.cogging_phase": -2.0},
}


@pytest.mark.parametrize("element", sorted(OFF))
def test_an_element_switched_off_changes_no_bit(gimbal_fmu, element):
    def run(extra):
        start = dict({"beta": 0.3, "beta_m": 0.3 * 60.0, "u_R1": 2.0, "u_R2": -1.0}, **extra)
        return simulate(gimbal_fmu, 0.3, 0.01, start, outputs=STATES + ["energy.cable", "energy.cogging"])

    plain, off = run({}), run(OFF[element])
    for name in STATES:
        assert np.array_equal(plain[name], off[name]), name
    assert not np.any(off["energy.cable"]) and not np.any(off["energy.cogging"])
