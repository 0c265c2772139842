// One simulation instance: the variable values, the constant model built from them, the state and
// the integrator (Pinocchio-style split: ModelParameters is constant during a run, the rest is data).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "gimbal/gimbal_c_api.h"
#include "gimbal/gimbal_model.hpp"
#include "gimbal/integrator.hpp"
#include "gimbal/variables.hpp"

namespace gimbal {

class GimbalInstance {
public:
    using Logger = std::function<void(GimbalStatus, const char* category, const std::string& message)>;

    explicit GimbalInstance(Logger logger);

    void reset();
    GimbalStatus set_real(unsigned vr, double value);
    GimbalStatus get_real(unsigned vr, double& value) const;
    GimbalStatus initialize(double start_time);
    GimbalStatus do_step(double current_time, double step_size);
    double time() const { return time_; }

private:
    StepInputs read_step_inputs(double step_start) const;
    void publish_outputs(const StepInputs& inputs);
    GimbalStatus refuse(GimbalStatus status, const std::string& message) const;

    Logger logger_;
    double values_[kRealVariableCount];
    ModelParameters params_;
    StateVector state_;
    std::unique_ptr<CvodeIntegrator> integrator_;
    StepInputs previous_inputs_;
    bool integrator_running_ = false;  // false: the next step must restart CVODE
    double previous_step_size_ = 0.0;
    double time_ = 0.0;
};

}  // namespace gimbal
