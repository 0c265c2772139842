#include "gimbal/model/variables.hpp"

namespace gimbal {

#define X(id, name, causality, variability, initial, declared_type, unit, display_unit, start, min, max, description) \
    {name, Causality::causality, Variability::variability, Initial::initial, declared_type, unit, display_unit, start, \
     min, max, description},

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

const EnumerationType kEnumerationTypes[kEnumerationTypeCount] = {
#define TYPE(id, description) {#id, description},
#define ITEM(type, item, value, description)
#include "gimbal/enumeration_types.def"
#undef ITEM
#undef TYPE
};

const EnumerationItem kEnumerationItems[kEnumerationItemCount] = {
#define TYPE(id, description)
#define ITEM(type, item, value, description) {#type, #item, value, description},
#include "gimbal/enumeration_types.def"
#undef ITEM
#undef TYPE
};

}  // namespace gimbal
