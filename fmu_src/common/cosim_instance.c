/* The instance part the small Co-Simulation FMUs share (cosim_instance.h). */
#include "cosim_instance.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char* const kLogCategories[LOG_CATEGORY_COUNT] = {"logStatusError", "logAll"};

static void log_error_va(const CosimInstance* instance, const char* format, va_list args) {
    if (instance == NULL || instance->logger == NULL) return;
    char text[1024];
    vsnprintf(text, sizeof text, format, args);
    /* The logger takes its message as a format string: every '%' doubled. */
    char escaped[2 * sizeof text];
    size_t j = 0;
    for (size_t i = 0; text[i] != '\0' && j + 2 < sizeof escaped; ++i) {
        if (text[i] == '%') escaped[j++] = '%';
        escaped[j++] = text[i];
    }
    escaped[j] = '\0';
    instance->logger(instance->environment, instance->instance_name, fmi2Error, kLogCategories[LOG_STATUS_ERROR],
                     escaped);
}

void cosim_log_error(const CosimInstance* instance, const char* format, ...) {
    va_list args;
    va_start(args, format);
    log_error_va(instance, format, args);
    va_end(args);
}

fmi2Status cosim_refuse(const CosimInstance* instance, const char* format, ...) {
    va_list args;
    va_start(args, format);
    log_error_va(instance, format, args);
    va_end(args);
    return fmi2Error;
}

char* cosim_copy_text(const char* text) {
    char* copy = (char*)malloc(strlen(text) + 1);
    if (copy != NULL) strcpy(copy, text);
    return copy;
}

void* cosim_instantiate(size_t instance_size, fmi2String instance_name, fmi2Type type, fmi2String guid,
                        const char* fmu_guid, const fmi2CallbackFunctions* functions, fmi2Boolean logging_on) {
    if (functions == NULL || functions->logger == NULL) return NULL; /* nowhere to say why */
    /* Says why an instance is refused before there is one. */
    CosimInstance probe;
    memset(&probe, 0, sizeof probe);
    probe.logger = functions->logger;
    probe.environment = functions->componentEnvironment;
    probe.instance_name = (char*)(instance_name != NULL ? instance_name : "?");
    if (instance_name == NULL || instance_name[0] == '\0') {
        cosim_log_error(&probe, "fmi2Instantiate: instanceName must be a non-empty string");
        return NULL;
    }
    if (type != fmi2CoSimulation) {
        cosim_log_error(&probe, "fmi2Instantiate: fmuType = %d: this FMU is Co-Simulation only (fmi2CoSimulation = 1)",
                        (int)type);
        return NULL;
    }
    if (guid == NULL || strcmp(guid, fmu_guid) != 0) {
        cosim_log_error(&probe, "fmi2Instantiate: GUID '%s' does not match this FMU's '%s'", guid != NULL ? guid : "(null)",
                        fmu_guid);
        return NULL;
    }
    CosimInstance* instance = (CosimInstance*)calloc(1, instance_size);
    if (instance != NULL) instance->instance_name = cosim_copy_text(instance_name);
    if (instance == NULL || instance->instance_name == NULL) {
        free(instance);
        cosim_log_error(&probe, "fmi2Instantiate: out of memory");
        return NULL;
    }
    instance->logger = functions->logger;
    instance->environment = functions->componentEnvironment;
    for (int k = 0; k < LOG_CATEGORY_COUNT; ++k) instance->category_enabled[k] = logging_on ? 1 : 0;
    instance->state = STATE_INSTANTIATED;
    return instance;
}

void cosim_free(CosimInstance* instance) {
    if (instance == NULL) return;
    free(instance->instance_name);
    free(instance);
}

const char* cosim_state_name(InstanceState state) {
    switch (state) {
        case STATE_INSTANTIATED: return "instantiated";
        case STATE_INITIALIZATION: return "initialization mode";
        case STATE_STEP_COMPLETE: return "step complete";
        case STATE_TERMINATED: return "terminated";
        default: return "error";
    }
}

int cosim_allowed(const CosimInstance* instance, const char* function, int states) {
    if (instance == NULL) return 0;
    if (instance->state & states) return 1;
    cosim_log_error(instance, "%s is not allowed in state '%s'", function, cosim_state_name(instance->state));
    return 0;
}

int cosim_not_null(const CosimInstance* instance, const char* function, const void* pointer, const char* argument) {
    if (pointer != NULL) return 1;
    cosim_log_error(instance, "%s: argument %s is a null pointer", function, argument);
    return 0;
}

fmi2Status cosim_set_debug_logging(CosimInstance* instance, fmi2Boolean logging_on, size_t category_count,
                                   const fmi2String categories[]) {
    const int any_state = STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_TERMINATED | STATE_ERROR;
    if (!cosim_allowed(instance, "fmi2SetDebugLogging", any_state)) return fmi2Error;
    if (category_count > 0 && !cosim_not_null(instance, "fmi2SetDebugLogging", categories, "categories"))
        return fmi2Error;
    int chosen[LOG_CATEGORY_COUNT] = {0};
    for (size_t i = 0; i < category_count; ++i) {
        int found = -1;
        for (int k = 0; k < LOG_CATEGORY_COUNT && categories[i] != NULL; ++k)
            if (strcmp(categories[i], kLogCategories[k]) == 0) found = k;
        if (found < 0)
            return cosim_refuse(instance, "fmi2SetDebugLogging: unknown log category '%s'",
                                categories[i] != NULL ? categories[i] : "(null)");
        chosen[found] = 1;
    }
    for (int k = 0; k < LOG_CATEGORY_COUNT; ++k)
        if (category_count == 0 || chosen[k]) instance->category_enabled[k] = logging_on ? 1 : 0;
    return fmi2OK;
}
