/* The controller FMU's variables (controller_variables.def) as enums of value references and as a
 * table of their attributes, shared by the FMI wrapper and the model description's generator. */
#ifndef GIMBAL_CONTROLLER_VARIABLES_H
#define GIMBAL_CONTROLLER_VARIABLES_H

#include <math.h>

#include "controller_variables.def"

#define NO_MIN (-HUGE_VAL)
#define NO_MAX HUGE_VAL

typedef enum { INPUT, OUTPUT, PARAMETER } ControllerCausality;

#define CONTROLLER_ENUM_REAL(id, ...) id,
#define CONTROLLER_ENUM_OTHER(id, ...) id,
enum { CONTROLLER_REALS(CONTROLLER_ENUM_REAL) REAL_COUNT };
enum { CONTROLLER_INTEGERS(CONTROLLER_ENUM_OTHER) INTEGER_COUNT };
enum { CONTROLLER_BOOLEANS(CONTROLLER_ENUM_OTHER) BOOLEAN_COUNT };

typedef struct {
    const char* name;
    ControllerCausality causality;
    double start;
    const char* unit;
    const char* display_unit;
    double min, max;
    const char* description;
} ControllerReal;

typedef struct {
    const char* name;
    int start, min, max;
    const char* description;
} ControllerInteger;

typedef struct {
    const char* name;
    int start;
    const char* description;
} ControllerBoolean;

extern const ControllerReal kControllerReals[REAL_COUNT];
extern const ControllerInteger kControllerIntegers[INTEGER_COUNT];
extern const ControllerBoolean kControllerBooleans[BOOLEAN_COUNT];

#endif
