#include "gimbal/integrators/integrator.hpp"

#include "one_step_integrator.hpp"
#if GIMBAL_WITH_SUNDIALS
#include "sundials_integrator.hpp"
#else
#include <stdexcept>
#endif

namespace gimbal {

std::unique_ptr<HybridIntegrator> HybridIntegrator::create(HybridSystem& system, const IntegratorSettings& settings,
                                                           MessageSink error_sink, MessageSink event_sink) {
    switch (settings.method) {
#if GIMBAL_WITH_SUNDIALS
        case IntegrationMethod::explicit_runge_kutta:
            return make_arkode_backend(system, settings, std::move(error_sink), std::move(event_sink));
        case IntegrationMethod::bdf_analytic_jacobian:
        case IntegrationMethod::bdf_difference_jacobian:
        case IntegrationMethod::adams:
            return make_cvode_backend(system, settings, std::move(error_sink), std::move(event_sink));
#else
        case IntegrationMethod::explicit_runge_kutta:
        case IntegrationMethod::bdf_analytic_jacobian:
        case IntegrationMethod::bdf_difference_jacobian:
        case IntegrationMethod::adams:
            // build_model_parameters refuses these first, with the message the user sees.
            throw std::invalid_argument("solver.method " + std::to_string(static_cast<int>(settings.method)) +
                                        " needs SUNDIALS, which this binary was built without");
#endif
        case IntegrationMethod::automatic:
        case IntegrationMethod::dormand_prince:
        case IntegrationMethod::rosenbrock:
        case IntegrationMethod::real_time:
            break;
    }
    return std::make_unique<OneStepIntegrator>(system, settings, std::move(error_sink), std::move(event_sink));
}

}  // namespace gimbal
