/* The table of a recorded base motion's file: a header row of names, then rows of numbers, all
 * separated by commas, '#' starting a comment, empty lines skipped; a 'time' column strictly
 * increasing, at least 4 rows (a cubic spline's minimum). Anything else is refused with a sentence
 * naming the line and the column, the scene runner's (scene/base_motion.py) and the ship-motion FMU's
 * alike: both read the file with this code, so both get the same doubles (strtod rounds correctly).
 *
 * Lines end at "\n", "\r\n" or "\r"; cells and names are stripped of spaces, tabs, '\v' and '\f'; a
 * name also of double quotes. A number is [+-] digits [. digits] [e|E [+-] digits] (digits on at least
 * one side of the point): C's and Python's common decimal notation. inf, infinity and nan (any case)
 * are named as not finite, as is a number too large for a double. The text must be UTF-8 (a byte order
 * mark is skipped).
 *
 * Finite numbers can still make a spline that is not: a time step of 5e-324 s divides a change into
 * an infinite rate, times or values near the largest double overflow the spline's sums. So a time
 * step must lie in [GIMBAL_CSV_LEAST_TIME_STEP, GIMBAL_CSV_LARGEST_TIME_STEP], and a column whose
 * change, rate or acceleration between two rows (or whose spline) overflows is refused naming the
 * rows and the column (gimbal_csv_table_spline): what the table gives is finite wherever it is
 * evaluated, from its first time to its last (and an end interval's length past either end). */
#ifndef GIMBAL_KERNEL_RECORDED_MOTION_CSV_H
#define GIMBAL_KERNEL_RECORDED_MOTION_CSV_H

#include <stddef.h>

/* The time steps a table may have [s]: a logger's finest is far above the least, a recording's
 * coarsest far below the largest. */
#define GIMBAL_CSV_LEAST_TIME_STEP 1e-9
#define GIMBAL_CSV_LARGEST_TIME_STEP 1e9

typedef struct {
    int columns;
    char** names;   /* columns names, each its own allocation */
    long rows;
    double* values; /* rows x columns, row by row */
    int time_column;
} GimbalCsvTable;

/* 0; 1 when refused (the reason in `message`); -1 when out of memory. `table` holds nothing unless 0. */
int gimbal_csv_table_read(const char* text, size_t length, GimbalCsvTable* table, char* message, size_t size);

/* gimbal_csv_table_read, and the file's line of each row into *row_lines (table->rows of them, for
 * messages that name a row; free it): NULL unless 0. */
int gimbal_csv_table_read_with_lines(const char* text, size_t length, GimbalCsvTable* table, long** row_lines,
                                     char* message, size_t size);

/* Frees what read allocated (twice is harmless). */
void gimbal_csv_table_free(GimbalCsvTable* table);

/* The index of the column `name`, or -1. */
int gimbal_csv_table_column(const GimbalCsvTable* table, const char* name);

/* The coefficients (cubic_spline.h: gimbal_cubic_spline_coefficient_count(rows) doubles) of the
 * spline through column `column` times `scale` at the table's times `time` (its time column), the
 * rows' lines `row_lines` (gimbal_csv_table_read_with_lines): 0; 1
 * when the column's change, rate or acceleration between two rows, or the spline, overflows a double
 * (the reason in `message`, naming the line, the row and the column); -1 when out of memory. */
int gimbal_csv_table_spline(const GimbalCsvTable* table, const long* row_lines, const double* time, int column,
                            double scale, double* coefficients, char* message, size_t size);

#endif
