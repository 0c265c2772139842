"""fmi2GetDirectionalDerivative of the Co-Simulation FMU (FMI 2.0, 4.2.1): derivatives of the outputs
with respect to the inputs at a communication point. The outputs are computed by fmi2DoStep and held
until the next step, so ModelStructure declares dependencies="" for each of them and the derivatives
are exactly zero; a difference quotient of the held outputs through fmi2SetReal / fmi2GetReal agrees.
The arguments are checked: unknowns must be outputs, knowns inputs, the seeds finite."""
import ctypes

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

OK = 0
VOLTAGES = {"u_R1": 2.0, "u_R2": -1.5}


def initialized(fmu, log):
    slave = fmu.instantiate("derivatives", log=log, logging_on=True)
    slave.setupExperiment(startTime=0.0)
    fmu.set_values(slave, VOLTAGES)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave


def real_names(fmu, causality):
    return [v.name for v in fmu.model_description.modelVariables if v.causality == causality and v.type == "Real"]


def directional(fmu, slave, unknowns, knowns, seed):
    vu = (ctypes.c_uint * len(unknowns))(*[fmu.vr(n) for n in unknowns])
    vk = (ctypes.c_uint * len(knowns))(*[fmu.vr(n) for n in knowns])
    dv_known = (ctypes.c_double * len(knowns))(*seed)
    dv_unknown = (ctypes.c_double * len(unknowns))(*([np.nan] * len(unknowns)))
    slave.fmi2GetDirectionalDerivative(slave.component, vu, len(unknowns), vk, len(knowns), dv_known, dv_unknown)
    return np.array(dv_unknown[:])


def test_the_capability_and_the_model_structure_agree(gimbal_fmu):
    md = gimbal_fmu.model_description
    assert md.coSimulation.providesDirectionalDerivative
    outputs = md.outputs
    assert outputs
    # One <ModelStructure> serves Model Exchange too: a continuous output depends on the states, and
    # only these few on inputs directly (the quasi-static current, the applied voltage, the gyro and the energies that
    # see the carrier). In Co-Simulation the outputs are held between steps, so the derivatives with
    # respect to the inputs are 0 (tested below): a declared dependency allows that.
    states = [d.variable.derivative.name for d in md.derivatives]
    # The quasi-static current and the applied voltage (amplifier<j>.u) see the voltage, or in current
    # drive the current command, at once.
    feedthrough = {"i_R1": {"u_R1", "i_R1_cmd"}, "i_R2": {"u_R2", "i_R2_cmd"},
                   "amplifier1.u": {"u_R1", "i_R1_cmd"}, "amplifier2.u": {"u_R2", "i_R2_cmd"}}
    carrier = ["base.delta", "base.psi", "base.gamma", "base.delta_dot", "base.psi_dot", "base.gamma_dot"]
    for k in (1, 2, 3):
        feedthrough[f"los.omega[{k}]"] = set(carrier)
    feedthrough["energy.kinetic"] = set(carrier) | {"base.v_a[1]", "base.v_a[2]", "base.v_a[3]"}
    feedthrough["energy.potential"] = set(carrier[:3])
    for unknown in outputs:
        names = {v.name for v in unknown.dependencies}
        if unknown.variable.type != "Real" or unknown.variable.name == "events.last_time":
            assert names == set(), unknown.variable.name
            continue
        assert set(states) <= names, unknown.variable.name
        assert names - set(states) == feedthrough.get(unknown.variable.name, set()), unknown.variable.name


def test_outputs_with_respect_to_inputs_match_the_difference_quotient_of_the_held_outputs(gimbal_fmu):
    log = []
    slave = initialized(gimbal_fmu, log)
    try:
        for k in range(20):
            slave.doStep(k * 1e-3, 1e-3)
        outputs = real_names(gimbal_fmu, "output")
        inputs = real_names(gimbal_fmu, "input")
        assert "i_R1" in outputs and "u_R1" in inputs
        for j, known in enumerate(inputs):
            seed = np.zeros(len(inputs))
            seed[j] = 1.0
            d = directional(gimbal_fmu, slave, outputs, inputs, seed)
            # Central difference of the outputs after setting the input (held until the next step).
            u0 = gimbal_fmu.get_values(slave, [known])[0]
            h = 1e-6 * max(1.0, abs(u0))
            gimbal_fmu.set_values(slave, {known: u0 + h})
            plus = np.array(gimbal_fmu.get_values(slave, outputs))
            gimbal_fmu.set_values(slave, {known: u0 - h})
            minus = np.array(gimbal_fmu.get_values(slave, outputs))
            gimbal_fmu.set_values(slave, {known: u0})
            np.testing.assert_array_equal(d, (plus - minus) / (2 * h))
            assert not np.any(d), known
        # The call changes nothing: the next step goes on as before.
        slave.doStep(20e-3, 1e-3)
    finally:
        slave.freeInstance()


def test_empty_calls_are_fine(gimbal_fmu):
    slave = initialized(gimbal_fmu, [])
    try:
        assert slave.fmi2GetDirectionalDerivative(slave.component, None, 0, None, 0, None, None) == OK
    finally:
        slave.freeInstance()


@pytest.mark.parametrize("unknown, known, seed, message", [
    ("u_R1", "u_R2", 1.0, "unknown u_R1 is not an output"),
    ("beta", "beta", 1.0, "known beta is not an input"),
    ("beta", "u_R1", float("nan"), "the seed of u_R1 must be finite"),
])
def test_wrong_arguments_are_refused_with_the_culprit_named(gimbal_fmu, unknown, known, seed, message):
    log = []
    slave = initialized(gimbal_fmu, log)
    try:
        with pytest.raises(FMICallException):
            directional(gimbal_fmu, slave, [unknown], [known], [seed])
        assert message in log[-1][2], log[-1]
    finally:
        slave.freeInstance()


def test_refused_in_initialization_mode(gimbal_fmu):
    log = []
    slave = gimbal_fmu.instantiate("derivatives", log=log, logging_on=True)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        with pytest.raises(FMICallException):
            directional(gimbal_fmu, slave, ["beta"], ["u_R1"], [1.0])
        assert "fmi2GetDirectionalDerivative is not allowed in state" in log[-1][2], log[-1]
    finally:
        slave.freeInstance()
