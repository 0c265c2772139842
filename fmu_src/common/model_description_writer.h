/* What the model-description generators of the small Co-Simulation FMUs (ship_motion/, controller/)
 * share. Each writes the three fragments of its modelDescription.xml.in from the variable table the
 * binary serves (so that the XML and the binary cannot disagree): units.xml, variables.xml,
 * structure.xml; configure_model_description.cmake fills the template with them at build time. */
#ifndef GIMBAL_MODEL_DESCRIPTION_WRITER_H
#define GIMBAL_MODEL_DESCRIPTION_WRITER_H

#include <stdio.h>

/* `text` as an XML attribute value: & < > " escaped. */
void write_xml_escaped(FILE* out, const char* text);

/* <Unknown index="..." dependencies=""/> of a ModelStructure section: index = value reference + 1,
 * for the Real variables `is_output` says yes to. The empty dependencies say that no input feeds
 * an output directly: a master has no algebraic loop to solve through this FMU. */
void write_output_unknowns(FILE* out, int real_count, int (*is_output)(int value_reference));

/* Writes one fragment; nonzero (said on stderr) when its table is inconsistent. */
typedef int (*FragmentWriter)(FILE* out);

/* The generator's main: `argv` names units.xml, variables.xml and structure.xml, written in that
 * order. 0, or nonzero (said on stderr) when a file cannot be written or a writer refuses. */
int write_model_description_fragments(int argc, char** argv, FragmentWriter units, FragmentWriter variables,
                                      FragmentWriter structure);

#endif
