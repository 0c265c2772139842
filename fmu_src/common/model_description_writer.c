/* The parts the small FMUs' model-description generators share (model_description_writer.h). */
#include "model_description_writer.h"

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

static int write_file(const char* path, FragmentWriter write) {
    FILE* out = fopen(path, "w");
    if (out == NULL) {
        fprintf(stderr, "cannot write %s\n", path);
        return 1;
    }
    const int failed = write(out);
    return (fclose(out) != 0) | failed;
}

int write_model_description_fragments(int argc, char** argv, FragmentWriter units, FragmentWriter variables,
                                      FragmentWriter structure) {
    if (argc != 4) {
        fprintf(stderr, "usage: %s <units.xml> <variables.xml> <structure.xml>\n", argv[0]);
        return 2;
    }
    return write_file(argv[1], units) || write_file(argv[2], variables) || write_file(argv[3], structure);
}
