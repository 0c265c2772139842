#include "controller_variables.h"

#define REAL_ROW(id, name, causality, start, unit, display_unit, min, max, description) \
    [id] = {name, causality, start, unit, display_unit, min, max, description},
#define INTEGER_ROW(id, name, start, min, max, description) [id] = {name, start, min, max, description},
#define BOOLEAN_ROW(id, name, start, description) [id] = {name, start, description},

const ControllerReal kControllerReals[REAL_COUNT] = {CONTROLLER_REALS(REAL_ROW)};
const ControllerInteger kControllerIntegers[INTEGER_COUNT] = {CONTROLLER_INTEGERS(INTEGER_ROW)};
const ControllerBoolean kControllerBooleans[BOOLEAN_COUNT] = {CONTROLLER_BOOLEANS(BOOLEAN_ROW)};
