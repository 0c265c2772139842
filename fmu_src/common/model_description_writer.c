/* The parts the small FMUs' model-description generators share (model_description_writer.h). */
#include "model_description_writer.h"

#include <string.h>

#include "fmi3_value_references.h"

void write_xml_escaped(FILE* out, const char* text) {
    for (; *text != '\0'; ++text) {
        switch (*text) {
            case '&': fputs("&amp;", out); break;
            case '<': fputs("&lt;", out); break;
            case '>': fputs("&gt;", out); break;
            case '"': fputs("&quot;", out); break;
            default: fputc(*text, out);
        }
    }
}

void write_output_unknowns(FILE* out, int real_count, int (*is_output)(int value_reference)) {
    for (int vr = 0; vr < real_count; ++vr)
        if (is_output(vr)) fprintf(out, "      <Unknown index=\"%d\" dependencies=\"\"/>\n", vr + 1);
}

void write_outputs_fmi3(FILE* out, int real_count, int (*is_output)(int value_reference)) {
    for (int vr = 0; vr < real_count; ++vr)
        if (is_output(vr)) fprintf(out, "    <Output valueReference=\"%d\" dependencies=\"\"/>\n", vr);
}

void write_independent_time(FILE* out, int fmi3) {
    if (fmi3)
        fprintf(out, "    <Float64 name=\"time\" valueReference=\"%d\" causality=\"independent\" variability=\"continuous\"\n"
                     "      description=\"simulation time\" unit=\"s\"/>\n", SMALL_FMI3_TIME);
}

void write_variable_start(FILE* out, int fmi3, const char* fmi2_type, const char* fmi3_type, const char* name,
                          int value_reference, const char* causality, const char* variability, const char* initial,
                          const char* description) {
    fprintf(out, "    <%s name=\"%s\" valueReference=\"%d\" causality=\"%s\" variability=\"%s\"",
            fmi3 ? fmi3_type : "ScalarVariable", name, value_reference, causality, variability);
    if (initial != NULL) fprintf(out, " initial=\"%s\"", initial);
    fputs("\n      description=\"", out);
    write_xml_escaped(out, description);
    if (fmi3) fputc('"', out);
    else fprintf(out, "\">\n      <%s", fmi2_type);
}

void write_variable_end(FILE* out, int fmi3) { fputs(fmi3 ? "/>\n" : "/>\n    </ScalarVariable>\n", out); }

void write_string_start_and_end(FILE* out, int fmi3, const char* start) {
    fputs(fmi3 ? ">\n      <Start value=\"" : " start=\"", out);
    write_xml_escaped(out, start);
    fputs(fmi3 ? "\"/>\n    </String>\n" : "\"/>\n    </ScalarVariable>\n", out);
}

/* Whether FMI 3.0 is asked for: a first argument --fmi3, then taken out of argv. */
static int take_fmi3_flag(int* argc, char** argv) {
    if (*argc < 2 || strcmp(argv[1], "--fmi3") != 0) return 0;
    for (int k = 1; k < *argc; ++k) argv[k] = argv[k + 1]; /* argv[argc] is NULL */
    *argc -= 1;
    return 1;
}

static int write_file(const char* path, FragmentWriter write, int fmi3) {
    FILE* out = fopen(path, "w");
    if (out == NULL) {
        fprintf(stderr, "cannot write %s\n", path);
        return 1;
    }
    const int failed = write(out, fmi3);
    return (fclose(out) != 0) | failed;
}

int write_model_description_fragments(int argc, char** argv, FragmentWriter units, FragmentWriter variables,
                                      FragmentWriter structure) {
    const int fmi3 = take_fmi3_flag(&argc, argv);
    if (argc != 4) {
        fprintf(stderr, "usage: %s [--fmi3] <units.xml> <variables.xml> <structure.xml>\n", argv[0]);
        return 2;
    }
    return write_file(argv[1], units, fmi3) || write_file(argv[2], variables, fmi3) ||
           write_file(argv[3], structure, fmi3);
}
