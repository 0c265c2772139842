"""The FMI 2.0 face of every FMU (fmu_src/fmi_layer/fmi2_functions.c), here the small FMUs': the
ship-motion and the controller FMU, each a model file and its table behind it, answer the calls the
face owns alike (the refusals of what their model descriptions declare absent, the status calls, an
unknown value reference), each message naming the function and the culprit; and the status calls
report the step the model took."""
import ctypes

import pytest
from fmpy.fmi1 import FMICallException

from gimbal2axis.fmu import FMU

FMI2_DO_STEP_STATUS, FMI2_PENDING_STATUS, FMI2_LAST_SUCCESSFUL_TIME, FMI2_TERMINATED = 0, 1, 2, 3
SMALL_FMUS = ["Gimbal2Axis-ShipMotion.fmu", "Gimbal2Axis-Controller.fmu"]


@pytest.fixture(scope="module", params=SMALL_FMUS)
def small_fmu(request, build_dir):
    path = build_dir / request.param
    if not path.is_file():
        pytest.fail(f"{path} is missing: the build did not package it")
    with FMU(path) as fmu:
        yield fmu


def initialized(fmu, log):
    slave = fmu.instantiate("small", log)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave


def refused(log, call, expected):
    """`call` raises, and the last message logged is the error `expected`."""
    with pytest.raises(FMICallException):
        call()
    assert log and log[-1].status == 3 and log[-1].category == "logStatusError", log
    assert log[-1].text == expected, log[-1]


def test_what_the_model_descriptions_declare_absent_is_refused_alike(small_fmu):
    md = small_fmu.model_description
    assert md.coSimulation.canGetAndSetFMUstate is False and md.coSimulation.canSerializeFMUstate is False
    log = []
    slave = initialized(small_fmu, log)
    refused(log, slave.getFMUState, "fmi2GetFMUstate: canGetAndSetFMUstate is false")
    refused(log, slave.cancelStep, "fmi2CancelStep: fmi2DoStep never runs asynchronously")
    refused(log, lambda: slave.getIntegerStatus(FMI2_DO_STEP_STATUS),
            "fmi2GetIntegerStatus: no status kind has an Integer value")
    refused(log, lambda: slave.getRealStatus(FMI2_DO_STEP_STATUS),
            "fmi2GetRealStatus: status kind 0 is not a Real status")
    booleans = sum(1 for v in md.modelVariables if v.type == "Boolean")
    refused(log, lambda: slave.getBoolean([booleans]),
            f"fmi2GetBoolean: value reference {booleans} is not a Boolean variable"
            + (" (this FMU has none)" if booleans == 0 else ""))
    slave.freeInstance()


def test_status_calls_report_the_step_taken(small_fmu):
    log = []
    slave = initialized(small_fmu, log)
    h = 1.0 / 64.0   # a binary fraction: the end time is exact
    slave.doStep(0.0, h)
    slave.doStep(h, h)
    assert slave.getStatus(FMI2_DO_STEP_STATUS) == 0
    assert slave.getRealStatus(FMI2_LAST_SUCCESSFUL_TIME) == 2 * h
    assert slave.getBooleanStatus(FMI2_TERMINATED) is False
    assert slave.getStringStatus(FMI2_PENDING_STATUS) == ""
    slave.terminate()
    assert slave.getRealStatus(FMI2_LAST_SUCCESSFUL_TIME) == 2 * h
    slave.reset()   # back to instantiated: the status calls are refused again, naming the state
    refused(log, lambda: slave.getStatus(FMI2_DO_STEP_STATUS),
            "fmi2GetStatus is not allowed in state 'instantiated'")
    slave.freeInstance()
    assert all(entry.status != 3 for entry in log[:-1]), log


def test_model_exchange_functions_are_refused_naming_the_interfaces_offered(small_fmu):
    """The face every FMU shares exports FMI 2.0's Model Exchange functions too; a Co-Simulation-only
    model's table has none, and each call says so instead of reaching a model that is not there."""
    log = []
    slave = initialized(small_fmu, log)
    derivatives = (ctypes.c_double * 1)()
    get_derivatives, enter_event_mode = slave.dll.fmi2GetDerivatives, slave.dll.fmi2EnterEventMode
    get_derivatives.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t]
    enter_event_mode.argtypes = [ctypes.c_void_p]
    assert get_derivatives(slave.component, derivatives, 1) == 3
    assert log[-1].text == "fmi2GetDerivatives: a Model Exchange function; this FMU offers Co-Simulation only"
    assert enter_event_mode(slave.component) == 3
    assert log[-1].text == "fmi2EnterEventMode: a Model Exchange function; this FMU offers Co-Simulation only"
    slave.freeInstance()
