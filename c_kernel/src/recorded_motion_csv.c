#include "gimbal_kernel/recorded_motion_csv.h"

#include "gimbal_kernel/cubic_spline.h"

#include <ctype.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { MINIMUM_ROWS = 4 };
/* The most bytes of the file a message quotes (a cell, a column name): a message stays one readable
 * line whatever the file holds. The file's content is quoted only once its header has a 'time'
 * column, i.e. once it is recognisably a recording: any other file is refused without a word of it. */
enum { EXCERPT_BYTES = 80 };

/* A bounded quote of text[0 .. length): print it as "%.*s%s" with (length, suffix). */
typedef struct {
    int length;
    char suffix[48];
} Excerpt;

static Excerpt excerpt_of(const char* text, size_t length) {
    Excerpt excerpt = {(int)length, ""};
    if (length > EXCERPT_BYTES) {
        size_t cut = EXCERPT_BYTES;
        while (cut > 0 && ((unsigned char)text[cut] & 0xC0) == 0x80) --cut; /* not inside a UTF-8 character */
        excerpt.length = (int)cut;
        snprintf(excerpt.suffix, sizeof excerpt.suffix, "\xE2\x80\xA6(%zu bytes)", length);
    }
    return excerpt;
}

typedef struct {
    const char* start;
    size_t length;
    long number; /* 1-based line number in the file */
} Line;

static int refuse(char* message, size_t size, const char* format, ...) {
    va_list args;
    va_start(args, format);
    vsnprintf(message, size, format, args);
    va_end(args);
    return 1;
}

static int is_blank(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f'; }

static void strip(const char** start, size_t* length, int quotes_too) {
    while (*length > 0 && (is_blank(**start) || (quotes_too && **start == '"'))) ++*start, --*length;
    while (*length > 0 && (is_blank((*start)[*length - 1]) || (quotes_too && (*start)[*length - 1] == '"'))) --*length;
}

/* How many continuation bytes a UTF-8 sequence led by `c` has (0: an ASCII byte), and the range of its
 * second byte (no overlong forms, no surrogates, nothing above U+10FFFF); -1 when `c` leads none. */
static int continuation_bytes(unsigned char c, unsigned char* low, unsigned char* high) {
    *low = 0x80, *high = 0xBF;
    if (c < 0x80) return 0;
    if (c >= 0xC2 && c <= 0xDF) return 1;
    if (c >= 0xE0 && c <= 0xEF) {
        if (c == 0xE0) *low = 0xA0;
        if (c == 0xED) *high = 0x9F;
        return 2;
    }
    if (c >= 0xF0 && c <= 0xF4) {
        if (c == 0xF0) *low = 0x90;
        if (c == 0xF4) *high = 0x8F;
        return 3;
    }
    return -1;
}

/* The offset of the first byte that is not part of well-formed UTF-8 (as Python's decoder judges:
 * no overlong forms, no surrogates, nothing above U+10FFFF), or -1. */
static long first_non_utf8(const unsigned char* text, size_t length) {
    size_t i = 0;
    while (i < length) {
        unsigned char low, high; /* the range of the second byte */
        const int extra = continuation_bytes(text[i], &low, &high);
        if (extra < 0) return (long)i;
        for (size_t k = 1; k <= (size_t)extra; ++k) {
            if (i + k >= length) return (long)i;
            const unsigned char next = text[i + k];
            if (k == 1 ? (next < low || next > high) : (next < 0x80 || next > 0xBF)) return (long)i;
        }
        i += (size_t)extra + 1;
    }
    return -1;
}

/* The non-empty lines, comments cut off and stripped. -1 when out of memory, else their count. */
static long split_lines(const char* text, size_t length, Line** lines) {
    size_t capacity = 1;
    for (size_t i = 0; i < length; ++i) capacity += text[i] == '\n' || text[i] == '\r';
    *lines = malloc(sizeof(Line) * capacity);
    if (*lines == NULL) return -1;
    long count = 0, number = 0;
    size_t i = 0;
    while (i < length) {
        const size_t begin = i;
        while (i < length && text[i] != '\n' && text[i] != '\r') ++i;
        ++number;
        const char* start = text + begin;
        size_t line_length = i - begin;
        const char* comment = memchr(start, '#', line_length);
        if (comment != NULL) line_length = (size_t)(comment - start);
        strip(&start, &line_length, 0);
        if (line_length > 0) (*lines)[count++] = (Line){start, line_length, number};
        if (i < length) i += text[i] == '\r' && i + 1 < length && text[i + 1] == '\n' ? 2 : 1;
    }
    return count;
}

static size_t count_cells(const char* start, size_t length) {
    size_t cells = 1;
    for (size_t i = 0; i < length; ++i) cells += start[i] == ',';
    return cells;
}

/* The next cell of a line from *position (comma-separated), stripped. */
static void next_cell(const char* line, size_t length, size_t* position, const char** cell, size_t* cell_length) {
    const size_t begin = *position;
    while (*position < length && line[*position] != ',') ++*position;
    *cell = line + begin;
    *cell_length = *position - begin;
    ++*position; /* past the comma */
}

static int is_word(const char* cell, size_t length, const char* word) {
    if (length > 0 && (cell[0] == '+' || cell[0] == '-')) ++cell, --length;
    if (length != strlen(word)) return 0;
    for (size_t i = 0; i < length; ++i)
        if (tolower((unsigned char)cell[i]) != word[i]) return 0;
    return 1;
}

/* The digits of the cell from *i on, *i moved past them: how many. */
static size_t skip_digits(const char* cell, size_t length, size_t* i) {
    size_t digits = 0;
    while (*i < length && isdigit((unsigned char)cell[*i])) ++*i, ++digits;
    return digits;
}

/* A sign, when there is one at *i: skipped. */
static void skip_sign(const char* cell, size_t length, size_t* i) {
    if (*i < length && (cell[*i] == '+' || cell[*i] == '-')) ++*i;
}

/* Does the cell follow the number grammar? */
static int is_decimal(const char* cell, size_t length) {
    size_t i = 0;
    skip_sign(cell, length, &i);
    size_t digits = skip_digits(cell, length, &i);
    if (i < length && cell[i] == '.') {
        ++i;
        digits += skip_digits(cell, length, &i);
    }
    if (digits == 0) return 0;
    if (i < length && (cell[i] == 'e' || cell[i] == 'E')) {
        ++i;
        skip_sign(cell, length, &i);
        if (skip_digits(cell, length, &i) == 0) return 0;
    }
    return i == length;
}

/* The cell's number: 0; 1 when it is not one; -1 when out of memory. Not finite (inf, nan, overflow)
 * is a number here; the caller names it. */
static int parse_number(const char* cell, size_t length, double* value) {
    if (is_word(cell, length, "inf") || is_word(cell, length, "infinity")) {
        *value = cell[0] == '-' ? -HUGE_VAL : HUGE_VAL;
        return 0;
    }
    if (is_word(cell, length, "nan")) {
        *value = NAN;
        return 0;
    }
    if (!is_decimal(cell, length)) return 1;
    char* copy = malloc(length + 1);
    if (copy == NULL) return -1;
    memcpy(copy, cell, length);
    copy[length] = '\0';
    /* strtod reads the locale's decimal point: a host may have set one other than '.'. */
    const char point = localeconv()->decimal_point[0];
    if (point != '\0' && point != '.') {
        char* dot = strchr(copy, '.');
        if (dot != NULL) *dot = point;
    }
    char* end = NULL;
    *value = strtod(copy, &end);
    const int whole = end == copy + length;
    free(copy);
    return whole ? 0 : 1;
}

void gimbal_csv_table_free(GimbalCsvTable* table) {
    if (table->names != NULL)
        for (int k = 0; k < table->columns; ++k) free(table->names[k]);
    free(table->names);
    free(table->values);
    memset(table, 0, sizeof *table);
}

int gimbal_csv_table_column(const GimbalCsvTable* table, const char* name) {
    for (int k = 0; k < table->columns; ++k)
        if (strcmp(table->names[k], name) == 0) return k;
    return -1;
}

static int read_header(const Line* header, GimbalCsvTable* table, char* message, size_t size) {
    if (memchr(header->start, ';', header->length) != NULL && memchr(header->start, ',', header->length) == NULL)
        return refuse(message, size,
                      "line %ld (the header) is separated by semicolons; the file must be comma-separated with '.' as "
                      "the decimal point (save it as CSV with ',' separators)",
                      header->number);
    const size_t columns = count_cells(header->start, header->length);
    if (columns > 100000) return refuse(message, size, "line %ld (the header) has %zu columns", header->number, columns);
    table->names = calloc(columns, sizeof(char*));
    if (table->names == NULL) return -1;
    table->columns = (int)columns;
    size_t position = 0;
    for (size_t k = 0; k < columns; ++k) {
        const char* name;
        size_t length;
        next_cell(header->start, header->length, &position, &name, &length);
        strip(&name, &length, 1);
        table->names[k] = malloc(length + 1);
        if (table->names[k] == NULL) return -1;
        memcpy(table->names[k], name, length);
        table->names[k][length] = '\0';
    }
    /* Before anything that quotes the header: without a 'time' column the file is not a recording
     * (a wrong path, say), and what it holds is none of the message's business. */
    table->time_column = gimbal_csv_table_column(table, "time");
    if (table->time_column < 0)
        return refuse(message, size,
                      "not a recorded motion: its header (line %ld, the first that is not a comment) has no 'time' "
                      "column (expected a comma-separated header row such as 'time,gamma', then rows of numbers)",
                      header->number);
    for (size_t k = 0; k < columns; ++k) {
        if (table->names[k][0] == '\0')
            return refuse(message, size, "line %ld (the header): column %zu has no name", header->number, k + 1);
        for (size_t j = 0; j < k; ++j)
            if (strcmp(table->names[j], table->names[k]) == 0) {
                const Excerpt name = excerpt_of(table->names[k], strlen(table->names[k]));
                return refuse(message, size, "line %ld (the header): column '%.*s%s' appears twice", header->number,
                              name.length, table->names[k], name.suffix);
            }
    }
    return 0;
}

static int read_row(const Line* line, long row, GimbalCsvTable* table, char* message, size_t size) {
    const size_t cells = count_cells(line->start, line->length);
    if (cells != (size_t)table->columns)
        return refuse(message, size, "line %ld (data row %ld) has %zu cells, the header %d%s", line->number, row, cells,
                      table->columns,
                      memchr(line->start, ';', line->length) != NULL ? " (semicolons: the file must be comma-separated)" : "");
    double* values = table->values + (size_t)(row - 1) * (size_t)table->columns;
    size_t position = 0;
    for (int k = 0; k < table->columns; ++k) {
        const char* cell;
        size_t length;
        next_cell(line->start, line->length, &position, &cell, &length);
        strip(&cell, &length, 0);
        const int parsed = parse_number(cell, length, &values[k]);
        if (parsed < 0) return -1;
        if (parsed > 0 && length == 0) {
            const Excerpt name = excerpt_of(table->names[k], strlen(table->names[k]));
            return refuse(message, size, "line %ld (data row %ld), column '%.*s%s' is empty", line->number, row,
                          name.length, table->names[k], name.suffix);
        }
        if (parsed == 0 && isfinite(values[k])) continue;
        const Excerpt name = excerpt_of(table->names[k], strlen(table->names[k]));
        const Excerpt text = excerpt_of(cell, length);
        if (parsed > 0)
            return refuse(message, size, "line %ld (data row %ld), column '%.*s%s' is not a number: '%.*s%s'",
                          line->number, row, name.length, table->names[k], name.suffix, text.length, cell, text.suffix);
        return refuse(message, size, "line %ld (data row %ld), column '%.*s%s' is '%.*s%s', not a finite number",
                      line->number, row, name.length, table->names[k], name.suffix, text.length, cell, text.suffix);
    }
    return 0;
}

static double cell(const GimbalCsvTable* table, long row, int column) {
    return table->values[(size_t)row * (size_t)table->columns + (size_t)column];
}

/* Strictly increasing times, each step within [GIMBAL_CSV_LEAST_TIME_STEP,
 * GIMBAL_CSV_LARGEST_TIME_STEP]: a subnormal step would divide a change into an infinite rate, one
 * near the largest double overflow the spline's sums of steps. */
static int check_time_steps(const GimbalCsvTable* table, const long* lines, char* message, size_t size) {
    const int c = table->time_column;
    for (long row = 1; row < table->rows; ++row) {
        const double before = cell(table, row - 1, c), now = cell(table, row, c);
        if (!(now > before))
            return refuse(message, size, "'time' must increase strictly, but line %ld has %g after %g", lines[row],
                          now, before);
        const double step = now - before;
        const int below = step < GIMBAL_CSV_LEAST_TIME_STEP;
        if (below || !(step <= GIMBAL_CSV_LARGEST_TIME_STEP))
            return refuse(message, size,
                          "line %ld (data row %ld), column 'time': %g s is %g s after line %ld's %g s, %s %g s",
                          lines[row], row + 1, now, step, lines[row - 1], before,
                          below ? "below the least time step," : "above the largest time step,",
                          below ? GIMBAL_CSV_LEAST_TIME_STEP : GIMBAL_CSV_LARGEST_TIME_STEP);
    }
    return 0;
}

/* The table of the lines, the line of each row into row_lines (count - 1 of them at most). */
static int read_table(const Line* lines, long count, GimbalCsvTable* table, long* row_lines,
                      char* message, size_t size) {
    if (count == 0)
        return refuse(message, size, "the file is empty (expected a header such as 'time,gamma' and rows of numbers)");
    int status = read_header(&lines[0], table, message, size);
    if (status != 0) return status;
    table->values = malloc(sizeof(double) * (size_t)table->columns * (size_t)(count > 1 ? count - 1 : 1));
    if (table->values == NULL) return -1;
    for (long row = 1; row < count; ++row) {
        if ((status = read_row(&lines[row], row, table, message, size)) != 0) return status;
        row_lines[row - 1] = lines[row].number;
    }
    table->rows = count - 1;
    if (table->rows < MINIMUM_ROWS)
        return refuse(message, size, "%ld data rows; a cubic spline needs at least %d", table->rows, MINIMUM_ROWS);
    return check_time_steps(table, row_lines, message, size);
}

int gimbal_csv_table_read_with_lines(const char* text, size_t length, GimbalCsvTable* table, long** row_lines,
                                     char* message, size_t size) {
    memset(table, 0, sizeof *table);
    *row_lines = NULL;
    const long invalid = first_non_utf8((const unsigned char*)text, length);
    if (invalid >= 0) return refuse(message, size, "not a text file (byte %ld is not UTF-8)", invalid);
    if (length >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) text += 3, length -= 3;
    Line* lines = NULL;
    const long count = split_lines(text, length, &lines);
    if (count < 0) return -1;
    *row_lines = malloc(sizeof(long) * (size_t)(count > 1 ? count - 1 : 1));
    const int status = *row_lines == NULL ? -1 : read_table(lines, count, table, *row_lines, message, size);
    free(lines);
    if (status != 0) {
        gimbal_csv_table_free(table);
        free(*row_lines);
        *row_lines = NULL;
    }
    return status;
}

int gimbal_csv_table_read(const char* text, size_t length, GimbalCsvTable* table, char* message, size_t size) {
    long* row_lines;
    const int status = gimbal_csv_table_read_with_lines(text, length, table, &row_lines, message, size);
    free(row_lines);
    return status;
}

/* Room left above a change, a rate and an acceleration between two rows for the spline's sums of
 * them (its slopes solve a system of a few such terms per row). */
static const double kSplineRoom = 64.0;

/* The first row (> 0) whose change from the row before, its rate or its acceleration over the time
 * step overflows, kSplineRoom included; 0 when none does. */
static long first_overflowing_change(long rows, const double* time, const double* samples) {
    for (long row = 1; row < rows; ++row) {
        const double step = time[row] - time[row - 1];
        const double change = samples[row] - samples[row - 1];
        const double rate = change / step;
        if (!isfinite(kSplineRoom * change) || !isfinite(kSplineRoom * rate) || !isfinite(kSplineRoom * rate / step))
            return row;
    }
    return 0;
}

static int refuse_column(const GimbalCsvTable* table, const long* lines, int column, long row, const char* why,
                         char* message, size_t size) {
    const char* name = table->names[column];
    const Excerpt excerpt = excerpt_of(name, strlen(name));
    const double step = cell(table, row, table->time_column) - cell(table, row - 1, table->time_column);
    return refuse(message, size, "line %ld (data row %ld), column '%.*s%s': %g after line %ld's %g, %g s earlier: %s",
                  lines[row], row + 1, excerpt.length, name, excerpt.suffix, cell(table, row, column), lines[row - 1],
                  cell(table, row - 1, column), step, why);
}

int gimbal_csv_table_spline(const GimbalCsvTable* table, const long* row_lines, const double* time, int column,
                            double scale, double* coefficients, char* message, size_t size) {
    const long n = table->rows;
    double* samples = malloc(sizeof(double) * (size_t)n);
    if (samples == NULL) return -1;
    for (long i = 0; i < n; ++i) samples[i] = scale == 1.0 ? cell(table, i, column) : cell(table, i, column) * scale;
    const long overflowing = first_overflowing_change(n, time, samples);
    const int fitted = overflowing > 0 ? 1 : gimbal_cubic_spline_fit(n, time, samples, coefficients);
    free(samples);
    if (fitted < 0) return -1;
    if (overflowing > 0)
        return refuse_column(table, row_lines, column, overflowing,
                             "the change, its rate or its acceleration overflows a double", message, size);
    /* Not 1 for n < 4 (the table has more): a singular system, which strictly increasing steps
     * within the bounds do not give; refused all the same rather than splined wrong. */
    if (fitted > 0)
        return refuse_column(table, row_lines, column, n - 1, "the spline's system is singular", message, size);
    const long interval = gimbal_cubic_spline_first_overflow(n, time, coefficients);
    if (interval >= 0)
        return refuse_column(table, row_lines, column, interval + 1, "the spline between these rows overflows a double",
                             message, size);
    return 0;
}
