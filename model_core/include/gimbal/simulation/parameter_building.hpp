// Turns the FMU's parameter values into the constant model, refusing what is not physical.
#pragma once

#include <string>

#include "gimbal/model/gimbal_model.hpp"
#include "gimbal/model/variables.hpp"

namespace gimbal {

// On failure returns false and a message naming the variable(s) and the rule broken.
bool build_model_parameters(const double (&values)[kRealVariableCount], const int (&integers)[kIntegerVariableCount],
                            const bool (&flags)[kBooleanVariableCount], ModelParameters& params, std::string& error);

// Start values of the state must be consistent with the parameters (docs/physics.md section 3.3).
bool validate_start_state(const double (&values)[kRealVariableCount], const ModelParameters& params, std::string& error);

}  // namespace gimbal
