/* What the model-description generators of the small Co-Simulation FMUs (ship_motion/, controller/)
 * share. Each writes the three fragments of its modelDescription.xml.in from the variable table the
 * binary serves (so that the XML and the binary cannot disagree): units.xml, variables.xml,
 * structure.xml, for FMI 2.0 or (--fmi3) FMI 3.0; configure_model_description.cmake fills the
 * version's template with them at build time. */
#ifndef GIMBAL_MODEL_DESCRIPTION_WRITER_H
#define GIMBAL_MODEL_DESCRIPTION_WRITER_H

#include <stdio.h>

/* `text` as an XML attribute value: & < > " escaped. */
void write_xml_escaped(FILE* out, const char* text);

/* <Unknown index="..." dependencies=""/> of a ModelStructure section: index = value reference + 1,
 * for the Real variables `is_output` says yes to. The empty dependencies say that no input feeds
 * an output directly: a master has no algebraic loop to solve through this FMU. */
void write_output_unknowns(FILE* out, int real_count, int (*is_output)(int value_reference));

/* The same for FMI 3.0's <ModelStructure>: <Output valueReference="..." dependencies=""/>. */
void write_outputs_fmi3(FILE* out, int real_count, int (*is_output)(int value_reference));

/* FMI 3.0's independent variable `time` (value reference SMALL_FMI3_TIME), which FMI 3.0 requires:
 * the first variable of an FMI 3.0 <ModelVariables>; FMI 2.0 has none. */
void write_independent_time(FILE* out, int fmi3);

/* A variable as its version writes it: FMI 2.0's <ScalarVariable ...><Real, or FMI 3.0's <Float64 ...
 * (`fmi2_type`, `fmi3_type`), with the attributes both share (`initial`: NULL for none); the caller
 * then writes the type's attributes (unit, start, min ...), and write_variable_end closes both. */
void write_variable_start(FILE* out, int fmi3, const char* fmi2_type, const char* fmi3_type, const char* name,
                          int value_reference, const char* causality, const char* variability, const char* initial,
                          const char* description);
void write_variable_end(FILE* out, int fmi3);
/* A String variable's start value: FMI 2.0's start attribute, FMI 3.0's <Start> element; it closes
 * the variable (no write_variable_end). */
void write_string_start_and_end(FILE* out, int fmi3, const char* start);

/* Writes one fragment of FMI 2.0 or (fmi3) FMI 3.0; nonzero (said on stderr) when its table is
 * inconsistent. */
typedef int (*FragmentWriter)(FILE* out, int fmi3);

/* The generator's main: `argv` names units.xml, variables.xml and structure.xml, written in that
 * order, after --fmi3 when FMI 3.0's are asked for. 0, or nonzero (said on stderr) when a file cannot be written or a writer refuses. */
int write_model_description_fragments(int argc, char** argv, FragmentWriter units, FragmentWriter variables,
                                      FragmentWriter structure);

#endif
