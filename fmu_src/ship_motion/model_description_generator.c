/* Writes the variable, unit and structure parts of the ship-motion FMU's modelDescription.xml from
 * its variable table (ship_motion_variables.c), so that the XML and the binary cannot disagree:
 *     ship_motion_model_description_generator <units.xml> <variables.xml> <structure.xml>
 * It refuses (exit status 1, a message on stderr) a variable whose unit or display unit is not defined. */
#include <math.h>
#include <stdio.h>
#include <string.h>

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

static int write_units(FILE* out) {
    for (int k = 0; k < UNIT_COUNT; ++k) {
        fprintf(out, "    <Unit name=\"%s\">", kUnits[k].name);
        if (kUnits[k].base_unit[0] != '\0') fprintf(out, "<BaseUnit %s/>", kUnits[k].base_unit);
        if (kUnits[k].display_unit[0] != '\0')
            fprintf(out, "<DisplayUnit name=\"%s\" factor=\"%s\" offset=\"0\"/>", kUnits[k].display_unit, kDegreesPerRadian);
        fputs("</Unit>\n", out);
    }
    return 0;
}

static int write_variables(FILE* out) {
    for (int vr = 0; vr < SHIP_REAL_COUNT; ++vr) {
        const ShipRealVariable* v = &kShipRealVariables[vr];
        const Unit* unit = find_unit(v->unit);
        if (unit == NULL || (v->display_unit[0] != '\0' && strcmp(unit->display_unit, v->display_unit) != 0)) {
            fprintf(stderr, "%s: unit '%s' or display unit '%s' is not defined\n", v->name, v->unit, v->display_unit);
            return 1;
        }
        const int output = v->causality == SHIP_OUTPUT;
        fprintf(out, "    <ScalarVariable name=\"%s\" valueReference=\"%d\" causality=\"%s\" variability=\"%s\" initial=\"%s\"\n"
                     "      description=\"",
                v->name, vr, output ? "output" : "parameter", output ? "continuous" : "fixed", output ? "calculated" : "exact");
        write_xml_escaped(out, v->description);
        fprintf(out, "\">\n      <Real unit=\"%s\"", v->unit);
        if (v->display_unit[0] != '\0') fprintf(out, " displayUnit=\"%s\"", v->display_unit);
        if (!output) fprintf(out, " start=\"%.17g\"", v->start);
        if (v->min != -HUGE_VAL) fprintf(out, " min=\"%.17g\"", v->min);
        fputs("/>\n    </ScalarVariable>\n", out);
    }
    for (int vr = 0; vr < SHIP_INTEGER_COUNT; ++vr) {
        const ShipIntegerVariable* v = &kShipIntegerVariables[vr];
        fprintf(out, "    <ScalarVariable name=\"%s\" valueReference=\"%d\" causality=\"parameter\" variability=\"fixed\" "
                     "initial=\"exact\"\n      description=\"", v->name, vr);
        write_xml_escaped(out, v->description);
        fprintf(out, "\">\n      <Integer start=\"%d\" min=\"%d\" max=\"%d\"/>\n    </ScalarVariable>\n", v->start, v->min,
                v->max);
    }
    for (int vr = 0; vr < SHIP_STRING_COUNT; ++vr) {
        const ShipStringVariable* v = &kShipStringVariables[vr];
        fprintf(out, "    <ScalarVariable name=\"%s\" valueReference=\"%d\" causality=\"parameter\" variability=\"fixed\" "
                     "initial=\"exact\"\n      description=\"", v->name, vr);
        write_xml_escaped(out, v->description);
        fputs("\">\n      <String start=\"", out);
        write_xml_escaped(out, v->start);
        fputs("\"/>\n    </ScalarVariable>\n", out);
    }
    return 0;
}

static int is_output(int value_reference) { return kShipRealVariables[value_reference].causality == SHIP_OUTPUT; }

/* The outputs are the first variables (index = value reference + 1). They depend on no input (there
 * are none); at initialization on the parameters (no dependencies attribute: on all of them). */
static int write_structure(FILE* out) {
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
