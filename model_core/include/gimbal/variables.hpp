// The FMU's variables: one table, in value-reference order, shared by the run-time get/set code and
// the generator of modelDescription.xml.
#pragma once

#include <cstddef>

namespace gimbal {

enum class Causality { parameter, input, output };
enum class Variability { fixed, tunable, continuous };
enum class Initial { none, exact, calculated };

struct RealVariableInfo {
    const char* name;
    Causality causality;
    Variability variability;
    Initial initial;
    const char* unit;
    const char* display_unit;  // empty when none
    double start;
    const char* description;
};

enum RealVariable : unsigned {
#define X(id, name, causality, variability, initial, unit, display_unit, start, description) vr_##id,
#include "gimbal/real_variables.def"
#undef X
    kRealVariableCount
};

extern const RealVariableInfo kRealVariables[kRealVariableCount];

}  // namespace gimbal
