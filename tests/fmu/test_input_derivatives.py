"""Input derivatives (canInterpolateInputs): ramped voltages, the clamp located on the ramp, history kept."""
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

STEP = 1e-3
OUTPUTS = ["alpha", "beta", "i_R1", "i_R2", "solver.steps"]
START = {"solver.rtol": 1e-10, "solver.atol": 1e-12, "beta_m": 0.0, "dry_friction": False, "base.fixed": True,
         "gear1.model": 1, "gear2.model": 1}


def voltage(t):
    """A smooth command whose ramp crosses the 24 V clamp."""
    return 30.0 * np.sin(8.0 * t), 10.0 * np.cos(5.0 * t)


def voltage_rate(t, step):
    """The secant to the next sample, as a master that knows its input signal gives it: consecutive ramps
    then join, and the input is continuous."""
    now, later = np.array(voltage(t)), np.array(voltage(t + step))
    return tuple((later - now) / step)


def run(fmu, steps, with_derivatives, step=STEP, log=None, **overrides):
    slave = fmu.instantiate("ramps", log=log)
    slave.setupExperiment(startTime=0.0)
    fmu.set_values(slave, dict(START, **overrides))
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    rows = []
    vr = [fmu.vr("u_R1"), fmu.vr("u_R2")]
    try:
        for k in range(steps):
            t = k * step
            slave.setReal(vr, list(voltage(t)))
            if with_derivatives:
                slave.setRealInputDerivatives(vr, [1, 1], list(voltage_rate(t, step)))
            slave.doStep(t, step)
            rows.append(fmu.get_values(slave, OUTPUTS))
    finally:
        slave.freeInstance()
    return np.array(rows)


def test_ramped_voltages_approach_the_continuous_input(gimbal_fmu):
    """With derivatives the inputs are piecewise linear instead of piecewise constant: a much better
    approximation of the smooth command, so coarse steps land far closer to the fine-step answer."""
    fine = run(gimbal_fmu, 400, with_derivatives=True, step=STEP / 4)[3::4]
    held = run(gimbal_fmu, 100, with_derivatives=False)
    ramped = run(gimbal_fmu, 100, with_derivatives=True)
    held_error = np.max(np.abs(held[:, :2] - fine[:, :2]))
    ramped_error = np.max(np.abs(ramped[:, :2] - fine[:, :2]))
    assert ramped_error < held_error / 20, (ramped_error, held_error)


def test_continuous_inputs_keep_the_integrator_history(gimbal_fmu):
    # A multistep method's history is what a joined ramp preserves: CVODE BDF shows it.
    loose = {"solver.rtol": 1e-7, "solver.atol": 1e-9, "solver.method": 0}
    held = run(gimbal_fmu, 100, with_derivatives=False, **loose)
    ramped = run(gimbal_fmu, 100, with_derivatives=True, **loose)
    # Held voltages jump at every step and restart BDF at order 1; ramps that join need no restart.
    assert ramped[-1, 4] < held[-1, 4] / 2, (ramped[-1, 4], held[-1, 4])


def test_only_voltages_take_first_derivatives(gimbal_fmu):
    log = []
    slave = gimbal_fmu.instantiate("refusals", log=log)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        with pytest.raises(FMICallException):
            slave.setRealInputDerivatives([gimbal_fmu.vr("base.gamma")], [1], [0.1])
        assert "base.gamma takes no derivative" in log[-1][2]
        with pytest.raises(FMICallException):
            slave.setRealInputDerivatives([gimbal_fmu.vr("u_R1")], [2], [0.1])
        assert "order 2" in log[-1][2]
        slave.setRealInputDerivatives([gimbal_fmu.vr("u_R1")], [1], [100.0])
        slave.doStep(0.0, STEP)
    finally:
        slave.freeInstance()
