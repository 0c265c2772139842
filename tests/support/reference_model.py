"""An independent Python implementation of the FMU's 12-state model for high-accuracy reference runs.

The rigid-body part comes from the symbolic Lagrangian (tests/support/symbolic), the drive train is written
from docs/physics.md section 4 (linear gear spring-damper, RL motor, viscous friction, and the
disturbances of section 4.5: cable restraints on the joints, cogging on the rotors), and the co-simulation
semantics of docs/model_overview.md ("Step semantics") (voltages held, base motion at constant acceleration over each step).
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from support.symbolic.lagrange_reference import reference_mass_matrix_and_bias

BODIES = ("body1", "rotor1", "body2", "rotor2")
COM_NAMES = ("d_bc", "d_be", "d_bd", "d_bf")
ROTOR, LOAD = (1, 3), (0, 2)


class ReferenceModel:
    def __init__(self, values: dict):
        """`values`: every parameter of the FMU by name (start values merged with overrides)."""
        v = values
        self.rigid = dict(
            mass=np.array([v[f"{b}.m"] for b in BODIES]),
            inertia=np.array([[v[f"{b}.{n}"] for n in ("I_xx", "I_yy", "I_zz", "I_xy", "I_xz", "I_yz")]
                              for b in BODIES]),
            com=np.array([[v[f"{b}.{c}[{i}]"] for i in (1, 2, 3)] for b, c in zip(BODIES, COM_NAMES)]),
            d_ab=np.array([v[f"base.d_ab[{i}]"] for i in (1, 2, 3)]),
            g=v["g"],
        )
        self.viscous = np.array([v[f"{b}.c_visc"] for b in BODIES])
        self.motor = [{k: v[f"motor{j}.{k}"] for k in ("R", "L", "k_torque", "k_emf", "U_L")} for j in (1, 2)]
        self.gear = [{k: v[f"gear{j}.{k}"] for k in ("N", "k_s", "c_s")} for j in (1, 2)]
        self.cable = [{k: v.get(f"cable{j}.{k}", 0.0) for k in ("k", "c", "angle_0")} for j in (1, 2)]
        self.cogging = [dict(T=v.get(f"motor{j}.T_cogging", 0.0), n=v.get(f"motor{j}.cogging_periods", 1),
                             phase=v.get(f"motor{j}.cogging_phase", 0.0)) for j in (1, 2)]

    def derivative(self, x, voltage, base):
        q, qd, current = x[0:4], x[4:8], x[8:10]
        J, f = reference_mass_matrix_and_bias(self.rigid, q, qd, base)
        xi = -self.viscous * qd
        dx = np.zeros(12)
        for j in range(2):
            gear, motor = self.gear[j], self.motor[j]
            r, l = ROTOR[j], LOAD[j]
            deflection = q[r] / gear["N"] - q[l]
            deflection_rate = qd[r] / gear["N"] - qd[l]
            shaft_torque = gear["k_s"] * deflection + gear["c_s"] * deflection_rate
            xi[l] += shaft_torque
            xi[r] += motor["k_torque"] * current[j] - shaft_torque / gear["N"]
            # A cable between the load's joint partners pulls the load angle back to angle_0; cogging
            # pulls the rotor (angle relative to its stator) towards n q_m + phase = 2 pi k.
            cable, cogging = self.cable[j], self.cogging[j]
            xi[l] += -cable["k"] * (q[l] - cable["angle_0"]) - cable["c"] * qd[l]
            xi[r] += -cogging["T"] * np.sin(cogging["n"] * q[r] + cogging["phase"])
            dx[8 + j] = (voltage[j] - motor["R"] * current[j] - motor["k_emf"] * qd[r]) / motor["L"]
        dx[0:4] = qd
        dx[4:8] = np.linalg.solve(J, xi + f)
        return dx

    def step(self, x, t0, h, inputs: dict, rtol=1e-12, atol=1e-14):
        """Advances over one communication step with the inputs given at its start."""
        voltage = [float(np.clip(inputs.get(f"u_R{j + 1}", 0.0), -self.motor[j]["U_L"], self.motor[j]["U_L"]))
                   for j in range(2)]
        names = ("delta", "psi", "gamma")
        angle = np.array([inputs.get(f"base.{n}", 0.0) for n in names])
        rate = np.array([inputs.get(f"base.{n}_dot", 0.0) for n in names])
        accel = np.array([inputs.get(f"base.{n}_ddot", 0.0) for n in names])
        v_a = np.array([inputs.get(f"base.v_a[{i}]", 0.0) for i in (1, 2, 3)])
        a_a = np.array([inputs.get(f"base.a_a[{i}]", 0.0) for i in (1, 2, 3)])

        def rhs(t, y):
            s = t - t0
            base = dict(attitude=angle + rate * s + 0.5 * accel * s * s, attitude_rate=rate + accel * s,
                        attitude_accel=accel, v_a=v_a + a_a * s, a_a=a_a)
            return self.derivative(y, voltage, base)

        sol = solve_ivp(rhs, (t0, t0 + h), x, method="DOP853", rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError(sol.message)
        return sol.y[:, -1]
