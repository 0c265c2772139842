/* Writes the controller FMU's modelDescription.xml from its variable table
 * (controller_variables.def), so the description and the binary cannot disagree.
 * Usage: controller_model_description <output file> <version> <generation date and time> */
#include <stdio.h>
#include <string.h>

#include "controller_guid.h"
#include "controller_variables.h"

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

static void write_xml_text(FILE* out, const char* text) {
    for (; *text; ++text) {
        switch (*text) {
            case '&': fputs("&amp;", out); break;
            case '<': fputs("&lt;", out); break;
            case '>': fputs("&gt;", out); break;
            case '"': fputs("&quot;", out); break;
            default: fputc(*text, out);
        }
    }
}

static void write_units(FILE* out) {
    fputs("  <UnitDefinitions>\n", out);
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
    fputs("  </UnitDefinitions>\n", out);
}

static void write_real(FILE* out, int vr, const ControllerReal* v) {
    static const char* const kCausality[] = {"input", "output", "parameter"};
    static const char* const kVariability[] = {"continuous", "discrete", "fixed"};
    fprintf(out, "    <ScalarVariable name=\"%s\" valueReference=\"%d\" causality=\"%s\" variability=\"%s\"%s description=\"",
            v->name, vr, kCausality[v->causality], kVariability[v->causality], v->causality == INPUT ? "" : " initial=\"exact\"");
    write_xml_text(out, v->description);
    fprintf(out, "\">\n      <Real unit=\"%s\"", v->unit);
    if (v->display_unit[0] != '\0') fprintf(out, " displayUnit=\"%s\"", v->display_unit);
    if (v->min > -HUGE_VAL) fprintf(out, " min=\"%.17g\"", v->min);
    if (v->max < HUGE_VAL) fprintf(out, " max=\"%.17g\"", v->max);
    fprintf(out, " start=\"%.17g\"/>\n    </ScalarVariable>\n", v->start);
}

int main(int argc, char** argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: %s <modelDescription.xml> <version> <generation date and time>\n", argv[0]);
        return 2;
    }
    FILE* out = fopen(argv[1], "w");
    if (out == NULL) {
        perror(argv[1]);
        return 1;
    }
    fprintf(out,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"Gimbal2Axis-Controller\" guid=\"%s\"\n"
            "  description=\"The built-in controllers of Gimbal2Axis (PID with gyro rate and feed-forward, state feedback) with "
            "their set points toward a target and the deterministic sensors, from the C kernel of the scene runner's "
            "compiled loop (docs/controller_fmu.md)\"\n"
            "  author=\"the Gimbal2Axis authors\" version=\"%s\" copyright=\"Copyright (c) 2026 the Gimbal2Axis authors\"\n"
            "  license=\"BSD-3-Clause\" generationTool=\"Gimbal2Axis %s (controller_model_description)\"\n"
            "  generationDateAndTime=\"%s\" variableNamingConvention=\"structured\" numberOfEventIndicators=\"0\">\n"
            "  <CoSimulation modelIdentifier=\"Gimbal2AxisController\" needsExecutionTool=\"false\"\n"
            "    canHandleVariableCommunicationStepSize=\"true\" canInterpolateInputs=\"false\" maxOutputDerivativeOrder=\"0\"\n"
            "    canRunAsynchronuously=\"false\" canBeInstantiatedOnlyOncePerProcess=\"false\"\n"
            "    canNotUseMemoryManagementFunctions=\"true\" canGetAndSetFMUstate=\"false\" canSerializeFMUstate=\"false\"\n"
            "    providesDirectionalDerivative=\"false\"/>\n",
            CONTROLLER_GUID, argv[2], argv[2], argv[3]);
    write_units(out);
    fputs("  <LogCategories>\n"
          "    <Category name=\"logStatusError\" description=\"calls that return fmi2Error (always logged)\"/>\n"
          "    <Category name=\"logAll\" description=\"every message\"/>\n"
          "  </LogCategories>\n"
          "  <DefaultExperiment startTime=\"0\" stopTime=\"2\" stepSize=\"0.001\"/>\n"
          "  <ModelVariables>\n",
          out);
    /* FMI 2.0 indexes variables from 1 in the order written: Reals, Integers, Booleans. */
    for (int vr = 0; vr < REAL_COUNT; ++vr) write_real(out, vr, &kControllerReals[vr]);
    for (int vr = 0; vr < INTEGER_COUNT; ++vr) {
        const ControllerInteger* v = &kControllerIntegers[vr];
        fprintf(out, "    <ScalarVariable name=\"%s\" valueReference=\"%d\" causality=\"parameter\" variability=\"fixed\" "
                     "initial=\"exact\" description=\"", v->name, vr);
        write_xml_text(out, v->description);
        fprintf(out, "\">\n      <Integer min=\"%d\" max=\"%d\" start=\"%d\"/>\n    </ScalarVariable>\n", v->min, v->max,
                v->start);
    }
    for (int vr = 0; vr < BOOLEAN_COUNT; ++vr) {
        const ControllerBoolean* v = &kControllerBooleans[vr];
        fprintf(out, "    <ScalarVariable name=\"%s\" valueReference=\"%d\" causality=\"parameter\" variability=\"fixed\" "
                     "initial=\"exact\" description=\"", v->name, vr);
        write_xml_text(out, v->description);
        fprintf(out, "\">\n      <Boolean start=\"%s\"/>\n    </ScalarVariable>\n", v->start ? "true" : "false");
    }
    /* The outputs change only in fmi2DoStep: no direct feedthrough from any input (dependencies=""),
       so a master has no algebraic loop to solve between this FMU and the gimbal. */
    fputs("  </ModelVariables>\n  <ModelStructure>\n    <Outputs>\n", out);
    for (int vr = 0; vr < REAL_COUNT; ++vr)
        if (kControllerReals[vr].causality == OUTPUT) fprintf(out, "      <Unknown index=\"%d\" dependencies=\"\"/>\n", vr + 1);
    fputs("    </Outputs>\n  </ModelStructure>\n</fmiModelDescription>\n", out);
    return fclose(out) == 0 ? 0 : 1;
}
