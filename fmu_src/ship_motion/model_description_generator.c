/* Writes the variable, unit and structure parts of the ship-motion FMU's modelDescription.xml from
 * its variable table (ship_motion_variables.c), so that the XML and the binary cannot disagree, for
 * the FMI 2.0 FMU or (--fmi3) the FMI 3.0 one:
 *     ship_motion_model_description_generator [--fmi3] <units.xml> <variables.xml> <structure.xml>
 * It refuses (exit status 1, a message on stderr) a variable whose unit or display unit is not defined. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fmi3_value_references.h"
#include "model_description_writer.h"
#include "ship_motion_variables.h"

typedef struct {
    const char* name;
    const char* base_unit;    /* the attributes of <BaseUnit> */
    const char* display_unit; /* "" for none; else degrees of the radian-based unit */
} Unit;

static const Unit kUnits[] = {
    {"1", "", ""},
    {"rad", "rad=\"1\"", "deg"},
    {"rad/s", "s=\"-1\" rad=\"1\"", "deg/s"},
    {"rad/s2", "s=\"-2\" rad=\"1\"", "deg/s2"},
    {"s", "s=\"1\"", ""},
    {"m", "m=\"1\"", ""},
    {"m/s", "m=\"1\" s=\"-1\"", ""},
    {"m/s2", "m=\"1\" s=\"-2\"", ""},
};
enum { UNIT_COUNT = sizeof kUnits / sizeof kUnits[0] };

/* 180 / pi, as the gimbal's model description writes it. */
static const char kDegreesPerRadian[] = "57.29577951308232";

static const Unit* find_unit(const char* name) {
    for (int k = 0; k < UNIT_COUNT; ++k)
        if (strcmp(kUnits[k].name, name) == 0) return &kUnits[k];
    return NULL;
}

/* The same in FMI 2.0 and FMI 3.0. */
static int write_units(FILE* out, int fmi3) {
    (void)fmi3;
    for (int k = 0; k < UNIT_COUNT; ++k) {
        fprintf(out, "    <Unit name=\"%s\">", kUnits[k].name);
        if (kUnits[k].base_unit[0] != '\0') fprintf(out, "<BaseUnit %s/>", kUnits[k].base_unit);
        if (kUnits[k].display_unit[0] != '\0')
            fprintf(out, "<DisplayUnit name=\"%s\" factor=\"%s\" offset=\"0\"/>", kUnits[k].display_unit, kDegreesPerRadian);
        fputs("</Unit>\n", out);
    }
    return 0;
}

/* FMI 3.0's value references: common/fmi3_value_references.h (FMI 2.0's number each type from 0). */
_Static_assert((int)SHIP_REAL_COUNT <= (int)SMALL_FMI3_TYPE_CAPACITY &&
                   (int)SHIP_INTEGER_COUNT <= (int)SMALL_FMI3_TYPE_CAPACITY,
               "FMI 3.0's value references leave room for the variables of each type");
/* One Real: an output, or a parameter with its start value; 1 (said on stderr) when its unit is not
 * one of the unit definitions. */
static int write_real(FILE* out, int fmi3, int vr) {
    const ShipRealVariable* v = &kShipRealVariables[vr];
    const Unit* unit = find_unit(v->unit);
    if (unit == NULL || (v->display_unit[0] != '\0' && strcmp(unit->display_unit, v->display_unit) != 0)) {
        fprintf(stderr, "%s: unit '%s' or display unit '%s' is not defined\n", v->name, v->unit, v->display_unit);
        return 1;
    }
    const int output = v->causality == SHIP_OUTPUT;
    write_variable_start(out, fmi3, "Real", "Float64", v->name, (fmi3 ? SMALL_FMI3_FLOAT64_BASE : 0) + vr,
                         output ? "output" : "parameter", output ? "continuous" : "fixed",
                         output ? "calculated" : "exact", v->description);
    fprintf(out, " unit=\"%s\"", v->unit);
    if (v->display_unit[0] != '\0') fprintf(out, " displayUnit=\"%s\"", v->display_unit);
    if (!output) fprintf(out, " start=\"%.17g\"", v->start);
    if (v->min != -HUGE_VAL) fprintf(out, " min=\"%.17g\"", v->min);
    write_variable_end(out, fmi3);
    return 0;
}

static int write_variables(FILE* out, int fmi3) {
    write_independent_time(out, fmi3);
    for (int vr = 0; vr < SHIP_REAL_COUNT; ++vr)
        if (write_real(out, fmi3, vr) != 0) return 1;
    for (int vr = 0; vr < SHIP_INTEGER_COUNT; ++vr) {
        const ShipIntegerVariable* v = &kShipIntegerVariables[vr];
        write_variable_start(out, fmi3, "Integer", "Int32", v->name, (fmi3 ? SMALL_FMI3_INT32_BASE : 0) + vr,
                             "parameter", "fixed", "exact", v->description);
        fprintf(out, " start=\"%d\" min=\"%d\" max=\"%d\"", v->start, v->min, v->max);
        write_variable_end(out, fmi3);
    }
    for (int vr = 0; vr < SHIP_STRING_COUNT; ++vr) {
        const ShipStringVariable* v = &kShipStringVariables[vr];
        write_variable_start(out, fmi3, "String", "String", v->name, (fmi3 ? SMALL_FMI3_STRING_BASE : 0) + vr,
                             "parameter", "fixed", "exact", v->description);
        write_string_start_and_end(out, fmi3, v->start);
    }
    return 0;
}

static int is_output(int value_reference) { return kShipRealVariables[value_reference].causality == SHIP_OUTPUT; }

/* The outputs are the first variables (FMI 2.0's index = value reference + 1, FMI 3.0 names the
 * value reference). They depend on no input (there are none); at initialization on the parameters
 * (no dependencies attribute: on all of them). */
static int write_structure(FILE* out, int fmi3) {
    if (fmi3) {
        write_outputs_fmi3(out, SHIP_REAL_COUNT, is_output);
        for (int vr = 0; vr < SHIP_REAL_OUTPUTS; ++vr)
            fprintf(out, "    <InitialUnknown valueReference=\"%d\"/>\n", SMALL_FMI3_FLOAT64_BASE + vr);
        return 0;
    }
    fputs("    <Outputs>\n", out);
    write_output_unknowns(out, SHIP_REAL_COUNT, is_output);
    fputs("    </Outputs>\n    <InitialUnknowns>\n", out);
    for (int vr = 0; vr < SHIP_REAL_OUTPUTS; ++vr) fprintf(out, "      <Unknown index=\"%d\"/>\n", vr + 1);
    fputs("    </InitialUnknowns>\n", out);
    return 0;
}

int main(int argc, char** argv) {
    for (int vr = 0; vr < SHIP_REAL_COUNT; ++vr)
        if (is_output(vr) != (vr < SHIP_REAL_OUTPUTS)) {
            fprintf(stderr, "%s: the first %d Real variables must be the outputs, and only they\n",
                    kShipRealVariables[vr].name, SHIP_REAL_OUTPUTS);
            return 1;
        }
    return write_model_description_fragments(argc, argv, write_units, write_variables, write_structure);
}
