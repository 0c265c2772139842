/* Writes the unit, variable and structure parts of the controller FMU's modelDescription.xml
 * (modelDescription.xml.in holds the rest) from its variable table (controller_variables.def), so
 * the description and the binary cannot disagree, for the FMI 2.0 FMU or (--fmi3) the FMI 3.0 one:
 *     controller_model_description [--fmi3] <units.xml> <variables.xml> <structure.xml> */
#include <math.h>
#include <stdio.h>

#include "controller_variables.h"
#include "fmi3_value_references.h"
#include "model_description_writer.h"

/* The units of the table, by their SI base units (kg, m, s, A, rad exponents). */
static const struct {
    const char* name;
    int kg, m, s, a, rad;
    const char* display; /* a degree-based display unit, or NULL */
} kUnits[] = {
    {"1", 0, 0, 0, 0, 0, NULL},        {"rad", 0, 0, 0, 0, 1, "deg"},     {"rad/s", 0, 0, -1, 0, 1, "deg/s"},
    {"s", 0, 0, 1, 0, 0, NULL},        {"V", 1, 2, -3, -1, 0, NULL},      {"V/rad", 1, 2, -3, -1, -1, NULL},
    {"V.s/rad", 1, 2, -2, -1, -1, NULL}, {"V/(rad.s)", 1, 2, -4, -1, -1, NULL},
    {"V.s2/rad", 1, 2, -1, -1, -1, NULL}, {"rad/s2", 0, 0, -2, 0, 1, "deg/s2"}, {"m", 0, 1, 0, 0, 0, NULL},
    {"m/s", 0, 1, -1, 0, 0, NULL},     {"m/s2", 0, 1, -2, 0, 0, NULL},
};

/* The same in FMI 2.0 and FMI 3.0. */
static int write_units(FILE* out, int fmi3) {
    (void)fmi3;
    for (size_t i = 0; i < sizeof kUnits / sizeof kUnits[0]; ++i) {
        fprintf(out, "    <Unit name=\"%s\">\n      <BaseUnit", kUnits[i].name);
        const char* names[] = {"kg", "m", "s", "A", "rad"};
        const int exponents[] = {kUnits[i].kg, kUnits[i].m, kUnits[i].s, kUnits[i].a, kUnits[i].rad};
        for (int j = 0; j < 5; ++j)
            if (exponents[j] != 0) fprintf(out, " %s=\"%d\"", names[j], exponents[j]);
        fputs("/>\n", out);
        if (kUnits[i].display != NULL)
            fprintf(out, "      <DisplayUnit name=\"%s\" factor=\"57.295779513082323\"/>\n", kUnits[i].display);
        fputs("    </Unit>\n", out);
    }
    return 0;
}

static void write_real(FILE* out, int fmi3, int vr, const ControllerReal* v) {
    static const char* const kCausality[] = {"input", "output", "parameter"};
    static const char* const kVariability[] = {"continuous", "discrete", "fixed"};
    write_variable_start(out, fmi3, "Real", "Float64", v->name, (fmi3 ? SMALL_FMI3_FLOAT64_BASE : 0) + vr,
                         kCausality[v->causality], kVariability[v->causality], v->causality == INPUT ? NULL : "exact",
                         v->description);
    fprintf(out, " unit=\"%s\"", v->unit);
    if (v->display_unit[0] != '\0') fprintf(out, " displayUnit=\"%s\"", v->display_unit);
    if (v->min > -HUGE_VAL) fprintf(out, " min=\"%.17g\"", v->min);
    if (v->max < HUGE_VAL) fprintf(out, " max=\"%.17g\"", v->max);
    fprintf(out, " start=\"%.17g\"", v->start);
    write_variable_end(out, fmi3);
}

/* FMI 2.0 indexes variables from 1 in the order written: Reals, Integers, Booleans. FMI 3.0's value
 * references: common/fmi3_value_references.h (FMI 2.0's number each type from 0). */
_Static_assert((int)REAL_COUNT <= (int)SMALL_FMI3_TYPE_CAPACITY && (int)INTEGER_COUNT <= (int)SMALL_FMI3_TYPE_CAPACITY &&
                   (int)BOOLEAN_COUNT <= (int)SMALL_FMI3_TYPE_CAPACITY,
               "FMI 3.0's value references leave room for the variables of each type");
static int write_variables(FILE* out, int fmi3) {
    write_independent_time(out, fmi3);
    for (int vr = 0; vr < REAL_COUNT; ++vr) write_real(out, fmi3, vr, &kControllerReals[vr]);
    for (int vr = 0; vr < INTEGER_COUNT; ++vr) {
        const ControllerInteger* v = &kControllerIntegers[vr];
        write_variable_start(out, fmi3, "Integer", "Int32", v->name, (fmi3 ? SMALL_FMI3_INT32_BASE : 0) + vr,
                             "parameter", "fixed", "exact", v->description);
        fprintf(out, " min=\"%d\" max=\"%d\" start=\"%d\"", v->min, v->max, v->start);
        write_variable_end(out, fmi3);
    }
    for (int vr = 0; vr < BOOLEAN_COUNT; ++vr) {
        const ControllerBoolean* v = &kControllerBooleans[vr];
        write_variable_start(out, fmi3, "Boolean", "Boolean", v->name, (fmi3 ? SMALL_FMI3_BOOLEAN_BASE : 0) + vr,
                             "parameter", "fixed", "exact", v->description);
        fprintf(out, " start=\"%s\"", v->start ? "true" : "false");
        write_variable_end(out, fmi3);
    }
    return 0;
}

static int is_output(int value_reference) { return kControllerReals[value_reference].causality == OUTPUT; }

/* The outputs change only in the step: no direct feedthrough from any input (dependencies=""),
   so a master has no algebraic loop to solve between this FMU and the gimbal. */
static int write_structure(FILE* out, int fmi3) {
    if (fmi3) {
        write_outputs_fmi3(out, REAL_COUNT, is_output);
        return 0;
    }
    fputs("    <Outputs>\n", out);
    write_output_unknowns(out, REAL_COUNT, is_output);
    fputs("    </Outputs>\n", out);
    return 0;
}

int main(int argc, char** argv) {
    return write_model_description_fragments(argc, argv, write_units, write_variables, write_structure);
}
