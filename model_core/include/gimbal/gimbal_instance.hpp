// One simulation instance: the variable values, the constant model built from them, the state, the
// hybrid system and its integrator (Pinocchio-style split: ModelParameters is constant during a run,
// the rest is per-run data).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "gimbal/gimbal_c_api.h"
#include "gimbal/gimbal_hybrid_system.hpp"
#include "gimbal/integrator.hpp"
#include "gimbal/variables.hpp"

namespace gimbal {

class GimbalInstance {
public:
    using Logger = std::function<void(GimbalStatus, const char* category, const std::string& message)>;

    explicit GimbalInstance(Logger logger);
    GimbalInstance(const GimbalInstance&) = delete;
    GimbalInstance& operator=(const GimbalInstance&) = delete;

    void reset();
    GimbalStatus set_real(unsigned vr, double value);
    GimbalStatus get_real(unsigned vr, double& value) const;
    GimbalStatus set_integer(unsigned vr, int value);
    GimbalStatus get_integer(unsigned vr, int& value) const;
    GimbalStatus set_boolean(unsigned vr, bool value);
    GimbalStatus get_boolean(unsigned vr, bool& value) const;
    GimbalStatus initialize(double start_time);
    GimbalStatus do_step(double current_time, double step_size);
    double time() const { return time_; }

private:
    StepInputs read_step_inputs(double step_start) const;
    void publish_outputs();
    GimbalStatus refuse(GimbalStatus status, const std::string& message) const;

    Logger logger_;
    double reals_[kRealVariableCount];
    int integers_[kIntegerVariableCount];
    bool booleans_[kBooleanVariableCount];
    ModelParameters params_;
    double state_[kMaxStateSize];
    std::unique_ptr<GimbalHybridSystem> system_;
    std::unique_ptr<HybridCvodeIntegrator> integrator_;
    bool integrator_running_ = false;  // false: the next step must restart the integrator
    double time_ = 0.0;
};

}  // namespace gimbal
