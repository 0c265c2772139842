/* The ship-motion FMU's FMI 2.0 Co-Simulation interface: the state machine, the checks of every
 * argument and value, logging, over ship_motion.h. Every exported fmi2* function holds the host's
 * floating-point environment around its implementation (host_fp_environment.h), as the gimbal's do.
 *
 * The clock: the outputs after k steps are row k of the grid at t = k h from the motion's start, h
 * the first doStep's step size; the motion is that of the scene runner's grid from t = 0 (the FMU
 * does not depend on the absolute start time, nor on how the master keeps its clock: its time is the
 * master's last point plus the step, communication_point.h). A doStep with another step size is
 * refused: its outputs would no longer be the grid's rows (canHandleVariableCommunicationStepSize=
 * "false"); one far below the grid's step is the master's clock rounding and moves no row.
 *
 * With motion = 1 the outputs are a recording's splines (recorded_motion.h) at the same grid times,
 * read at the end of initialization from recording_file (recording_file.h finds it); a step past the
 * recording's end is refused, as the scene runner refuses a recording that does not cover its run. */
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "fmi_layer/fmi2_face.h"
#include "gimbal_kernel/recorded_motion.h"
#include "host_fp_environment.h"
#include "recording_file.h"
#include "ship_motion.h"
#include "ship_motion_guid.h"
#include "ship_motion_variables.h"

typedef struct {
    FmiInstance common; /* first: fmi_instantiate allocates the Instance around it */
    ShipMotionParameters parameters;
    char* recording_file;             /* the String parameter's value, the instance's copy */
    char* resources;                  /* the resources folder, NULL when fmuResourceLocation names none */
    ShipMotion motion;
    GimbalRecordedMotion* recording; /* motion = 1: the file's splines, once prepared */
    int prepared;       /* motion or recording holds what `parameters` say */
    double start_time;
    double step;        /* 0 until the first doStep */
    long row;           /* the grid row of the current communication point */
    double outputs[SHIP_MOTION_OUTPUTS];
    fmi2Status last_step_status;
} Instance;
_Static_assert(offsetof(Instance, common) == 0, "the FmiInstance must be the Instance's first member");

/* Below this fraction of the grid's step, a step is the master's clock rounding (see impl_DoStep). */
static const double kClockRoundingOfStep = 1e-6;

#define REFUSE(instance, ...)                               \
    do {                                                    \
        fmi_log_error(&(instance)->common, __VA_ARGS__);    \
        return fmi2Error;                                   \
    } while (0)

/* NULL-safe: is `function` allowed in the instance's state (a mask of InstanceState)? */
static int allowed(Instance* instance, const char* function, int states) {
    return instance != NULL && fmi_allowed(&instance->common, function, states);
}

static int not_null(Instance* instance, const char* function, const void* pointer, const char* argument) {
    return fmi_not_null(&instance->common, function, pointer, argument);
}

static char* copy_text(const char* text) {
    char* copy = (char*)malloc(strlen(text) + 1);
    if (copy != NULL) strcpy(copy, text);
    return copy;
}

/* The model's fields follow the FmiInstance: fmi_instantiate allocates them, zeroed; the instance's
 * own setup (its resources folder, the start values) is fmi2Instantiate's. */
static void* model_fields(FmiInstance* instance) { return instance; }
static void no_own_allocation(void* model) { (void)model; }

static const char* const kLogCategories[] = {"logStatusError", "logAll"};

/* canGetAndSetFMUstate is false: the FMU-state calls are refused before they reach the layer. */
static const FmiModel kShipMotionModel = {
    SHIP_MOTION_GUID, sizeof(Instance), kLogCategories, (int)(sizeof kLogCategories / sizeof kLogCategories[0]),
    model_fields, no_own_allocation, NULL, NULL, NULL, NULL, NULL,
};

static const int kGetStates = STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_TERMINATED | STATE_ERROR;
static const int kSetStates = STATE_INSTANTIATED | STATE_INITIALIZATION;
static const int kAnyState = STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_TERMINATED | STATE_ERROR;

/* The recording of recording_file, checked to cover the experiment from t = 0 (the grid's time; a
 * stopTime, when given, to its end), and row 0. */
static fmi2Status prepare_recording(Instance* instance, const char* function) {
    char message[1024];
    char* path = recording_path(instance->resources, instance->recording_file, message, sizeof message);
    if (path == NULL) REFUSE(instance, "%s: %s", function, message);
    size_t length = 0;
    char* text = recording_read(path, &length, message, sizeof message);
    if (text == NULL) {
        free(path);
        REFUSE(instance, "%s: %s", function, message);
    }
    const int status = gimbal_recorded_motion_read(text, length, &instance->recording, message, sizeof message);
    free(text);
    if (status != GIMBAL_RECORDED_MOTION_READ) {
        fmi_log_error(&instance->common, "%s: recorded motion %s: %s", function, path, message);
        free(path);
        return fmi2Error;
    }
    const double start = gimbal_recorded_motion_start(instance->recording);
    const double end = gimbal_recorded_motion_end(instance->recording);
    const double duration = instance->common.stop_time - instance->start_time;
    if (start > 0.0 || (instance->common.stop_time_defined && end < duration)) {
        if (instance->common.stop_time_defined)
            fmi_log_error(&instance->common, "%s: recorded motion %s covers [%g, %g] s, not [0, %g] s",
                        function, path, start, end, duration);
        else
            fmi_log_error(&instance->common,
                        "%s: recorded motion %s covers [%g, %g] s, not t = 0, where the outputs start", function, path,
                        start, end);
        free(path);
        gimbal_recorded_motion_free(instance->recording);
        instance->recording = NULL;
        return fmi2Error;
    }
    free(path);
    instance->prepared = 1;
    gimbal_recorded_motion_row(instance->recording, 0.0, instance->outputs);
    return fmi2OK;
}

/* Parameters that pass their checks can still give no finite motion (amplitudes near the largest
 * double, whose rates and accelerations overflow): the row is refused, naming the first output that
 * is not finite, and the outputs keep their last values; the host never reads a NaN. */
static int finite_row(Instance* instance, const double row[], const char* function, double time) {
    for (int k = 0; k < SHIP_MOTION_OUTPUTS; ++k) {
        if (isfinite(row[k])) continue;
        fmi_log_error(&instance->common, "%s: %s = %g at t = %.17g: the sea state's parameters give no finite motion",
                      function, kShipRealVariables[k].name, row[k], time);
        return 0;
    }
    return 1;
}

/* What the current parameters say (the sea state's components or the recording), and row 0 (the
 * outputs before the first step). */
static fmi2Status prepare(Instance* instance, const char* function) {
    if (instance->prepared) return fmi2OK;
    if (instance->parameters.motion == SHIP_MOTION_RECORDED) return prepare_recording(instance, function);
    char message[512];
    if (ship_motion_check(&instance->parameters, message, sizeof message) != 0)
        REFUSE(instance, "%s: %s", function, message);
    if (ship_motion_prepare(&instance->motion, &instance->parameters, 0.0) != 0)
        REFUSE(instance, "%s: out of memory for the sea state's components", function);
    double row[SHIP_MOTION_OUTPUTS];
    ship_motion_row(&instance->motion, 0, row);
    if (!finite_row(instance, row, function, instance->start_time)) {
        ship_motion_release(&instance->motion);
        return fmi2Error;
    }
    instance->prepared = 1;
    memcpy(instance->outputs, row, sizeof row);
    return fmi2OK;
}

static void unprepare(Instance* instance) {
    ship_motion_release(&instance->motion);
    gimbal_recorded_motion_free(instance->recording);
    instance->recording = NULL;
    instance->prepared = 0;
}

/* ---------------------------------------------------------------- inquiry, logging, lifetime */

static fmi2Status impl_SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                       const fmi2String categories[]) {
    Instance* instance = (Instance*)c;
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)fmi_set_debug_logging(&instance->common, "fmi2SetDebugLogging", loggingOn != fmi2False, nCategories,
                                             categories);
}

/* 0, or -1 when out of memory (the recording file's value then stays as it was). */
static int reset_instance(Instance* instance) {
    unprepare(instance);
    char* file = copy_text(kShipStringVariables[SHIP_STRING_RECORDING_FILE].start);
    if (file == NULL) return -1;
    free(instance->recording_file);
    instance->recording_file = file;
    ship_motion_start_parameters(&instance->parameters);
    instance->start_time = 0.0;
    instance->common.time = 0.0;
    instance->step = 0.0;
    instance->row = 0;
    instance->common.stop_time_defined = 0;
    instance->common.stop_time = 0.0;
    instance->last_step_status = fmi2OK;
    for (int k = 0; k < SHIP_MOTION_OUTPUTS; ++k) instance->outputs[k] = 0.0;
    instance->common.state = STATE_INSTANTIATED;
    return 0;
}

static fmi2Component impl_Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                      fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions,
                                      fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)visible;
    Instance* instance =
        (Instance*)fmi2_instantiate(&kShipMotionModel, 0, instanceName, fmuType, fmuGUID, functions, loggingOn);
    if (instance == NULL) return NULL;
    /* No resources folder is no error here: only a relative recording_file needs one. */
    instance->resources = recording_resources_folder(fmuResourceLocation);
    if (reset_instance(instance) != 0) {
        fmi_log_error(&instance->common, "fmi2Instantiate: out of memory");
        free(instance->resources);
        fmi_free_instance(&instance->common);
        return NULL;
    }
    return instance;
}

static void impl_FreeInstance(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (instance == NULL) return;
    unprepare(instance);
    free(instance->recording_file);
    free(instance->resources);
    fmi_free_instance(&instance->common);
}

/* ---------------------------------------------------------------- initialization and termination */

static fmi2Status impl_SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                       fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Instance* instance = (Instance*)c;
    (void)toleranceDefined;
    (void)tolerance; /* the motion is exact: no tolerance to meet */
    if (!allowed(instance, "fmi2SetupExperiment", STATE_INSTANTIATED)) return fmi2Error;
    if (!fmi_experiment_times_valid(&instance->common, "fmi2SetupExperiment", startTime, stopTimeDefined != fmi2False,
                                    stopTime))
        return fmi2Error;
    instance->start_time = startTime;
    instance->common.time = startTime;
    instance->common.stop_time_defined = stopTimeDefined ? 1 : 0;
    instance->common.stop_time = stopTime;
    return fmi2OK;
}

static fmi2Status impl_EnterInitializationMode(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2EnterInitializationMode", STATE_INSTANTIATED)) return fmi2Error;
    instance->common.state = STATE_INITIALIZATION;
    return fmi2OK;
}

static fmi2Status impl_ExitInitializationMode(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2ExitInitializationMode", STATE_INITIALIZATION)) return fmi2Error;
    /* Refused parameters leave the instance in initialization mode: the master may correct them. */
    if (prepare(instance, "fmi2ExitInitializationMode") != fmi2OK) return fmi2Error;
    instance->row = 0;
    instance->common.time = instance->start_time;
    instance->common.state = STATE_STEP_COMPLETE;
    return fmi2OK;
}

static fmi2Status impl_Terminate(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2Terminate", STATE_STEP_COMPLETE | STATE_ERROR)) return fmi2Error;
    instance->common.state = STATE_TERMINATED;
    return fmi2OK;
}

static fmi2Status impl_Reset(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2Reset", kAnyState)) return fmi2Error;
    if (reset_instance(instance) != 0) REFUSE(instance, "fmi2Reset: out of memory for recording_file's start value");
    return fmi2OK;
}

/* ---------------------------------------------------------------- values */

static int check_array_arguments(Instance* instance, const char* function, const fmi2ValueReference vr[], size_t nvr,
                                 const void* value) {
    return nvr == 0 || (not_null(instance, function, vr, "vr") && not_null(instance, function, value, "value"));
}

static fmi2Status impl_GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetReal", kGetStates) ||
        !check_array_arguments(instance, "fmi2GetReal", vr, nvr, value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        if (vr[i] >= SHIP_REAL_COUNT) REFUSE(instance, "fmi2GetReal: value reference %u is not a Real variable", (unsigned)vr[i]);
        if (vr[i] < SHIP_REAL_OUTPUTS) {
            /* In initialization mode the outputs are row 0 of the parameters as they are now. */
            if (prepare(instance, "fmi2GetReal") != fmi2OK) return fmi2Error;
            value[i] = instance->outputs[vr[i]];
        } else {
            value[i] = *ship_real_parameter(&instance->parameters, vr[i]);
        }
    }
    return fmi2OK;
}

static fmi2Status impl_GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetInteger", kGetStates) ||
        !check_array_arguments(instance, "fmi2GetInteger", vr, nvr, value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        if (vr[i] >= SHIP_INTEGER_COUNT)
            REFUSE(instance, "fmi2GetInteger: value reference %u is not an Integer variable", (unsigned)vr[i]);
        value[i] = *ship_integer_parameter(&instance->parameters, vr[i]);
    }
    return fmi2OK;
}

/* A value the variable's bounds (and those the XML cannot say: > min, finite) refuse, named; 0 if fine. */
static int real_refused(Instance* instance, const char* function, fmi2ValueReference vr, double value) {
    if (vr >= SHIP_REAL_COUNT) {
        fmi_log_error(&instance->common, "%s: value reference %u is not a Real variable", function,
                    (unsigned)vr);
        return 1;
    }
    const ShipRealVariable* variable = &kShipRealVariables[vr];
    if (variable->causality == SHIP_OUTPUT) {
        fmi_log_error(&instance->common, "%s: %s is an output and cannot be set", function, variable->name);
        return 1;
    }
    if (!isfinite(value)) {
        fmi_log_error(&instance->common, "%s: %s = %g must be finite", function, variable->name, value);
        return 1;
    }
    if (variable->min_exclusive ? !(value > variable->min) : !(value >= variable->min)) {
        fmi_log_error(&instance->common, "%s: %s = %.17g must be %s %g", function, variable->name,
                    value, variable->min_exclusive ? ">" : ">=", variable->min);
        return 1;
    }
    return 0;
}

static fmi2Status impl_SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2SetReal", kSetStates) || !check_array_arguments(instance, "fmi2SetReal", vr, nvr, value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) /* all or nothing: every value checked before any is applied */
        if (real_refused(instance, "fmi2SetReal", vr[i], value[i])) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) *ship_real_parameter(&instance->parameters, vr[i]) = value[i];
    if (nvr > 0) unprepare(instance);
    return fmi2OK;
}

static fmi2Status impl_SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2SetInteger", kSetStates) ||
        !check_array_arguments(instance, "fmi2SetInteger", vr, nvr, value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        if (vr[i] >= SHIP_INTEGER_COUNT)
            REFUSE(instance, "fmi2SetInteger: value reference %u is not an Integer variable", (unsigned)vr[i]);
        const ShipIntegerVariable* variable = &kShipIntegerVariables[vr[i]];
        if (value[i] < variable->min || value[i] > variable->max)
            REFUSE(instance, "fmi2SetInteger: %s = %d must be in [%d, %d]", variable->name, (int)value[i], variable->min,
                   variable->max);
    }
    for (size_t i = 0; i < nvr; ++i) *ship_integer_parameter(&instance->parameters, vr[i]) = value[i];
    if (nvr > 0) unprepare(instance);
    return fmi2OK;
}

static fmi2Status impl_GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetString", kGetStates) ||
        !check_array_arguments(instance, "fmi2GetString", vr, nvr, value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        if (vr[i] >= SHIP_STRING_COUNT)
            REFUSE(instance, "fmi2GetString: value reference %u is not a String variable", (unsigned)vr[i]);
        value[i] = instance->recording_file; /* valid until it is set again or the instance is freed */
    }
    return fmi2OK;
}

static fmi2Status impl_SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2SetString", kSetStates) ||
        !check_array_arguments(instance, "fmi2SetString", vr, nvr, value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) { /* all checked before any is applied */
        if (vr[i] >= SHIP_STRING_COUNT)
            REFUSE(instance, "fmi2SetString: value reference %u is not a String variable", (unsigned)vr[i]);
        if (value[i] == NULL)
            REFUSE(instance, "fmi2SetString: the value of %s is a null pointer", kShipStringVariables[vr[i]].name);
    }
    for (size_t i = 0; i < nvr; ++i) {
        char* copy = copy_text(value[i]);
        if (copy == NULL) REFUSE(instance, "fmi2SetString: out of memory for %s", kShipStringVariables[vr[i]].name);
        free(instance->recording_file);
        instance->recording_file = copy;
    }
    if (nvr > 0) unprepare(instance);
    return fmi2OK;
}

/* The FMU has no Boolean variables. */
static fmi2Status no_variables(Instance* instance, const char* function, int states, const fmi2ValueReference vr[],
                               size_t nvr, const void* value, const char* type) {
    if (!allowed(instance, function, states) || !check_array_arguments(instance, function, vr, nvr, value))
        return fmi2Error;
    if (nvr > 0) REFUSE(instance, "%s: value reference %u is not a %s variable (this FMU has none)", function, (unsigned)vr[0], type);
    return fmi2OK;
}

/* ---------------------------------------------------------------- stepping */

/* fmi2DoStep of motion = 1: the recording's splines at the next row's time. */
static fmi2Status step_recording(Instance* instance, double step, double end_time) {
    /* The grid's time, not the master's: the motion starts at t = 0 whatever startTime is. */
    const double motion_time = (double)(instance->row + 1) * step;
    const double end = gimbal_recorded_motion_end(instance->recording);
    if (motion_time > end + 1e-12 * fmax(1.0, fabs(end)) + 1e-6 * step)
        REFUSE(instance, "fmi2DoStep: step to t = %.17g s (the recording's time %.17g s) passes the recording's end at %.17g s",
               end_time, motion_time, end);
    instance->step = step;
    instance->row += 1;
    instance->common.time = end_time;
    gimbal_recorded_motion_row(instance->recording, motion_time, instance->outputs);
    instance->last_step_status = fmi2OK;
    return fmi2OK;
}

static fmi2Status impl_DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                              fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Instance* instance = (Instance*)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(instance, "fmi2DoStep", STATE_STEP_COMPLETE)) return fmi2Error;
    /* The master's point becomes the FMU's time; the outputs stay the rows of the grid, counted,
     * whatever clock the master keeps. */
    if (!fmi_step_valid(&instance->common, "fmi2DoStep", currentCommunicationPoint, communicationStepSize))
        return fmi2Error;
    const double end_time = currentCommunicationPoint + communicationStepSize;
    /* A master whose clock rounds differently from its step (an SSP engine that ends on its stop time
     * with a last step of 5e-11 s) takes a step far below the grid's: the clock's rounding, not a
     * step. The rows stay where they are; only the time follows the master. */
    if (instance->step != 0.0 && communicationStepSize < kClockRoundingOfStep * instance->step) {
        instance->common.time = end_time;
        instance->last_step_status = fmi2OK;
        return fmi2OK;
    }
    /* A master that keeps time in integer nanoseconds (libcosim) passes steps a few units in the last
     * place off h: the same grid step. More than that is another step, which the grid cannot give. */
    if (instance->step != 0.0 && !(fabs(communicationStepSize - instance->step) <= 1e-9 * instance->step))
        REFUSE(instance,
               "fmi2DoStep: communicationStepSize = %.17g differs from the first step's %.17g: the outputs are the rows "
               "of one grid (canHandleVariableCommunicationStepSize=\"false\")",
               communicationStepSize, instance->step);
    const double step = instance->step != 0.0 ? instance->step : communicationStepSize;
    if (instance->row >= LONG_MAX - 1) REFUSE(instance, "fmi2DoStep: the grid's %ld rows are used up", instance->row);
    if (instance->recording != NULL) return step_recording(instance, step, end_time);
    if (instance->step == 0.0) {
        if (ship_motion_set_step(&instance->motion, step) != 0) {
            instance->common.state = STATE_ERROR;
            instance->last_step_status = fmi2Error;
            REFUSE(instance, "fmi2DoStep: out of memory for the rotation tables of step %g", step);
        }
        instance->step = step;
    }
    double row[SHIP_MOTION_OUTPUTS];
    ship_motion_row(&instance->motion, instance->row + 1, row);
    if (!finite_row(instance, row, "fmi2DoStep", end_time)) {
        instance->common.state = STATE_ERROR;
        instance->last_step_status = fmi2Error;
        return fmi2Error;
    }
    instance->row += 1;
    instance->common.time = end_time;
    memcpy(instance->outputs, row, sizeof row);
    instance->last_step_status = fmi2OK;
    return fmi2OK;
}

static fmi2Status impl_GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetStatus", STATE_STEP_COMPLETE | STATE_TERMINATED | STATE_ERROR) ||
        !not_null(instance, "fmi2GetStatus", value, "value"))
        return fmi2Error;
    if (s != fmi2DoStepStatus) REFUSE(instance, "fmi2GetStatus: status kind %d is not a fmi2Status", (int)s);
    *value = instance->last_step_status;
    return fmi2OK;
}

static fmi2Status impl_GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetRealStatus", STATE_STEP_COMPLETE | STATE_TERMINATED | STATE_ERROR) ||
        !not_null(instance, "fmi2GetRealStatus", value, "value"))
        return fmi2Error;
    if (s != fmi2LastSuccessfulTime) REFUSE(instance, "fmi2GetRealStatus: status kind %d is not a Real status", (int)s);
    *value = instance->common.time;
    return fmi2OK;
}

static fmi2Status impl_GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetBooleanStatus", STATE_STEP_COMPLETE | STATE_TERMINATED | STATE_ERROR) ||
        !not_null(instance, "fmi2GetBooleanStatus", value, "value"))
        return fmi2Error;
    if (s != fmi2Terminated) REFUSE(instance, "fmi2GetBooleanStatus: status kind %d has no Boolean value", (int)s);
    *value = fmi2False; /* the FMU never asks to end the simulation */
    return fmi2OK;
}

static fmi2Status impl_GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetStringStatus", STATE_STEP_COMPLETE | STATE_TERMINATED | STATE_ERROR) ||
        !not_null(instance, "fmi2GetStringStatus", value, "value"))
        return fmi2Error;
    if (s != fmi2PendingStatus) REFUSE(instance, "fmi2GetStringStatus: status kind %d has no String value", (int)s);
    *value = ""; /* doStep is synchronous: never pending */
    return fmi2OK;
}

/* What the model description says the FMU does not do. */
static fmi2Status unsupported(fmi2Component c, const char* function, const char* because) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, function, kAnyState)) return fmi2Error;
    REFUSE(instance, "%s: not supported (%s)", function, because);
}

/* ---------------------------------------------------------------- the exported functions */

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories, const fmi2String categories[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetDebugLogging(c, loggingOn, nCategories, categories));
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    IN_FMU_FP_ENVIRONMENT(fmi2Component,
                          impl_Instantiate(instanceName, fmuType, fmuGUID, fmuResourceLocation, functions, visible, loggingOn));
}

void fmi2FreeInstance(fmi2Component c) {
    HostFpEnvironment host_environment;
    enter_fmu_fp(&host_environment);
    impl_FreeInstance(c);
    leave_fmu_fp(&host_environment);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status,
                          impl_SetupExperiment(c, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_EnterInitializationMode(c)); }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_ExitInitializationMode(c)); }
fmi2Status fmi2Terminate(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_Terminate(c)); }
fmi2Status fmi2Reset(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_Reset(c)); }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetReal(c, vr, nvr, value));
}
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetInteger(c, vr, nvr, value));
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, no_variables((Instance*)c, "fmi2GetBoolean", kGetStates, vr, nvr, value, "Boolean"));
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetString(c, vr, nvr, value));
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetReal(c, vr, nvr, value));
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetInteger(c, vr, nvr, value));
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, no_variables((Instance*)c, "fmi2SetBoolean", kSetStates, vr, nvr, value, "Boolean"));
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetString(c, vr, nvr, value));
}

static const char kNoState[] = "canGetAndSetFMUstate=\"false\"";

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    (void)FMUstate;
    IN_FMU_FP_ENVIRONMENT(fmi2Status, unsupported(c, "fmi2GetFMUstate", kNoState));
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    (void)FMUstate;
    IN_FMU_FP_ENVIRONMENT(fmi2Status, unsupported(c, "fmi2SetFMUstate", kNoState));
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    (void)FMUstate;
    IN_FMU_FP_ENVIRONMENT(fmi2Status, unsupported(c, "fmi2FreeFMUstate", kNoState));
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size) {
    (void)FMUstate;
    (void)size;
    IN_FMU_FP_ENVIRONMENT(fmi2Status, unsupported(c, "fmi2SerializedFMUstateSize", "canSerializeFMUstate=\"false\""));
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    (void)FMUstate;
    (void)serializedState;
    (void)size;
    IN_FMU_FP_ENVIRONMENT(fmi2Status, unsupported(c, "fmi2SerializeFMUstate", "canSerializeFMUstate=\"false\""));
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size, fmi2FMUstate* FMUstate) {
    (void)serializedState;
    (void)size;
    (void)FMUstate;
    IN_FMU_FP_ENVIRONMENT(fmi2Status, unsupported(c, "fmi2DeSerializeFMUstate", "canSerializeFMUstate=\"false\""));
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    IN_FMU_FP_ENVIRONMENT(fmi2Status, unsupported(c, "fmi2GetDirectionalDerivative", "providesDirectionalDerivative=\"false\""));
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    IN_FMU_FP_ENVIRONMENT(fmi2Status, unsupported(c, "fmi2SetRealInputDerivatives", "the FMU has no inputs"));
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    IN_FMU_FP_ENVIRONMENT(fmi2Status, unsupported(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder=\"0\""));
}
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status,
                          impl_DoStep(c, currentCommunicationPoint, communicationStepSize, noSetFMUStatePriorToCurrentPoint));
}
fmi2Status fmi2CancelStep(fmi2Component c) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, unsupported(c, "fmi2CancelStep", "doStep never runs asynchronously"));
}
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetStatus(c, s, value));
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetRealStatus(c, s, value));
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value) {
    (void)s;
    (void)value;
    IN_FMU_FP_ENVIRONMENT(fmi2Status, unsupported(c, "fmi2GetIntegerStatus", "no status kind has an Integer value"));
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetBooleanStatus(c, s, value));
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetStringStatus(c, s, value));
}
