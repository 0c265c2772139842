#include "gimbal_kernel/recorded_target.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gimbal_kernel/cubic_spline.h"
#include "gimbal_kernel/recorded_motion_csv.h"

struct GimbalRecordedTarget {
    long samples;
    double* time;
    double* coefficients[GIMBAL_RECORDED_TARGET_OUTPUTS]; /* NULL: the output is a derivative of the position's */
};

static const char* const kColumns[GIMBAL_RECORDED_TARGET_OUTPUTS] = {
    "x", "y", "z", "x_dot", "y_dot", "z_dot", "x_ddot", "y_ddot", "z_ddot"};

/* The header's names: time and x, y, z needed, the derivatives optional, nothing else. */
static int check_columns(const GimbalCsvTable* table, char* message, size_t size) {
    for (int i = 0; i < 3; ++i)
        if (gimbal_csv_table_column(table, kColumns[i]) < 0) {
            snprintf(message, size, "no column '%s': a target's table has time, x, y, z [m] (the target from the "
                     "gimbal in G) and optionally x_dot ... z_dot [m/s], x_ddot ... z_ddot [m/s2]", kColumns[i]);
            return GIMBAL_RECORDED_TARGET_BAD_COLUMNS;
        }
    for (int k = 0; k < table->columns; ++k) {
        int known = strcmp(table->names[k], "time") == 0;
        for (int i = 0; i < GIMBAL_RECORDED_TARGET_OUTPUTS && !known; ++i) known = strcmp(table->names[k], kColumns[i]) == 0;
        if (!known) {
            snprintf(message, size, "unknown column '%.40s%s' (allowed: time, x, y, z, x_dot, y_dot, z_dot, x_ddot, "
                     "y_ddot, z_ddot)", table->names[k], strlen(table->names[k]) > 40 ? "..." : "");
            return GIMBAL_RECORDED_TARGET_BAD_COLUMNS;
        }
    }
    return 0;
}

/* The spline of column `column` into *coefficients: 0; -1 when out of memory; 1 when it overflows
 * (the reason in `message`). */
static int fit_column(const GimbalRecordedTarget* target, const GimbalCsvTable* table, const long* lines, int column,
                      double** coefficients, char* message, size_t size) {
    *coefficients = malloc(sizeof(double) * (size_t)gimbal_cubic_spline_coefficient_count(table->rows));
    if (*coefficients == NULL) return -1;
    const int status = gimbal_csv_table_spline(table, lines, target->time, column, 1.0, *coefficients, message, size);
    if (status != 0) {
        free(*coefficients);
        *coefficients = NULL;
    }
    return status;
}

void gimbal_recorded_target_free(GimbalRecordedTarget* target) {
    if (target == NULL) return;
    for (int k = 0; k < GIMBAL_RECORDED_TARGET_OUTPUTS; ++k) free(target->coefficients[k]);
    free(target->time);
    free(target);
}

/* The splines of a checked table into *built: 0; -1 when out of memory; 1 when a column's spline
 * overflows (the reason in `message`). */
static int build(const GimbalCsvTable* table, const long* lines, GimbalRecordedTarget** built, char* message,
                 size_t size) {
    GimbalRecordedTarget* target = calloc(1, sizeof *target);
    if (target == NULL) return -1;
    target->samples = table->rows;
    target->time = malloc(sizeof(double) * (size_t)table->rows);
    if (target->time == NULL) {
        gimbal_recorded_target_free(target);
        return -1;
    }
    for (long i = 0; i < table->rows; ++i)
        target->time[i] = table->values[(size_t)i * (size_t)table->columns + (size_t)table->time_column];
    for (int k = 0; k < GIMBAL_RECORDED_TARGET_OUTPUTS; ++k) {
        const int column = gimbal_csv_table_column(table, kColumns[k]);
        if (column < 0) continue;
        const int status = fit_column(target, table, lines, column, &target->coefficients[k], message, size);
        if (status != 0) {
            gimbal_recorded_target_free(target);
            return status;
        }
    }
    *built = target;
    return 0;
}

int gimbal_recorded_target_read(const char* text, size_t length, GimbalRecordedTarget** target, char* message,
                                size_t size) {
    *target = NULL;
    GimbalCsvTable table;
    long* lines;
    int status = gimbal_csv_table_read_with_lines(text, length, &table, &lines, message, size);
    if (status != 0) return status < 0 ? GIMBAL_RECORDED_TARGET_OUT_OF_MEMORY : GIMBAL_RECORDED_TARGET_BAD_TABLE;
    status = check_columns(&table, message, size);
    GimbalRecordedTarget* built = NULL;
    const int splined = status == 0 ? build(&table, lines, &built, message, size) : 0;
    gimbal_csv_table_free(&table);
    free(lines);
    if (status != 0) return status;
    if (splined > 0) return GIMBAL_RECORDED_TARGET_BAD_TABLE;
    if (built == NULL) {
        snprintf(message, size, "out of memory for the target's splines");
        return GIMBAL_RECORDED_TARGET_OUT_OF_MEMORY;
    }
    *target = built;
    return GIMBAL_RECORDED_TARGET_READ;
}

double gimbal_recorded_target_start(const GimbalRecordedTarget* target) { return target->time[0]; }
double gimbal_recorded_target_end(const GimbalRecordedTarget* target) { return target->time[target->samples - 1]; }

void gimbal_recorded_target_row(const GimbalRecordedTarget* target, double t, double outputs[GIMBAL_RECORDED_TARGET_OUTPUTS]) {
    for (int k = 0; k < GIMBAL_RECORDED_TARGET_OUTPUTS; ++k) {
        const int axis = k % 3, order = k / 3;
        /* a given column's own spline, else the position's derivative */
        const double* coefficients = target->coefficients[k] != NULL ? target->coefficients[k] : target->coefficients[axis];
        outputs[k] = gimbal_cubic_spline_evaluate(target->samples, target->time, coefficients, t,
                                                  target->coefficients[k] != NULL ? 0 : order);
    }
}
