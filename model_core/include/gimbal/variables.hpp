// The FMU's variables: one table per FMI type, in value-reference order, shared by the run-time
// get/set code and the generator of modelDescription.xml.
#pragma once

#include <cstddef>

namespace gimbal {

enum class Causality { parameter, input, output };
enum class Variability { fixed, tunable, discrete, continuous };
enum class Initial { none, exact, calculated };

struct VariableInfo {
    const char* name;
    Causality causality;
    Variability variability;
    Initial initial;
    const char* unit;          // empty for Integer and Boolean
    const char* display_unit;  // empty when none
    double start;
    const char* description;
};
using RealVariableInfo = VariableInfo;

enum RealVariable : unsigned {
#define X(id, name, causality, variability, initial, unit, display_unit, start, description) vr_##id,
#include "gimbal/real_variables.def"
#undef X
    kRealVariableCount
};

enum IntegerVariable : unsigned {
#define X(id, name, causality, variability, initial, unit, display_unit, start, description) vi_##id,
#include "gimbal/integer_variables.def"
#undef X
    kIntegerVariableCount
};

enum BooleanVariable : unsigned {
#define X(id, name, causality, variability, initial, unit, display_unit, start, description) vb_##id,
#include "gimbal/boolean_variables.def"
#undef X
    kBooleanVariableCount
};

extern const VariableInfo kRealVariables[kRealVariableCount];
extern const VariableInfo kIntegerVariables[kIntegerVariableCount];
extern const VariableInfo kBooleanVariables[kBooleanVariableCount];

}  // namespace gimbal
