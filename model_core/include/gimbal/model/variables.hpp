// The FMU's variables: one table per FMI type, in value-reference order, shared by the run-time
// get/set code and the generator of modelDescription.xml.
#pragma once

#include <cstddef>
#include <limits>

namespace gimbal {

enum class Causality { parameter, input, output, local };
enum class Variability { fixed, tunable, discrete, continuous };
// approx: the start value is where the FMU begins, not necessarily where it ends: the rotor angles and
// rates, which a compliant gear's start rule (gear<j>.start) may put in mesh with their loads. In the
// order of the C interface's GimbalInitial (gimbal_c_api.h), which gimbal_variable_info casts to.
enum class Initial { none, exact, calculated, approx };

// Bounds of the .def tables' min and max columns. FMI's min and max are inclusive, so a strict bound
// is written as the nearest double inside it: "> 0" as the least positive normal double (not the
// least subnormal one, 4.9e-324: C's strtod reports it as out of range, and std::stod throws), "< 1"
// as the greatest double below 1. The validation's "> 0" is ">= kAboveZero" accordingly.
inline constexpr double kNoMin = -std::numeric_limits<double>::infinity();
inline constexpr double kNoMax = std::numeric_limits<double>::infinity();
inline constexpr double kAboveZero = (std::numeric_limits<double>::min)();          // 2.2250738585072014e-308
inline constexpr double kBelowOne = 1.0 - std::numeric_limits<double>::epsilon() / 2;  // 0.99999999999999989

struct VariableInfo {
    const char* name;
    Causality causality;
    Variability variability;
    Initial initial;
    const char* declared_type;  // an enumeration type (enumeration_types.def), or empty
    const char* unit;           // empty for Integer and Boolean
    const char* display_unit;   // empty when none
    double start;
    double min, max;            // kNoMin, kNoMax when unbounded
    const char* description;
};
using RealVariableInfo = VariableInfo;

enum RealVariable : unsigned {
#define X(id, name, causality, variability, initial, declared_type, unit, display_unit, start, min, max, description) vr_##id,
#include "gimbal/real_variables.def"
#undef X
    kRealVariableCount
};

enum IntegerVariable : unsigned {
#define X(id, name, causality, variability, initial, declared_type, unit, display_unit, start, min, max, description) vi_##id,
#include "gimbal/integer_variables.def"
#undef X
    kIntegerVariableCount
};

enum BooleanVariable : unsigned {
#define X(id, name, causality, variability, initial, declared_type, unit, display_unit, start, min, max, description) vb_##id,
#include "gimbal/boolean_variables.def"
#undef X
    kBooleanVariableCount
};

struct EnumerationType {
    const char* name;
    const char* description;
};
struct EnumerationItem {
    const char* type;  // the EnumerationType's name
    const char* name;
    int value;
    const char* description;
};

enum EnumerationTypeIndex : unsigned {
#define TYPE(id, description) enumeration_##id,
#define ITEM(type, item, value, description)
#include "gimbal/enumeration_types.def"
#undef ITEM
#undef TYPE
    kEnumerationTypeCount
};
inline constexpr unsigned kEnumerationItemCount = 0
#define TYPE(id, description)
#define ITEM(type, item, value, description) +1
#include "gimbal/enumeration_types.def"
#undef ITEM
#undef TYPE
    ;

extern const VariableInfo kRealVariables[kRealVariableCount];
extern const VariableInfo kIntegerVariables[kIntegerVariableCount];
extern const VariableInfo kBooleanVariables[kBooleanVariableCount];
extern const EnumerationType kEnumerationTypes[kEnumerationTypeCount];
extern const EnumerationItem kEnumerationItems[kEnumerationItemCount];

}  // namespace gimbal
