// The model put in place for a run being built (GimbalInstance): the hybrid system keeps a reference
// to the instance model's parameters, so a new model goes in place, whole, before it is built.
#pragma once

#include "gimbal/simulation/gimbal_instance.hpp"

namespace gimbal {

// Puts the previous model back unless the new run is committed.
class ModelSwap {
public:
    ModelSwap(InstanceModel& current, const InstanceModel& next) : current_(current), previous_(current) {
        current_ = next;
    }
    ~ModelSwap() {
        if (!committed_) current_ = previous_;
    }
    void commit() { committed_ = true; }

private:
    InstanceModel& current_;
    InstanceModel previous_;
    bool committed_ = false;
};

}  // namespace gimbal
