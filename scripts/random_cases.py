#!/usr/bin/env python3
"""The default integrator against CVODE BDF on random parameter sets (a check, not a test).

Each case draws gear stiffness, damping and backlash, motor inductance and current limit, every
fidelity switch and dry friction, and drives a moving base with a saturated square-wave loop. It runs
the default (solver.method 4) at rtol 1e-8, CVODE BDF at rtol 1e-11 and BDF with difference quotients
at 1e-12, and prints the default's max angle error next to the spread of the two references, the
event counts and the method switches; `<-- CHECK` marks a case whose error exceeds 100 times the
spread and 1e-6 rad. With --costs it also counts the work of methods 4, 5 and 6 at default settings.

    .venv/bin/python scripts/random_cases.py [--seed 1] [--cases 25] [--stop-time 0.3] [--costs]
"""
import argparse
import pathlib
import sys

import numpy as np
from fmpy.fmi1 import FMICallException

from gimbal2axis.fmu import FMU, simulate

REPO = pathlib.Path(__file__).resolve().parents[1]

OUTPUTS = ["alpha", "beta", "alpha_dot", "beta_dot", "events.total", "solver.method_switches", "solver.steps",
           "solver.rhs_evaluations", "solver.jacobian_evaluations"]


def draw_case(rng):
    parameters = {
        "gear1.k_s": float(10 ** rng.uniform(3, 7)), "gear2.k_s": float(10 ** rng.uniform(3, 7)),
        "gear1.c_s": float(10 ** rng.uniform(-3, 1.5)), "gear2.c_s": float(10 ** rng.uniform(-3, 1.5)),
        "gear1.eta": float(rng.choice([0.0, 10 ** rng.uniform(-5, -2)])),
        "gear2.eta": float(rng.choice([0.0, 10 ** rng.uniform(-5, -2)])),
        "motor1.L": float(10 ** rng.uniform(-6, -2)), "motor2.L": float(10 ** rng.uniform(-6, -2)),
        "motor1.i_L": float(rng.uniform(0.5, 6)), "motor2.i_L": float(rng.uniform(0.5, 6)),
        "gear1.model": int(rng.integers(0, 3)), "gear2.model": int(rng.integers(0, 3)),
        "motor1.model": int(rng.integers(0, 2)), "motor2.model": int(rng.integers(0, 2)),
        "dry_friction": bool(rng.integers(0, 2)),
    }
    amplitude, frequency = rng.uniform(0.0, 0.2, 3), rng.uniform(0.2, 3.0, 3)
    gains, set_point = rng.uniform(10, 200, 2), rng.uniform(0.02, 0.5)

    def inputs(t, y):
        values = {}
        for k, name in enumerate(["delta", "psi", "gamma"]):
            w = 2 * np.pi * frequency[k]
            values[f"base.{name}"] = amplitude[k] * np.sin(w * t)
            values[f"base.{name}_dot"] = amplitude[k] * w * np.cos(w * t)
            values[f"base.{name}_ddot"] = -amplitude[k] * w * w * np.sin(w * t)
        reference = set_point * np.sign(np.sin(2 * np.pi * 2 * t))
        values["u_R1"] = gains[0] * (reference - y["alpha"]) - 2 * y["alpha_dot"]
        values["u_R2"] = gains[1] * (-reference - y["beta"]) - 2 * y["beta_dot"]
        return values

    return parameters, inputs


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cases", type=int, default=25)
    ap.add_argument("--stop-time", type=float, default=0.3)
    ap.add_argument("--fmu", type=pathlib.Path, default=REPO / "build" / "Gimbal2Axis.fmu")
    ap.add_argument("--costs", action="store_true", help="also count the work of methods 4, 5, 6 at default settings")
    args = ap.parse_args()
    if not args.fmu.exists():
        print(f"random_cases: no FMU at {args.fmu}: run `bash scripts/setup.sh` first", file=sys.stderr)
        return 2
    fmu = FMU(args.fmu)
    rng = np.random.default_rng(args.seed)
    flagged = 0
    for case in range(args.cases):
        parameters, inputs = draw_case(rng)
        run = lambda extra: simulate(fmu, args.stop_time, 1e-3, {**parameters, **extra}, inputs, OUTPUTS)  # noqa: E731
        fast = run({"solver.rtol": 1e-8, "solver.atol": 1e-10})
        reference = run({"solver.method": 0, "solver.rtol": 1e-11, "solver.atol": 1e-13})
        second = run({"solver.method": 1, "solver.rtol": 1e-12, "solver.atol": 1e-14})
        error = max(np.max(np.abs(fast[n] - reference[n])) for n in ("alpha", "beta"))
        spread = max(np.max(np.abs(second[n] - reference[n])) for n in ("alpha", "beta"))
        suspicious = error > 100 * max(spread, 1e-9) and error > 1e-6
        flagged += suspicious
        line = (f"{case:3d}  error {error:.2e}  reference spread {spread:.2e}  events "
                f"{fast['events.total'][-1]:.0f}/{reference['events.total'][-1]:.0f}  switches "
                f"{fast['solver.method_switches'][-1]:.0f}" + ("  <-- CHECK" if suspicious else ""))
        if args.costs:
            for method in (4, 5, 6):
                try:
                    r = run({"solver.method": method})
                except FMICallException:  # the explicit method alone may give up on a stiff case
                    line += f" | method {method}: discarded (solver.max_steps)"
                    continue
                line += (f" | method {method}: {r['solver.rhs_evaluations'][-1]:.0f} RHS, "
                         f"{r['solver.jacobian_evaluations'][-1]:.0f} Jacobians, {r['solver.method_switches'][-1]:.0f} switches")
        print(line, flush=True)
    print(f"{flagged} of {args.cases} cases flagged")
    return 1 if flagged else 0


if __name__ == "__main__":
    sys.exit(main())
