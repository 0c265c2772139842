/* The layout table of the kernel's structs (layout.h), made from the same field lists as their
 * declarations. */
#include "gimbal_kernel/layout.h"

#include <stddef.h>
#include <string.h>

#include "gimbal_kernel/controllers.h"
#include "gimbal_kernel/gyro.h"
#include "gimbal_kernel/master_loop.h"
#include "gimbal_kernel/sensors.h"

typedef struct {
    const char* structure;
    const char* field;
    long offset;
    const char* kind;
    long count;
} Field;

#define GIMBAL_QUOTE(x) #x
#define GIMBAL_NAME(x) GIMBAL_QUOTE(x)
#define FIELD_ROW(c_type, name, kind) {GIMBAL_NAME(STRUCTURE), #name, (long)offsetof(STRUCTURE, name), #kind, 1},
#define ARRAY_ROW(c_type, name, kind, count) \
    {GIMBAL_NAME(STRUCTURE), #name, (long)offsetof(STRUCTURE, name), #kind, count},

static const Field kFields[] = {
#define STRUCTURE GimbalGyro
    GIMBAL_GYRO_FIELDS(FIELD_ROW, ARRAY_ROW)
#undef STRUCTURE
#define STRUCTURE GimbalSensors
    GIMBAL_SENSORS_FIELDS(FIELD_ROW, ARRAY_ROW)
#undef STRUCTURE
#define STRUCTURE GimbalAxisPid
    GIMBAL_AXIS_PID_FIELDS(FIELD_ROW, ARRAY_ROW)
#undef STRUCTURE
#define STRUCTURE GimbalSetPoints
    GIMBAL_SET_POINTS_FIELDS(FIELD_ROW, ARRAY_ROW)
#undef STRUCTURE
#define STRUCTURE GimbalController
    GIMBAL_CONTROLLER_FIELDS(FIELD_ROW, ARRAY_ROW)
#undef STRUCTURE
#define STRUCTURE GimbalMasterLoop
    GIMBAL_MASTER_LOOP_FIELDS(FIELD_ROW, ARRAY_ROW)
#undef STRUCTURE
};

static const struct {
    const char* structure;
    long size;
} kSizes[] = {{"GimbalGyro", sizeof(GimbalGyro)},
              {"GimbalSensors", sizeof(GimbalSensors)},
              {"GimbalAxisPid", sizeof(GimbalAxisPid)},
              {"GimbalSetPoints", sizeof(GimbalSetPoints)},
              {"GimbalController", sizeof(GimbalController)},
              {"GimbalMasterLoop", sizeof(GimbalMasterLoop)}};

long gimbal_layout_field_count(void) { return (long)(sizeof kFields / sizeof kFields[0]); }

int gimbal_layout_field(long index, const char** structure, const char** field, long* offset, const char** kind,
                        long* count) {
    if (index < 0 || index >= gimbal_layout_field_count()) return 0;
    const Field* row = &kFields[index];
    *structure = row->structure, *field = row->field, *offset = row->offset, *kind = row->kind, *count = row->count;
    return 1;
}

long gimbal_layout_size(const char* structure) {
    for (size_t i = 0; i < sizeof kSizes / sizeof kSizes[0]; ++i)
        if (strcmp(kSizes[i].structure, structure) == 0) return kSizes[i].size;
    return -1;
}
