/* The ship-motion FMU's model file: ship_motion.h and the recorded motion behind the FMI 2.0 and FMI
 * 3.0 faces (fmi_layer/fmu_model.h), which check the states, pointers and value references and
 * export the fmi2* or fmi3* functions; here are the checks of the
 * values, the clock, the rows, and the FMU-state snapshot (offered by the FMI 3.0 FMU).
 *
 * The clock: the outputs after k steps are row k of the grid at t = k h from the motion's start, h
 * the first doStep's step size; the motion is that of the scene runner's grid from t = 0 (the FMU
 * does not depend on the absolute start time, nor on how the master keeps its clock: its time is the
 * master's last point plus the step, communication_point.h). A doStep with another step size is
 * refused, unless it ends on the grid's next point start + k h (a master's last step to its stop
 * time): its outputs would no longer be the grid's rows (canHandleVariableCommunicationStepSize=
 * "false"); one far below the grid's step, or ending on the grid's current point, is the master's
 * clock rounding and moves no row (communication_point.h: communication_grid_rows).
 *
 * With motion = 1 the outputs are a recording's splines (recorded_motion.h) at the same grid times,
 * read at the end of initialization from recording_file (recording_file.h finds it); a step past the
 * recording's end is refused, as the scene runner refuses a recording that does not cover its run.
 *
 * With target = 1 the target outputs are the splines of a table of the target's position relative to
 * the gimbal (recorded_target.h), read from target_file at the end of initialization and evaluated at
 * the same grid times, refused past its end as the recording is. */
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "common/communication_point.h"
#include "fmi_layer/fmu_model.h"
#include "gimbal_kernel/recorded_motion.h"
#include "gimbal_kernel/recorded_target.h"
#include "recording_file.h"
#include "ship_motion.h"
#include "ship_motion_guid.h"
#include "ship_motion_variables.h"

typedef struct {
    FmiInstance common; /* first: fmi_instantiate allocates the Instance around it */
    ShipMotionParameters parameters;
    char* recording_file;             /* the String parameter's value, the instance's copy */
    char* target_file;                /* the same of target_file */
    char* resources;                  /* the resources folder, NULL when fmuResourceLocation names none */
    ShipMotion motion;
    GimbalRecordedMotion* recording; /* motion = 1: the file's splines, once prepared */
    GimbalRecordedTarget* target;    /* target = 1: the table's splines, once prepared */
    int prepared;       /* motion or recording holds what `parameters` say */
    double start_time;
    double step;        /* 0 until the first doStep */
    long row;           /* the grid row of the current communication point */
    double outputs[SHIP_REAL_OUTPUTS]; /* the motion's, then the target's */
} Instance;
_Static_assert(offsetof(Instance, common) == 0, "the FmiInstance must be the Instance's first member");

#define REFUSE(instance, ...)                               \
    do {                                                    \
        fmi_log_error(&(instance)->common, __VA_ARGS__);    \
        return FMI_ERROR;                                   \
    } while (0)

static char* copy_text(const char* text) {
    char* copy = (char*)malloc(strlen(text) + 1);
    if (copy != NULL) strcpy(copy, text);
    return copy;
}

/* The model's fields follow the FmiInstance: fmi_instantiate allocates them, zeroed; the instance's
 * own setup (its resources folder, the start values) is `instantiated`'s. */
static void* model_fields(FmiInstance* instance) { return instance; }
static void no_own_allocation(void* model) { (void)model; }

static const char* const kLogCategories[] = {"logStatusError", "logAll"};

/* The text of `file` (absolute, or relative to the resources folder) into *text (its length into
 * *length) and its path into *path, both the caller's to free; 0, logged (after `prefix`), when it
 * cannot be found or read. */
static int read_file(Instance* instance, const char* function, const char* prefix, const char* file, char** path,
                     char** text, size_t* length) {
    char message[1024];
    *path = recording_path(instance->resources, file, message, sizeof message);
    if (*path == NULL) {
        fmi_log_error(&instance->common, "%s: %s%s", function, prefix, message);
        return 0;
    }
    *text = recording_read(*path, length, message, sizeof message);
    if (*text == NULL) {
        fmi_log_error(&instance->common, "%s: %s%s", function, prefix, message);
        free(*path);
        return 0;
    }
    return 1;
}

/* Whether a table over [start, end] covers the experiment from t = 0 (the grid's time; a stopTime,
 * when given, to its end); else 0, logged naming `what` at `path`. */
static int covers_experiment(Instance* instance, const char* function, const char* what, const char* path, double start,
                             double end) {
    const double duration = instance->common.stop_time - instance->start_time;
    if (!(start > 0.0 || end < 0.0 || (instance->common.stop_time_defined && end < duration))) return 1;
    if (instance->common.stop_time_defined)
        fmi_log_error(&instance->common, "%s: %s %s covers [%g, %g] s, not [0, %g] s", function, what, path, start, end,
                      duration);
    else
        fmi_log_error(&instance->common, "%s: %s %s covers [%g, %g] s, not t = 0, where the outputs start", function,
                      what, path, start, end);
    return 0;
}

/* The recording of recording_file, checked to cover the experiment, and row 0. */
static FmiStatus prepare_recording(Instance* instance, const char* function) {
    char message[1024];
    char *path, *text;
    size_t length = 0;
    if (!read_file(instance, function, "", instance->recording_file, &path, &text, &length)) return FMI_ERROR;
    const int status = gimbal_recorded_motion_read(text, length, &instance->recording, message, sizeof message);
    free(text);
    if (status != GIMBAL_RECORDED_MOTION_READ) {
        fmi_log_error(&instance->common, "%s: recorded motion %s: %s", function, path, message);
        free(path);
        return FMI_ERROR;
    }
    if (!covers_experiment(instance, function, "recorded motion", path, gimbal_recorded_motion_start(instance->recording),
                           gimbal_recorded_motion_end(instance->recording))) {
        free(path);
        gimbal_recorded_motion_free(instance->recording);
        instance->recording = NULL;
        return FMI_ERROR;
    }
    free(path);
    instance->prepared = 1;
    gimbal_recorded_motion_row(instance->recording, 0.0, instance->outputs);
    return FMI_OK;
}

/* Where the motion outputs come from, for finite_row's messages. */
static const char kSeaState[] = "the sea state's parameters give";
static const char kRecording[] = "the recording's splines give";

/* Parameters that pass their checks can still give no finite motion (amplitudes near the largest
 * double, whose rates and accelerations overflow), and the tables' splines are checked where they
 * are read, not at every time a step asks for: a row (its first `count` outputs, the motion's from
 * `motion_from`) is refused, naming the first output that is not finite, and the outputs keep their
 * last values; the host never reads a NaN with status OK. */
static int finite_row(Instance* instance, const double row[], int count, const char* function, double time,
                      const char* motion_from) {
    for (int k = 0; k < count; ++k) {
        if (isfinite(row[k])) continue;
        fmi_log_error(&instance->common, "%s: %s = %g at t = %.17g: %s no finite value", function,
                      kShipRealVariables[k].name, row[k], time,
                      k < SHIP_REAL_TARGET ? motion_from : "the target table's splines give");
        return 0;
    }
    return 1;
}

static const char* motion_source(const Instance* instance) {
    return instance->recording != NULL ? kRecording : kSeaState;
}

/* The sea state's components of the parameters, and row 0. */
static FmiStatus prepare_sea_state(Instance* instance, const char* function) {
    char message[512];
    if (ship_motion_check(&instance->parameters, message, sizeof message) != 0)
        REFUSE(instance, "%s: %s", function, message);
    if (ship_motion_prepare(&instance->motion, &instance->parameters, 0.0) != 0)
        REFUSE(instance, "%s: out of memory for the sea state's components", function);
    double row[SHIP_MOTION_OUTPUTS];
    ship_motion_row(&instance->motion, 0, row);
    if (!finite_row(instance, row, SHIP_MOTION_OUTPUTS, function, instance->start_time, kSeaState)) {
        ship_motion_release(&instance->motion);
        return FMI_ERROR;
    }
    instance->prepared = 1;
    memcpy(instance->outputs, row, sizeof row);
    return FMI_OK;
}

/* The target's table of target_file, checked to cover the experiment as the recording is, and row 0. */
static FmiStatus prepare_target(Instance* instance, const char* function) {
    char message[1024];
    char *path, *text;
    size_t length = 0;
    if (!read_file(instance, function, "target_file: ", instance->target_file, &path, &text, &length)) return FMI_ERROR;
    const int status = gimbal_recorded_target_read(text, length, &instance->target, message, sizeof message);
    free(text);
    if (status != GIMBAL_RECORDED_TARGET_READ) {
        fmi_log_error(&instance->common, "%s: target table %s: %s", function, path, message);
        free(path);
        return FMI_ERROR;
    }
    if (!covers_experiment(instance, function, "target table", path, gimbal_recorded_target_start(instance->target),
                           gimbal_recorded_target_end(instance->target))) {
        free(path);
        gimbal_recorded_target_free(instance->target);
        instance->target = NULL;
        return FMI_ERROR;
    }
    free(path);
    gimbal_recorded_target_row(instance->target, 0.0, instance->outputs + SHIP_REAL_TARGET);
    return FMI_OK;
}

static void unprepare(Instance* instance);

/* What the current parameters say (the sea state's components or the recording, and the target's
 * table), and row 0 (the outputs before the first step). */
static FmiStatus prepare(Instance* instance, const char* function) {
    if (instance->prepared) return FMI_OK;
    const FmiStatus status = instance->parameters.motion == SHIP_MOTION_RECORDED
                                 ? prepare_recording(instance, function)
                                 : prepare_sea_state(instance, function);
    if (status != FMI_OK) return status;
    if (instance->parameters.target == SHIP_TARGET_RECORDED && prepare_target(instance, function) != FMI_OK) {
        unprepare(instance);
        return FMI_ERROR;
    }
    if (!finite_row(instance, instance->outputs, SHIP_REAL_OUTPUTS, function, instance->start_time,
                    motion_source(instance))) {
        unprepare(instance);
        return FMI_ERROR;
    }
    return FMI_OK;
}

static void unprepare(Instance* instance) {
    ship_motion_release(&instance->motion);
    gimbal_recorded_motion_free(instance->recording);
    instance->recording = NULL;
    gimbal_recorded_target_free(instance->target);
    instance->target = NULL;
    instance->prepared = 0;
}

static Instance* ship(FmiInstance* instance) { return (Instance*)instance; }

/* ---------------------------------------------------------------- lifetime and reset */

/* 0, or -1 when out of memory (the recording file's value then stays as it was). */
static int reset_instance(Instance* instance) {
    unprepare(instance);
    char* file = copy_text(kShipStringVariables[SHIP_STRING_RECORDING_FILE].start);
    char* target_file = copy_text(kShipStringVariables[SHIP_STRING_TARGET_FILE].start);
    if (file == NULL || target_file == NULL) {
        free(file);
        free(target_file);
        return -1;
    }
    free(instance->recording_file);
    instance->recording_file = file;
    free(instance->target_file);
    instance->target_file = target_file;
    ship_motion_start_parameters(&instance->parameters);
    instance->start_time = 0.0;
    instance->common.time = 0.0;
    instance->step = 0.0;
    instance->row = 0;
    instance->common.stop_time_defined = 0;
    instance->common.stop_time = 0.0;
    instance->common.last_step_status = FMI_OK;
    for (int k = 0; k < SHIP_REAL_OUTPUTS; ++k) instance->outputs[k] = 0.0;
    instance->common.state = instance->common.face->instantiated_state;
    return 0;
}

static int instantiated(FmiInstance* common, const char* resource_location) {
    Instance* instance = ship(common);
    /* No resources folder is no error here: only a relative recording_file needs one. */
    instance->resources = common->face->resource_location_is_uri ? recording_resources_folder(resource_location)
                                                                 : recording_resources_folder_of_path(resource_location);
    return reset_instance(instance);
}

static void release(FmiInstance* common) {
    Instance* instance = ship(common);
    unprepare(instance);
    free(instance->recording_file);
    free(instance->target_file);
    free(instance->resources);
}

static FmiStatus reset(FmiInstance* common, const char* function) {
    if (reset_instance(ship(common)) != 0)
        REFUSE(ship(common), "%s: out of memory for the start values of recording_file and target_file", function);
    return FMI_OK;
}

/* ---------------------------------------------------------------- values */

static FmiStatus get_real(FmiInstance* common, const char* function, unsigned vr, void* value) {
    Instance* instance = ship(common);
    if (vr < SHIP_REAL_OUTPUTS) {
        /* In initialization mode the outputs are row 0 of the parameters as they are now. */
        if (prepare(instance, function) != FMI_OK) return FMI_ERROR;
        *(double*)value = instance->outputs[vr];
    } else {
        *(double*)value = *ship_real_parameter(&instance->parameters, vr);
    }
    return FMI_OK;
}

/* A value the variable's bounds (and those the XML cannot say: > min, finite) refuse, named. */
static int real_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    const ShipRealVariable* variable = &kShipRealVariables[vr];
    const double x = *(const double*)value;
    if (variable->causality == SHIP_OUTPUT) {
        fmi_log_error(instance, "%s: %s is an output and cannot be set", function, variable->name);
        return 0;
    }
    if (!isfinite(x)) {
        fmi_log_error(instance, "%s: %s = %g must be finite", function, variable->name, x);
        return 0;
    }
    if (variable->min_exclusive ? !(x > variable->min) : !(x >= variable->min)) {
        fmi_log_error(instance, "%s: %s = %.17g must be %s %g", function, variable->name, x,
                      variable->min_exclusive ? ">" : ">=", variable->min);
        return 0;
    }
    return 1;
}

static FmiStatus set_real(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)function;
    *ship_real_parameter(&ship(instance)->parameters, vr) = *(const double*)value;
    return FMI_OK;
}

static FmiStatus get_integer(FmiInstance* instance, const char* function, unsigned vr, void* value) {
    (void)function;
    *(int*)value = *ship_integer_parameter(&ship(instance)->parameters, vr);
    return FMI_OK;
}

static int integer_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    const ShipIntegerVariable* variable = &kShipIntegerVariables[vr];
    const int x = *(const int*)value;
    if (x >= variable->min && x <= variable->max) return 1;
    fmi_log_error(instance, "%s: %s = %d must be in [%d, %d]", function, variable->name, x, variable->min, variable->max);
    return 0;
}

static FmiStatus set_integer(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)function;
    *ship_integer_parameter(&ship(instance)->parameters, vr) = *(const int*)value;
    return FMI_OK;
}

/* The instance's copy of String variable vr. */
static char** string_value(Instance* instance, unsigned vr) {
    return vr == SHIP_STRING_TARGET_FILE ? &instance->target_file : &instance->recording_file;
}

static FmiStatus get_string(FmiInstance* instance, const char* function, unsigned vr, void* value) {
    (void)function;
    *(const char**)value = *string_value(ship(instance), vr); /* valid until it is set again or the instance is freed */
    return FMI_OK;
}

static int string_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    if (*(const char* const*)value != NULL) return 1;
    fmi_log_error(instance, "%s: the value of %s is a null pointer", function, kShipStringVariables[vr].name);
    return 0;
}

static FmiStatus set_string(FmiInstance* common, const char* function, unsigned vr, const void* value) {
    Instance* instance = ship(common);
    char* copy = copy_text(*(const char* const*)value);
    if (copy == NULL) REFUSE(instance, "%s: out of memory for %s", function, kShipStringVariables[vr].name);
    char** stored = string_value(instance, vr);
    free(*stored);
    *stored = copy;
    return FMI_OK;
}

/* New parameters: the motion is prepared again from them when next needed. */
static void values_set(FmiInstance* instance) { unprepare(ship(instance)); }

/* ---------------------------------------------------------------- initialization and stepping */

static void experiment_start(FmiInstance* instance, double start_time) { ship(instance)->start_time = start_time; }

static FmiStatus exit_initialization(FmiInstance* common, const char* function) {
    Instance* instance = ship(common);
    /* Refused parameters leave the instance in initialization mode: the master may correct them. */
    if (prepare(instance, function) != FMI_OK) return FMI_ERROR;
    instance->row = 0;
    instance->common.time = instance->start_time;
    return FMI_OK;
}

/* Whether the target's table (if any) reaches the next row's time on the grid of `step`: refused,
 * as a recording's end, before the step changes anything. */
static FmiStatus target_covers(Instance* instance, const char* function, double step, double end_time) {
    if (instance->target == NULL) return FMI_OK;
    const double motion_time = (double)(instance->row + 1) * step;
    const double end = gimbal_recorded_target_end(instance->target);
    if (motion_time > end + 1e-12 * fmax(1.0, fabs(end)) + 1e-6 * step)
        REFUSE(instance, "%s: step to t = %.17g s (the table's time %.17g s) passes the target table's end at %.17g s",
               function, end_time, motion_time, end);
    return FMI_OK;
}

/* The target outputs (if any) of the row at `motion_time` into row[SHIP_REAL_TARGET ...]. */
static void target_row(const Instance* instance, double motion_time, double row[SHIP_REAL_OUTPUTS]) {
    if (instance->target != NULL) gimbal_recorded_target_row(instance->target, motion_time, row + SHIP_REAL_TARGET);
}

/* The step's new row, when finite, becomes the outputs at end_time; else refused (the error state). */
static FmiStatus commit_row(Instance* instance, const char* function, const double row[SHIP_REAL_OUTPUTS], double step,
                            double end_time) {
    if (!finite_row(instance, row, SHIP_REAL_OUTPUTS, function, end_time, motion_source(instance))) {
        instance->common.state = instance->common.face->error_state;
        return FMI_ERROR;
    }
    instance->step = step;
    instance->row += 1;
    instance->common.time = end_time;
    memcpy(instance->outputs, row, sizeof instance->outputs);
    return FMI_OK;
}

/* A step of motion = 1: the recording's splines at the next row's time. */
static FmiStatus step_recording(Instance* instance, const char* function, double step, double end_time) {
    /* The grid's time, not the master's: the motion starts at t = 0 whatever startTime is. */
    const double motion_time = (double)(instance->row + 1) * step;
    const double end = gimbal_recorded_motion_end(instance->recording);
    if (motion_time > end + 1e-12 * fmax(1.0, fabs(end)) + 1e-6 * step)
        REFUSE(instance, "%s: step to t = %.17g s (the recording's time %.17g s) passes the recording's end at %.17g s",
               function, end_time, motion_time, end);
    double row[SHIP_REAL_OUTPUTS];
    memcpy(row, instance->outputs, sizeof row);
    gimbal_recorded_motion_row(instance->recording, motion_time, row);
    target_row(instance, motion_time, row);
    return commit_row(instance, function, row, step, end_time);
}

/* The master's point becomes the FMU's time (the face checked it); the outputs stay the rows of the
 * grid, counted, whatever clock the master keeps. */
static FmiStatus do_step(FmiInstance* common, const char* function, double point, double step_size, int* ended_early) {
    (void)ended_early; /* no mode changes: never early */
    Instance* instance = ship(common);
    const double end_time = point + step_size;
    /* A master whose clock rounds differently from its step (an SSP engine that ends on its stop time
     * with a last step of 5e-11 s, one that sums t += h and ends a drift short of its stop time) takes
     * a step that ends on the current row's grid point: the clock's rounding, not a step. The rows
     * stay where they are; only the time follows the master. A master in integer nanoseconds (libcosim)
     * passes steps a few ulp off h, one that sums t += h ends its last step a drift short of h, on the
     * next row's grid point: the same grid step (communication_point.h). More than that is another
     * step, which the grid cannot give. */
    if (instance->step != 0.0) {
        const double h = instance->step;
        const double current = instance->start_time + (double)instance->row * h;
        const double next = instance->start_time + (double)(instance->row + 1) * h;
        const int rows = communication_grid_rows(point, step_size, h, current, next);
        if (rows == 0) {
            instance->common.time = end_time;
            return FMI_OK;
        }
        if (rows < 0)
            REFUSE(instance,
                   "%s: communicationStepSize = %.17g differs from the first step's %.17g, and the step's end %.17g is "
                   "not a point of the grid (%.17g, %.17g): the outputs are the rows of one grid "
                   "(canHandleVariableCommunicationStepSize=\"false\")",
                   function, step_size, h, end_time, current, next);
    }
    const double step = instance->step != 0.0 ? instance->step : step_size;
    if (instance->row >= LONG_MAX - 1) REFUSE(instance, "%s: the grid's %ld rows are used up", function, instance->row);
    if (target_covers(instance, function, step, end_time) != FMI_OK) return FMI_ERROR;
    if (instance->recording != NULL) return step_recording(instance, function, step, end_time);
    if (instance->step == 0.0) {
        if (ship_motion_set_step(&instance->motion, step) != 0) {
            instance->common.state = instance->common.face->error_state;
            REFUSE(instance, "%s: out of memory for the rotation tables of step %g", function, step);
        }
        instance->step = step;
    }
    double row[SHIP_REAL_OUTPUTS];
    memcpy(row, instance->outputs, sizeof row);
    ship_motion_row(&instance->motion, instance->row + 1, row);
    if (!finite_row(instance, row, SHIP_MOTION_OUTPUTS, function, end_time, kSeaState)) {
        instance->common.state = instance->common.face->error_state;
        return FMI_ERROR;
    }
    target_row(instance, (double)(instance->row + 1) * step, row);
    return commit_row(instance, function, row, step, end_time);
}

/* ---------------------------------------------------------------- FMU states */

/* The instance's part of an FMU state (the layer's record holds the times and the state): what the
 * outputs and the next rows follow from. The sea state's components and the recording's splines are
 * not in it: restoring prepares them again from the parameters (and the file), as initialization
 * did, so the rows that follow have the same bits. */
enum { kSnapshotFileCapacity = 1024 };
typedef struct {
    int32_t initialized; /* after initialization: what the layer checks against the record's state */
    int32_t prepared;
    int32_t stop_time_defined;
    int32_t reserved;
    ShipMotionParameters parameters;
    double start_time, stop_time, step;
    int64_t row;
    double outputs[SHIP_REAL_OUTPUTS];
    char recording_file[kSnapshotFileCapacity];
    char target_file[kSnapshotFileCapacity];
} ShipSnapshot;

static const char* calling(const Instance* instance) {
    return instance->common.calling != NULL ? instance->common.calling : "fmi3SetFMUState";
}

static size_t snapshot_size(void) { return sizeof(ShipSnapshot); }

static FmiStatus save(void* model, unsigned char* bytes) {
    Instance* instance = (Instance*)model;
    ShipSnapshot snapshot;
    memset(&snapshot, 0, sizeof snapshot);
    const size_t length = strlen(instance->recording_file), target_length = strlen(instance->target_file);
    if (length >= sizeof snapshot.recording_file)
        REFUSE(instance, "%s: recording_file has %zu characters, an FMU state holds %zu at most", calling(instance),
               length, sizeof snapshot.recording_file - 1);
    if (target_length >= sizeof snapshot.target_file)
        REFUSE(instance, "%s: target_file has %zu characters, an FMU state holds %zu at most", calling(instance),
               target_length, sizeof snapshot.target_file - 1);
    snapshot.initialized = (instance->common.state & instance->common.face->before_initialized_states) == 0;
    snapshot.prepared = instance->prepared;
    snapshot.stop_time_defined = instance->common.stop_time_defined;
    snapshot.parameters = instance->parameters;
    snapshot.start_time = instance->start_time;
    snapshot.stop_time = instance->common.stop_time;
    snapshot.step = instance->step;
    snapshot.row = instance->row;
    memcpy(snapshot.outputs, instance->outputs, sizeof snapshot.outputs);
    memcpy(snapshot.recording_file, instance->recording_file, length + 1);
    memcpy(snapshot.target_file, instance->target_file, target_length + 1);
    memcpy(bytes, &snapshot, sizeof snapshot);
    return FMI_OK;
}

/* A snapshot's flags and file names, or NULL. */
static const char* state_problem(const ShipSnapshot* snapshot) {
    if ((snapshot->initialized & ~1) != 0 || (snapshot->prepared & ~1) != 0 || (snapshot->stop_time_defined & ~1) != 0)
        return "a flag is not a boolean";
    if (snapshot->initialized && !snapshot->prepared) return "it is initialized without a prepared motion";
    if (memchr(snapshot->recording_file, '\0', sizeof snapshot->recording_file) == NULL)
        return "its recording_file is not a terminated string";
    if (memchr(snapshot->target_file, '\0', sizeof snapshot->target_file) == NULL)
        return "its target_file is not a terminated string";
    return NULL;
}

/* A snapshot's parameters outside their bounds, or NULL. */
static const char* parameters_problem(ShipSnapshot* snapshot) {
    for (unsigned vr = SHIP_REAL_OUTPUTS; vr < SHIP_REAL_COUNT; ++vr) {
        const double x = *ship_real_parameter(&snapshot->parameters, vr);
        const ShipRealVariable* variable = &kShipRealVariables[vr];
        if (!isfinite(x) || (variable->min_exclusive ? !(x > variable->min) : !(x >= variable->min)))
            return "a Real parameter lies outside its bounds";
    }
    for (unsigned vr = 0; vr < SHIP_INTEGER_COUNT; ++vr) {
        const int x = *ship_integer_parameter(&snapshot->parameters, vr);
        if (x < kShipIntegerVariables[vr].min || x > kShipIntegerVariables[vr].max)
            return "an Integer parameter lies outside its bounds";
    }
    return NULL;
}

/* A snapshot's times, grid row and outputs, or NULL. */
static const char* progress_problem(const ShipSnapshot* snapshot) {
    if (!isfinite(snapshot->start_time) || !isfinite(snapshot->stop_time) || !isfinite(snapshot->step) ||
        snapshot->step < 0.0)
        return "its times or its step are not finite";
    if (snapshot->row < 0 || snapshot->row >= LONG_MAX - 1 || (snapshot->row > 0 && snapshot->step == 0.0))
        return "its grid row is not one a step reached";
    for (int k = 0; k < SHIP_REAL_OUTPUTS; ++k)
        if (!isfinite(snapshot->outputs[k])) return "an output is not finite";
    return NULL;
}

/* What in a snapshot this FMU could not have saved, or NULL: the first problem, in this order. */
static const char* snapshot_problem(ShipSnapshot* snapshot) {
    const char* problem = state_problem(snapshot);
    if (problem == NULL) problem = parameters_problem(snapshot);
    if (problem == NULL) problem = progress_problem(snapshot);
    return problem;
}

static FmiStatus check_snapshot(void* model, const unsigned char* bytes, int* initialized) {
    ShipSnapshot snapshot;
    memcpy(&snapshot, bytes, sizeof snapshot);
    return fmi_snapshot_verdict((FmiInstance*)model, snapshot_problem(&snapshot), snapshot.initialized, initialized);
}

/* The motion of the snapshot is prepared beside the instance's and committed only when it could be:
 * a refusal (the recording file gone, memory short) leaves the instance as it was. */
static FmiStatus restore(void* model, const unsigned char* bytes) {
    Instance* instance = (Instance*)model;
    ShipSnapshot snapshot;
    memcpy(&snapshot, bytes, sizeof snapshot);
    Instance restored = *instance; /* the instance's identity, for prepare's messages */
    memset(&restored.motion, 0, sizeof restored.motion);
    restored.recording = NULL;
    restored.target = NULL;
    restored.prepared = 0;
    restored.parameters = snapshot.parameters;
    restored.start_time = snapshot.start_time;
    restored.common.stop_time = snapshot.stop_time;
    restored.common.stop_time_defined = snapshot.stop_time_defined;
    restored.recording_file = copy_text(snapshot.recording_file);
    restored.target_file = copy_text(snapshot.target_file);
    if (restored.recording_file == NULL || restored.target_file == NULL) {
        free(restored.recording_file);
        free(restored.target_file);
        REFUSE(instance, "%s: out of memory for recording_file and target_file", calling(instance));
    }
    if (snapshot.prepared && prepare(&restored, calling(instance)) != FMI_OK) {
        free(restored.recording_file);
        free(restored.target_file);
        return FMI_ERROR;
    }
    if (restored.prepared && restored.recording == NULL && snapshot.step != 0.0 &&
        ship_motion_set_step(&restored.motion, snapshot.step) != 0) {
        unprepare(&restored);
        free(restored.recording_file);
        free(restored.target_file);
        REFUSE(instance, "%s: out of memory for the rotation tables of step %g", calling(instance), snapshot.step);
    }
    unprepare(instance);
    free(instance->recording_file);
    instance->recording_file = restored.recording_file;
    free(instance->target_file);
    instance->target_file = restored.target_file;
    instance->parameters = restored.parameters;
    instance->motion = restored.motion;
    instance->recording = restored.recording;
    instance->target = restored.target;
    instance->prepared = restored.prepared;
    instance->start_time = snapshot.start_time;
    instance->step = snapshot.step;
    instance->row = (long)snapshot.row;
    memcpy(instance->outputs, snapshot.outputs, sizeof instance->outputs);
    return FMI_OK;
}

/* A failed step leaves the error state, in which the values and the step's status can still be read
 * and the instance terminated. */
const FmuModel kFmuModel = {
    .layer = {SHIP_MOTION_GUID, sizeof(Instance), kLogCategories, (int)(sizeof kLogCategories / sizeof kLogCategories[0]),
              model_fields, no_own_allocation, NULL, snapshot_size, save, check_snapshot, restore},
    .get_states = STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_TERMINATED | STATE_ERROR,
    .set_states = STATE_INSTANTIATED | STATE_INITIALIZATION,
    .terminate_states = STATE_STEP_COMPLETE | STATE_ERROR,
    .status_states = STATE_STEP_COMPLETE | STATE_TERMINATED | STATE_ERROR,
    .real = {SHIP_REAL_COUNT, get_real, real_settable, set_real},
    .integer = {SHIP_INTEGER_COUNT, get_integer, integer_settable, set_integer},
    .boolean = {0, NULL, NULL, NULL},
    .string = {SHIP_STRING_COUNT, get_string, string_settable, set_string},
    .instantiated = instantiated,
    .release = release,
    .reset = reset,
    .experiment_start = experiment_start,
    .exit_initialization = exit_initialization,
    .do_step = do_step,
    .values_set = values_set,
};
