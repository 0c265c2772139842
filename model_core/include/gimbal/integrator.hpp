// SUNDIALS CVODE (BDF, Newton, dense linear solver) over the continuous dynamics.
#pragma once

#include <functional>
#include <string>

#include "gimbal/gimbal_model.hpp"

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nvector.h>

namespace gimbal {

struct IntegratorStatistics {
    long steps = 0;
    long rhs_evaluations = 0;
    long jacobian_evaluations = 0;
};

class CvodeIntegrator {
public:
    using ErrorSink = std::function<void(const std::string&)>;

    CvodeIntegrator(const ModelParameters& params, ErrorSink error_sink);
    ~CvodeIntegrator();
    CvodeIntegrator(const CvodeIntegrator&) = delete;
    CvodeIntegrator& operator=(const CvodeIntegrator&) = delete;

    // Starts integration afresh at (time, state): needed after any discontinuity of the right-hand side.
    bool restart(double time, const StateVector& state);

    // Integrates to exactly end_time under inputs held over the step. False on failure, with the
    // reason sent to the error sink; the state is then unspecified and the caller must roll back.
    bool advance(const StepInputs& inputs, double end_time, StateVector& state);

    IntegratorStatistics statistics() const;

private:
    static int right_hand_side(sunrealtype time, N_Vector y, N_Vector ydot, void* user_data);
    static void forward_error(int code, const char* module, const char* function, char* message, void* user_data);

    const ModelParameters& params_;
    ErrorSink error_sink_;
    StepInputs inputs_;
    SUNContext context_ = nullptr;
    N_Vector y_ = nullptr;
    SUNMatrix jacobian_ = nullptr;
    SUNLinearSolver linear_solver_ = nullptr;
    void* cvode_ = nullptr;
    bool initialized_ = false;
};

}  // namespace gimbal
