#include "gimbal/variables.hpp"

namespace gimbal {

const RealVariableInfo kRealVariables[kRealVariableCount] = {
#define X(id, name, causality, variability, initial, unit, display_unit, start, description) \
    {name, Causality::causality, Variability::variability, Initial::initial, unit, display_unit, start, description},
#include "gimbal/real_variables.def"
#undef X
};

}  // namespace gimbal
