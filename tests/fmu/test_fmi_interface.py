"""The FMI 2.0 Co-Simulation interface as a master uses it: rollback, reset, threads, failures, logging."""
import threading

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2LastSuccessfulTime, fmi2DoStepStatus

from gimbal2axis.fmu import simulate

from support.expected_names import STATES

OUTPUTS = STATES + ["T_E1", "T_E2", "los.omega[1]", "los.omega[2]", "los.omega[3]"]
START = {"beta": 0.3, "beta_m": 18.0, "solver.rtol": 1e-8, "solver.atol": 1e-10}
STEP = 1e-3
ERROR, DISCARD = 3, 2


def square_wave(t):
    """Voltages that keep backlash, limiter and friction switching, and a rolling base."""
    sign = 1.0 if int(t / 0.02) % 2 == 0 else -1.0
    return {"u_R1": 8.0 * sign, "u_R2": -5.0 * sign, "base.gamma": 0.05 * np.sin(3 * t),
            "base.gamma_dot": 0.15 * np.cos(3 * t), "base.gamma_ddot": -0.45 * np.sin(3 * t)}


def started(fmu, name="instance", log=None, start=START):
    slave = fmu.instantiate(name, log=log)
    slave.setupExperiment(startTime=0.0)
    fmu.set_values(slave, start)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave


def run(fmu, slave, t0, steps, record=True):
    rows = []
    for k in range(steps):
        t = t0 + k * STEP
        fmu.set_values(slave, square_wave(t))
        slave.doStep(t, STEP)
        if record:
            rows.append(fmu.get_values(slave, OUTPUTS))
    return np.array(rows)


def test_rollback_replays_bit_for_bit(gimbal_fmu):
    slave = started(gimbal_fmu)
    try:
        run(gimbal_fmu, slave, 0.0, 50, record=False)
        state = slave.getFMUstate()
        first = run(gimbal_fmu, slave, 0.05, 60)
        slave.setFMUstate(state)
        second = run(gimbal_fmu, slave, 0.05, 60)
        slave.freeFMUstate(state)
        assert np.ptp(first[:, 2]) > 1e-3  # it moved
        assert np.array_equal(first, second)
    finally:
        slave.freeInstance()


def test_serialized_state_continues_bit_for_bit_in_a_fresh_instance(gimbal_fmu):
    original = started(gimbal_fmu, "original")
    try:
        run(gimbal_fmu, original, 0.0, 40, record=False)
        state = original.getFMUstate()
        blob = original.serializeFMUstate(state)
        original.freeFMUstate(state)
        expected = run(gimbal_fmu, original, 0.04, 60)
    finally:
        original.freeInstance()
    fresh = gimbal_fmu.instantiate("fresh")
    try:
        state = fresh.deSerializeFMUstate(blob)
        fresh.setFMUstate(state)
        fresh.freeFMUstate(state)
        assert np.array_equal(run(gimbal_fmu, fresh, 0.04, 60), expected)
    finally:
        fresh.freeInstance()


def test_foreign_serialized_state_is_refused(gimbal_fmu):
    log = []
    slave = started(gimbal_fmu, log=log)
    try:
        state = slave.getFMUstate()
        blob = bytearray(slave.serializeFMUstate(state))
        slave.freeFMUstate(state)
        blob[0] ^= 0xFF
        with pytest.raises(FMICallException):
            slave.deSerializeFMUstate(bytes(blob))
        assert "does not start like an FMU state of this FMU" in log[-1][2]
        with pytest.raises(FMICallException):
            slave.deSerializeFMUstate(bytes(blob[:100]))
        assert "its size is not that of this FMU's states" in log[-1][2]
        run(gimbal_fmu, slave, 0.0, 3)  # still usable
    finally:
        slave.freeInstance()


def test_reset_gives_the_trajectory_of_a_new_instance(gimbal_fmu):
    slave = started(gimbal_fmu)
    try:
        reference = run(gimbal_fmu, slave, 0.0, 80)
        slave.reset()
        slave.setupExperiment(startTime=0.0)
        gimbal_fmu.set_values(slave, START)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        assert np.array_equal(run(gimbal_fmu, slave, 0.0, 80), reference)
    finally:
        slave.freeInstance()
    fresh = started(gimbal_fmu, "fresh")
    try:
        assert np.array_equal(run(gimbal_fmu, fresh, 0.0, 80), reference)
    finally:
        fresh.freeInstance()


def test_instances_in_threads_match_one_at_a_time(gimbal_fmu):
    gains = [20.0, 35.0, 50.0, 65.0]

    def scene(gain):
        controller = lambda t, y: {"u_R1": gain * (0.2 - y["alpha"]) - 1.0 * y["alpha_dot"],
                                   "u_R2": gain * (-0.1 - y["beta"]) - 1.0 * y["beta_dot"]}
        return simulate(gimbal_fmu, 0.3, STEP, START, controller, OUTPUTS, instance_name=f"gain{gain}")

    serial = [scene(g) for g in gains]
    parallel = [None] * len(gains)

    def worker(k):
        parallel[k] = scene(gains[k])

    threads = [threading.Thread(target=worker, args=(k,)) for k in range(len(gains))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(serial, parallel):
        for name in OUTPUTS:
            assert np.array_equal(a[name], b[name]), name
    assert not np.array_equal(serial[0]["alpha"], serial[-1]["alpha"])  # the cases really differ


def test_integrator_failure_discards_and_rolls_back(gimbal_fmu):
    log = []
    slave = started(gimbal_fmu, log=log, start=dict(START, **{"solver.max_steps": 200}))
    try:
        gimbal_fmu.set_values(slave, {"u_R1": 10.0})
        slave.doStep(0.0, 1e-4)  # 200 internal steps are enough for this...
        before = gimbal_fmu.get_values(slave, OUTPUTS)
        with pytest.raises(FMICallException) as failure:
            slave.doStep(1e-4, 0.1)  # ...but not for this
        assert failure.value.status == DISCARD
        assert any(status == DISCARD and "rolled back to t = 0.0001" in text and
                   ("CV_TOO_MUCH_WORK" in text or "more than solver.max_steps = 200" in text)
                   for status, _, text in log), log[-3:]
        assert slave.getRealStatus(fmi2LastSuccessfulTime) == 1e-4
        assert slave.getStatus(fmi2DoStepStatus) == DISCARD
        assert gimbal_fmu.get_values(slave, OUTPUTS) == before
        # The standard's way on: restore an earlier state and continue with smaller steps.
        with pytest.raises(FMICallException):
            slave.doStep(1e-4, 1e-4)  # not allowed in stepFailed
        slave.terminate()
    finally:
        slave.freeInstance()


def test_outputs_are_computed_in_initialization_mode(gimbal_fmu):
    slave = gimbal_fmu.instantiate("init")
    try:
        slave.setupExperiment(startTime=0.0)
        eta = 2e-4
        deflection = 1e-3  # beyond the stop: contact at +eta
        # Wound beyond the stop with theta_b at +eta: in contact, T_E = k_s (theta_d - eta).
        gimbal_fmu.set_values(slave, {"gear2.eta": eta, "beta_m": 60.0 * deflection, "theta_b2": eta})
        slave.enterInitializationMode()
        torque, contact = gimbal_fmu.get_values(slave, ["T_E2", "gear2.contact"])
        stiffness = next(v.start for v in gimbal_fmu.model_description.modelVariables if v.name == "gear2.k_s")
        assert contact == 1 and torque == pytest.approx(float(stiffness) * (deflection - eta), rel=1e-12)
        slave.exitInitializationMode()
        assert gimbal_fmu.get_values(slave, ["T_E2"])[0] == torque
    finally:
        slave.freeInstance()


def test_debug_logging_categories_switch_event_messages(gimbal_fmu):
    log = []
    slave = started(gimbal_fmu, log=log)
    try:
        run(gimbal_fmu, slave, 0.0, 40, record=False)
        assert not any(category == "logEvents" for _, category, _ in log)
        slave.setDebugLogging(True, ["logEvents"])
        run(gimbal_fmu, slave, 0.04, 40, record=False)
        events = [text for _, category, text in log if category == "logEvents"]
        assert events and "mode change" in events[0]
        # Each message names the element that switched and how, e.g. "gear1 backlash: gap -> +eta stop".
        elements = ("backlash: ", "current limiter: ", "voltage clamp: ", "dry friction: ")
        assert all(any(element in text for element in elements) and " -> " in text for text in events
                   if "chattering" not in text), events[:5]
        slave.setDebugLogging(False, ["logEvents"])
        count = len(log)
        run(gimbal_fmu, slave, 0.08, 40, record=False)
        assert len(log) == count
        with pytest.raises(FMICallException):
            slave.setDebugLogging(True, ["logNonsense"])
        assert "unknown log category 'logNonsense'" in log[-1][2] and log[-1][0] == ERROR
    finally:
        slave.freeInstance()


def test_calls_in_the_wrong_state_are_refused_and_named(gimbal_fmu):
    log = []
    slave = gimbal_fmu.instantiate("states", log=log)
    try:
        with pytest.raises(FMICallException):
            slave.doStep(0.0, STEP)
        assert "fmi2DoStep is not allowed in state 'instantiated'" in log[-1][2]
        with pytest.raises(FMICallException):
            slave.getReal([gimbal_fmu.vr("alpha")])
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.terminate()
        with pytest.raises(FMICallException):
            gimbal_fmu.set_values(slave, {"u_R1": 1.0})
        assert "fmi2SetReal is not allowed in state 'terminated'" in log[-1][2]
        # Outputs stay readable after termination.
        gimbal_fmu.get_values(slave, ["alpha"])
    finally:
        slave.freeInstance()


def test_the_package_reads_the_states_from_the_model_description(gimbal_fmu):
    """gimbal2axis takes the states from the model description (outputs with initial="exact"), not from
    a list of its own: they are the 12 states of docs/physics.md section 3.3, in that order."""
    assert gimbal_fmu.states == STATES
