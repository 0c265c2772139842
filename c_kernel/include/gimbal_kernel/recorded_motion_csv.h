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
 * mark is skipped). */
#ifndef GIMBAL_KERNEL_RECORDED_MOTION_CSV_H
#define GIMBAL_KERNEL_RECORDED_MOTION_CSV_H

#include <stddef.h>

typedef struct {
    int columns;
    char** names;   /* columns names, each its own allocation */
    long rows;
    double* values; /* rows x columns, row by row */
    int time_column;
} GimbalCsvTable;

/* 0; 1 when refused (the reason in `message`); -1 when out of memory. `table` holds nothing unless 0. */
int gimbal_csv_table_read(const char* text, size_t length, GimbalCsvTable* table, char* message, size_t size);

/* Frees what read allocated (twice is harmless). */
void gimbal_csv_table_free(GimbalCsvTable* table);

/* The index of the column `name`, or -1. */
int gimbal_csv_table_column(const GimbalCsvTable* table, const char* name);

#endif
