"""Physical invariants of the integrated FMU: energy, Galilean invariance, convergence."""
import numpy as np

from gimbal2axis.fmu import simulate

from support.expected_names import STATES

CONSERVATIVE = {
    # Fixed base, no friction, no damping, motors that exert no torque: only gravity and gear springs act
    # (the gears keep their backlash: with c_s = 0 it is a lossless dead zone).
    "rotor1.T_din": 0.0, "rotor1.T_max": 0.0, "rotor2.T_din": 0.0, "rotor2.T_max": 0.0,
    "body1.c_visc": 0.0, "rotor1.c_visc": 0.0, "body2.c_visc": 0.0, "rotor2.c_visc": 0.0,
    "gear1.c_s": 0.0, "gear2.c_s": 0.0, "motor1.k_torque": 0.0, "motor2.k_torque": 0.0,
    "solver.rtol": 1e-12, "solver.atol": 1e-14,
    # A state away from every equilibrium: swinging payload, spinning azimuth, wound-up gears.
    "alpha_dot": 0.8, "beta": 0.6, "beta_dot": -0.5, "alpha_m": 0.02, "beta_m": 60.0 * 0.6 - 0.03,
    "alpha_m_dot": 80.0 * 0.8 + 1.0,
    "gear1.start": 2, "gear2.start": 2,  # as_given: beta_m_dot stays 0, not in mesh
}
ENERGY = ["energy.kinetic", "energy.potential", "energy.spring"]


def total_energy(result):
    return result["energy.kinetic"] + result["energy.potential"] + result["energy.spring"]


def test_energy_is_conserved_without_dissipation(gimbal_fmu):
    result = simulate(gimbal_fmu, stop_time=10.0, step_size=0.01, start_values=CONSERVATIVE,
                      outputs=STATES + ENERGY)
    energy = total_energy(result)
    # The energy really moves between its forms (else conservation would prove nothing)...
    kinetic_scale = np.max(result["energy.kinetic"])
    assert np.ptp(result["energy.kinetic"]) > 0.5 * kinetic_scale
    assert np.ptp(result["energy.spring"]) > 1e-3 * kinetic_scale
    assert np.ptp(result["beta"]) > 0.5
    # ...and its sum stays put. The potential energy has an arbitrary zero, so the drift is measured
    # against the largest kinetic energy: a stricter scale than the total here.
    drift = np.max(np.abs(energy - energy[0])) / kinetic_scale
    assert drift < 1e-7, f"relative energy drift {drift:.3e}"


def test_energy_decays_with_viscous_friction(gimbal_fmu):
    start = dict(CONSERVATIVE, **{"body2.c_visc": 0.05})
    result = simulate(gimbal_fmu, stop_time=2.0, step_size=0.01, start_values=start, outputs=ENERGY + ["beta_dot"])
    energy = total_energy(result)
    assert np.all(np.diff(energy) <= 1e-9 * abs(energy[0]))  # never gains energy
    assert energy[-1] < energy[0] - 0.01 * np.max(result["energy.kinetic"])


MOVING_BASE = {
    "base.delta": 0.05, "base.psi": 0.3, "base.gamma": -0.1,
    "base.delta_dot": 0.2, "base.psi_dot": -0.1, "base.gamma_dot": 0.3,
    "base.delta_ddot": 0.5, "base.psi_ddot": 0.2, "base.gamma_ddot": -0.4,
    "base.a_a[1]": 0.5, "base.a_a[2]": -0.3, "base.a_a[3]": 1.0,
}


def moving_base_inputs(t, outputs, velocity=(0.0, 0.0, 0.0)):
    """Base motion sampled analytically at each step start, plus a PD loop on both axes."""
    values = {
        "base.delta": 0.05 * np.sin(2.0 * t), "base.delta_dot": 0.1 * np.cos(2.0 * t),
        "base.delta_ddot": -0.2 * np.sin(2.0 * t),
        "base.gamma": 0.1 * np.sin(1.3 * t), "base.gamma_dot": 0.13 * np.cos(1.3 * t),
        "base.gamma_ddot": -0.169 * np.sin(1.3 * t),
        "base.psi": 0.2, "base.psi_dot": 0.0, "base.psi_ddot": 0.0,
        "base.a_a[3]": 2.0 * np.sin(3.0 * t),
    }
    for i, v in enumerate(velocity, start=1):
        values[f"base.v_a[{i}]"] = v
    values["u_R1"] = 40.0 * (0.2 - outputs["alpha"]) - 2.0 * outputs["alpha_dot"]
    values["u_R2"] = 40.0 * (0.1 - outputs["beta"]) - 2.0 * outputs["beta_dot"]
    return values


def test_constant_base_velocity_changes_no_trajectory(gimbal_fmu):
    outputs = STATES + ["T_E1", "T_E2", "los.omega[1]", "los.omega[2]", "los.omega[3]", "energy.kinetic"]
    runs = [simulate(gimbal_fmu, 1.0, 1e-3, {"solver.rtol": 1e-9, "solver.atol": 1e-11},
                     lambda t, y, v=v: moving_base_inputs(t, y, v), outputs)
            for v in [(0.0, 0.0, 0.0), (12.0, -7.0, 3.0)]]
    # The FMU reads v_a: it shows in the inertial kinetic energy...
    assert np.max(np.abs(runs[1]["energy.kinetic"] - runs[0]["energy.kinetic"])) > 1.0
    # ...but no trajectory depends on it.
    for name in outputs[:-1]:
        scale = max(1.0, np.max(np.abs(runs[0][name])))
        assert np.max(np.abs(runs[1][name] - runs[0][name])) <= 1e-12 * scale, name
    assert np.ptp(runs[0]["alpha"]) > 0.05  # the loop really moved the gimbal


def test_results_converge_as_the_tolerance_tightens(gimbal_fmu):
    def run(rtol):
        return simulate(gimbal_fmu, 1.0, 1e-3, {"solver.rtol": rtol, "solver.atol": rtol * 1e-2},
                        moving_base_inputs, ["alpha", "beta", "alpha_dot", "beta_dot"])

    reference = run(1e-12)
    errors = []
    for rtol in (1e-6, 1e-8, 1e-10):
        r = run(rtol)
        errors.append(max(np.max(np.abs(r[n] - reference[n])) for n in ("alpha", "beta")))
    assert errors[0] > errors[1] > errors[2], errors
    assert errors[0] / errors[2] > 100, errors  # four decades of tolerance buy at least two of error
    assert errors[2] < 1e-8, errors
