// Parameters put in place for a run being built (GimbalInstance): the hybrid system keeps a reference
// to the instance's parameters, so new ones go in place before it is built.
#pragma once

#include "gimbal/model/gimbal_model.hpp"

namespace gimbal {

// Puts the previous parameters back unless the new run is committed.
class ParameterSwap {
public:
    ParameterSwap(ModelParameters& current, const ModelParameters& next) : current_(current), previous_(current) {
        current_ = next;
    }
    ~ParameterSwap() {
        if (!committed_) current_ = previous_;
    }
    void commit() { committed_ = true; }

private:
    ModelParameters& current_;
    ModelParameters previous_;
    bool committed_ = false;
};

}  // namespace gimbal
