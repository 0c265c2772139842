#include "gimbal_kernel/recorded_motion.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gimbal_kernel/cubic_spline.h"
#include "gimbal_kernel/recorded_motion_csv.h"

/* At most: 3 angles, 3 given rates, 3 given accelerations, 3 positions. */
enum { MAXIMUM_SPLINES = 12 };

struct GimbalRecordedMotion {
    long samples;
    double* time;
    int splines;
    double* coefficients[MAXIMUM_SPLINES];
    int output_spline[GIMBAL_RECORDED_MOTION_OUTPUTS];     /* -1: the output is 0 */
    int output_derivative[GIMBAL_RECORDED_MOTION_OUTPUTS]; /* of that spline: 0, 1 or 2 */
    int position_spline[3];                                /* -1: no such column */
};

static const char* const kAngles[3] = {"delta", "psi", "gamma"};
static const char* const kAnglesInDegrees[3] = {"pitch_deg", "yaw_deg", "roll_deg"};
static const char* const kPositions[3] = {"x", "y", "z"};
/* Python's sorted() of the allowed names, as base_motion.Recorded listed them. */
static const char kAllowed[] = "['delta', 'delta_ddot', 'delta_dot', 'gamma', 'gamma_ddot', 'gamma_dot', 'pitch_deg', "
                               "'psi', 'psi_ddot', 'psi_dot', 'roll_deg', 'time', 'x', 'y', 'yaw_deg', 'z']";

static int refuse(char* message, size_t size, const char* format, ...) {
    va_list args;
    va_start(args, format);
    vsnprintf(message, size, format, args);
    va_end(args);
    return GIMBAL_RECORDED_MOTION_BAD_COLUMNS;
}

static int is_allowed(const char* name) {
    if (strcmp(name, "time") == 0) return 1;
    for (int i = 0; i < 3; ++i) {
        const size_t length = strlen(kAngles[i]);
        if (strcmp(name, kAnglesInDegrees[i]) == 0 || strcmp(name, kPositions[i]) == 0) return 1;
        if (strncmp(name, kAngles[i], length) == 0 &&
            (name[length] == '\0' || strcmp(name + length, "_dot") == 0 || strcmp(name + length, "_ddot") == 0))
            return 1;
    }
    return 0;
}

static int compare_names(const void* a, const void* b) { return strcmp(*(const char* const*)a, *(const char* const*)b); }

/* The angles' columns: one of radians or degrees, and no rate or acceleration without its angle. */
static int check_angle_columns(const GimbalCsvTable* table, char* message, size_t size) {
    char name[64];
    for (int i = 0; i < 3; ++i) {
        const int angle = gimbal_csv_table_column(table, kAngles[i]) >= 0;
        const int degrees = gimbal_csv_table_column(table, kAnglesInDegrees[i]) >= 0;
        if (angle && degrees)
            return refuse(message, size, "columns '%s' and '%s' are the same angle; give one", kAngles[i], kAnglesInDegrees[i]);
        for (int order = 1; order <= 2; ++order) {
            snprintf(name, sizeof name, "%s%s", kAngles[i], order == 1 ? "_dot" : "_ddot");
            if (gimbal_csv_table_column(table, name) >= 0 && !angle && !degrees)
                return refuse(message, size, "column '%s' without the angle '%s' (or '%s') would be ignored; add the angle",
                              name, kAngles[i], kAnglesInDegrees[i]);
        }
    }
    return 0;
}

/* The refusal of the `count` unknown column names (sorted). What the user wrote is quoted in part (a
 * header is any text: a message stays a line): the first kQuotedColumns names, each cut at
 * kQuotedNameLength characters, then how many more. */
static int refuse_unknown_columns(const char** unknown, int count, char* message, size_t size) {
    enum { kQuotedColumns = 5, kQuotedNameLength = 40 };
    int written = snprintf(message, size, "unknown columns [");
    for (int k = 0; k < count && k < kQuotedColumns && written >= 0 && (size_t)written < size; ++k) {
        const int cut = strlen(unknown[k]) > kQuotedNameLength;
        written += snprintf(message + written, size - (size_t)written, "%s'%.*s%s'", k > 0 ? ", " : "",
                            (int)kQuotedNameLength, unknown[k], cut ? "..." : "");
    }
    if (count > kQuotedColumns && written >= 0 && (size_t)written < size)
        written += snprintf(message + written, size - (size_t)written, " and %d more", count - kQuotedColumns);
    if (written >= 0 && (size_t)written < size) snprintf(message + written, size - (size_t)written, "] (allowed: %s)", kAllowed);
    return GIMBAL_RECORDED_MOTION_BAD_COLUMNS;
}

/* base_motion.Recorded's checks of the names, in its order, with its messages. */
static int check_columns(const GimbalCsvTable* table, char* message, size_t size) {
    const int angles = check_angle_columns(table, message, size);
    if (angles != 0) return angles;
    const char** unknown = malloc(sizeof(char*) * (size_t)table->columns);
    if (unknown == NULL) return GIMBAL_RECORDED_MOTION_OUT_OF_MEMORY;
    int count = 0;
    for (int k = 0; k < table->columns; ++k)
        if (!is_allowed(table->names[k])) unknown[count++] = table->names[k];
    int status = 0;
    if (count > 0) {
        qsort(unknown, (size_t)count, sizeof(char*), compare_names);
        status = refuse_unknown_columns(unknown, count, message, size);
    }
    free(unknown);
    return status;
}

/* A spline through column `column` of the table (scaled by `scale`): its index (>= 0); -1 when out of
 * memory; -2 when the column's spline overflows (the reason in `message`). */
static int add_spline(GimbalRecordedMotion* motion, const GimbalCsvTable* table, const long* lines, int column,
                      double scale, char* message, size_t size) {
    double* coefficients = malloc(sizeof(double) * (size_t)gimbal_cubic_spline_coefficient_count(table->rows));
    if (coefficients == NULL) return -1;
    const int status = gimbal_csv_table_spline(table, lines, motion->time, column, scale, coefficients, message, size);
    if (status != 0) {
        free(coefficients);
        return status < 0 ? -1 : -2;
    }
    motion->coefficients[motion->splines] = coefficients;
    return motion->splines++;
}

static void set_output(GimbalRecordedMotion* motion, int output, int spline, int derivative) {
    motion->output_spline[output] = spline;
    motion->output_derivative[output] = derivative;
}

/* The splines of a checked table: 0; -1 when out of memory; -2 when a column's spline overflows
 * (the reason in `message`). */
static int build(GimbalRecordedMotion* motion, const GimbalCsvTable* table, const long* lines, char* message,
                 size_t size) {
    char name[64];
    /* Degrees as Python's math.radians converts them: x * (pi / 180). */
    const double radians_per_degree = 3.141592653589793 / 180.0;
    for (int i = 0; i < 3; ++i) {
        const int radians = gimbal_csv_table_column(table, kAngles[i]);
        const int degrees = gimbal_csv_table_column(table, kAnglesInDegrees[i]);
        if (radians < 0 && degrees < 0) continue;
        const int angle = radians >= 0 ? add_spline(motion, table, lines, radians, 1.0, message, size)
                                       : add_spline(motion, table, lines, degrees, radians_per_degree, message, size);
        if (angle < 0) return angle;
        set_output(motion, i, angle, 0);
        for (int order = 1; order <= 2; ++order) {
            snprintf(name, sizeof name, "%s%s", kAngles[i], order == 1 ? "_dot" : "_ddot");
            const int given = gimbal_csv_table_column(table, name);
            const int spline = given >= 0 ? add_spline(motion, table, lines, given, 1.0, message, size) : angle;
            if (spline < 0) return spline;
            set_output(motion, 3 * order + i, spline, given >= 0 ? 0 : order);
        }
    }
    for (int i = 0; i < 3; ++i) {
        const int column = gimbal_csv_table_column(table, kPositions[i]);
        if (column < 0) continue;
        const int spline = add_spline(motion, table, lines, column, 1.0, message, size);
        if (spline < 0) return spline;
        motion->position_spline[i] = spline;
        set_output(motion, 9 + i, spline, 1);
        set_output(motion, 12 + i, spline, 2);
    }
    return 0;
}

void gimbal_recorded_motion_free(GimbalRecordedMotion* motion) {
    if (motion == NULL) return;
    for (int k = 0; k < motion->splines; ++k) free(motion->coefficients[k]);
    free(motion->time);
    free(motion);
}

int gimbal_recorded_motion_read(const char* text, size_t length, GimbalRecordedMotion** motion, char* message,
                                size_t size) {
    *motion = NULL;
    GimbalCsvTable table;
    long* lines;
    int status = gimbal_csv_table_read_with_lines(text, length, &table, &lines, message, size);
    if (status != 0) return status < 0 ? GIMBAL_RECORDED_MOTION_OUT_OF_MEMORY : GIMBAL_RECORDED_MOTION_BAD_TABLE;
    status = check_columns(&table, message, size);
    GimbalRecordedMotion* built = status == 0 ? calloc(1, sizeof *built) : NULL;
    if (status == 0 && built != NULL) {
        for (int k = 0; k < GIMBAL_RECORDED_MOTION_OUTPUTS; ++k) set_output(built, k, -1, 0);
        for (int i = 0; i < 3; ++i) built->position_spline[i] = -1;
        built->samples = table.rows;
        built->time = malloc(sizeof(double) * (size_t)table.rows);
        if (built->time != NULL)
            for (long i = 0; i < table.rows; ++i)
                built->time[i] = table.values[(size_t)i * (size_t)table.columns + (size_t)table.time_column];
        const int splined = built->time == NULL ? -1 : build(built, &table, lines, message, size);
        if (splined != 0) {
            gimbal_recorded_motion_free(built);
            built = NULL;
        }
        if (splined == -2) status = GIMBAL_RECORDED_MOTION_BAD_TABLE;
    }
    gimbal_csv_table_free(&table);
    free(lines);
    if (status != 0) return status;
    if (built == NULL) {
        snprintf(message, size, "out of memory for the recording's splines");
        return GIMBAL_RECORDED_MOTION_OUT_OF_MEMORY;
    }
    *motion = built;
    return GIMBAL_RECORDED_MOTION_READ;
}

double gimbal_recorded_motion_start(const GimbalRecordedMotion* motion) { return motion->time[0]; }
double gimbal_recorded_motion_end(const GimbalRecordedMotion* motion) { return motion->time[motion->samples - 1]; }

void gimbal_recorded_motion_row(const GimbalRecordedMotion* motion, double t, double outputs[GIMBAL_RECORDED_MOTION_OUTPUTS]) {
    for (int k = 0; k < GIMBAL_RECORDED_MOTION_OUTPUTS; ++k) {
        const int spline = motion->output_spline[k];
        outputs[k] = spline < 0 ? 0.0
                                : gimbal_cubic_spline_evaluate(motion->samples, motion->time, motion->coefficients[spline], t,
                                                               motion->output_derivative[k]);
    }
}

void gimbal_recorded_motion_sample(const GimbalRecordedMotion* motion, long count, const double* t, double* outputs) {
    for (long i = 0; i < count; ++i) gimbal_recorded_motion_row(motion, t[i], outputs + (size_t)i * GIMBAL_RECORDED_MOTION_OUTPUTS);
}

void gimbal_recorded_motion_position(const GimbalRecordedMotion* motion, long count, const double* t, double* positions) {
    for (long i = 0; i < count; ++i)
        for (int axis = 0; axis < 3; ++axis) {
            const int spline = motion->position_spline[axis];
            positions[3 * i + axis] =
                spline < 0 ? 0.0 : gimbal_cubic_spline_evaluate(motion->samples, motion->time, motion->coefficients[spline], t[i], 0);
        }
}
