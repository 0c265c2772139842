#include "gimbal/variables.hpp"

namespace gimbal {

#define X(id, name, causality, variability, initial, unit, display_unit, start, description) \
    {name, Causality::causality, Variability::variability, Initial::initial, unit, display_unit, start, description},

const VariableInfo kRealVariables[kRealVariableCount] = {
#include "gimbal/real_variables.def"
};

const VariableInfo kIntegerVariables[kIntegerVariableCount] = {
#include "gimbal/integer_variables.def"
};

const VariableInfo kBooleanVariables[kBooleanVariableCount] = {
#include "gimbal/boolean_variables.def"
};

#undef X

}  // namespace gimbal
