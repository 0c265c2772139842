/* The gimbal's table for the FMI instance layer (gimbal_model.h). */
#include "gimbal_model.h"

#include "gimbal_guid.h"

_Static_assert((int)GIMBAL_INPUT == (int)FMI_INPUT && (int)GIMBAL_PARAMETER == (int)FMI_PARAMETER &&
                   (int)GIMBAL_TUNABLE == (int)FMI_TUNABLE && (int)GIMBAL_INITIAL_EXACT == (int)FMI_INITIAL_EXACT &&
                   (int)GIMBAL_INITIAL_APPROX == (int)FMI_INITIAL_APPROX,
               "the core's variable attributes are the layer's");

/* The <LogCategories> of both model descriptions, in their order. */
static const char* const kLogCategories[] = {"logEvents", "logSolver", "logStatusWarning", "logStatusDiscard",
                                             "logStatusError", "logAll"};

static void core_log(void* context, GimbalStatus status, const char* category, const char* message) {
    fmi_log_from_model((FmiInstance*)context, gimbal_status(status), category, message);
}

static int core_log_enabled(void* context, const char* category) {
    return fmi_log_enabled((const FmiInstance*)context, category);
}

/* A Model Exchange instance's core evaluates the equations at the host's points instead of stepping. */
static void* create(FmiInstance* instance) {
    GimbalCore* core = gimbal_core_create(core_log, core_log_enabled, instance);
    if (core != NULL && instance->model_exchange && gimbal_core_use_continuous_time(core) != GIMBAL_OK) {
        gimbal_core_destroy(core);
        return NULL;
    }
    return core;
}

static void destroy(void* model) { gimbal_core_destroy((GimbalCore*)model); }

static FmiStatus reset(void* model) { return gimbal_status(gimbal_core_reset((GimbalCore*)model)); }

static FmiStatus save(void* model, unsigned char* snapshot) {
    return gimbal_status(gimbal_core_save((GimbalCore*)model, snapshot));
}

static FmiStatus check_snapshot(void* model, const unsigned char* snapshot, int* initialized) {
    return gimbal_status(gimbal_core_check_snapshot((GimbalCore*)model, snapshot, initialized));
}

static FmiStatus restore(void* model, const unsigned char* snapshot) {
    return gimbal_status(gimbal_core_restore((GimbalCore*)model, snapshot));
}

const FmiModel kGimbalModel = {
    GIMBAL_GUID,
    sizeof(FmiInstance),
    kLogCategories,
    (int)(sizeof kLogCategories / sizeof kLogCategories[0]),
    create,
    destroy,
    reset,
    gimbal_core_snapshot_size,
    save,
    check_snapshot,
    restore,
};
