/* Writes the unit, variable and structure parts of the controller FMU's modelDescription.xml
 * (modelDescription.xml.in holds the rest) from its variable table (controller_variables.def), so
 * the description and the binary cannot disagree:
 *     controller_model_description <units.xml> <variables.xml> <structure.xml> */
#include <math.h>
#include <stdio.h>

#include "controller_variables.h"
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
};

static int write_units(FILE* out) {
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

static void write_real(FILE* out, int vr, const ControllerReal* v) {
    static const char* const kCausality[] = {"input", "output", "parameter"};
    static const char* const kVariability[] = {"continuous", "discrete", "fixed"};
    fprintf(out, "    <ScalarVariable name=\"%s\" valueReference=\"%d\" causality=\"%s\" variability=\"%s\"%s description=\"",
            v->name, vr, kCausality[v->causality], kVariability[v->causality], v->causality == INPUT ? "" : " initial=\"exact\"");
    write_xml_escaped(out, v->description);
    fprintf(out, "\">\n      <Real unit=\"%s\"", v->unit);
    if (v->display_unit[0] != '\0') fprintf(out, " displayUnit=\"%s\"", v->display_unit);
    if (v->min > -HUGE_VAL) fprintf(out, " min=\"%.17g\"", v->min);
    if (v->max < HUGE_VAL) fprintf(out, " max=\"%.17g\"", v->max);
    fprintf(out, " start=\"%.17g\"/>\n    </ScalarVariable>\n", v->start);
}

/* FMI 2.0 indexes variables from 1 in the order written: Reals, Integers, Booleans. */
static int write_variables(FILE* out) {
    for (int vr = 0; vr < REAL_COUNT; ++vr) write_real(out, vr, &kControllerReals[vr]);
    for (int vr = 0; vr < INTEGER_COUNT; ++vr) {
        const ControllerInteger* v = &kControllerIntegers[vr];
        fprintf(out, "    <ScalarVariable name=\"%s\" valueReference=\"%d\" causality=\"parameter\" variability=\"fixed\" "
                     "initial=\"exact\" description=\"", v->name, vr);
        write_xml_escaped(out, v->description);
        fprintf(out, "\">\n      <Integer min=\"%d\" max=\"%d\" start=\"%d\"/>\n    </ScalarVariable>\n", v->min, v->max,
                v->start);
    }
    for (int vr = 0; vr < BOOLEAN_COUNT; ++vr) {
        const ControllerBoolean* v = &kControllerBooleans[vr];
        fprintf(out, "    <ScalarVariable name=\"%s\" valueReference=\"%d\" causality=\"parameter\" variability=\"fixed\" "
                     "initial=\"exact\" description=\"", v->name, vr);
        write_xml_escaped(out, v->description);
        fprintf(out, "\">\n      <Boolean start=\"%s\"/>\n    </ScalarVariable>\n", v->start ? "true" : "false");
    }
    return 0;
}

static int is_output(int value_reference) { return kControllerReals[value_reference].causality == OUTPUT; }

/* The outputs change only in fmi2DoStep: no direct feedthrough from any input (dependencies=""),
   so a master has no algebraic loop to solve between this FMU and the gimbal. */
static int write_structure(FILE* out) {
    fputs("    <Outputs>\n", out);
    write_output_unknowns(out, REAL_COUNT, is_output);
    fputs("    </Outputs>\n", out);
    return 0;
}

int main(int argc, char** argv) {
    return write_model_description_fragments(argc, argv, write_units, write_variables, write_structure);
}
