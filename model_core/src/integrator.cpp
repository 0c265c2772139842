#include "gimbal/integrator.hpp"

#include "one_step_integrator.hpp"
#include "sundials_integrator.hpp"

namespace gimbal {

std::unique_ptr<HybridIntegrator> HybridIntegrator::create(HybridSystem& system, const IntegratorSettings& settings,
                                                           MessageSink error_sink, MessageSink event_sink) {
    switch (settings.method) {
        case IntegrationMethod::explicit_runge_kutta:
            return make_arkode_backend(system, settings, std::move(error_sink), std::move(event_sink));
        case IntegrationMethod::bdf_analytic_jacobian:
        case IntegrationMethod::bdf_difference_jacobian:
        case IntegrationMethod::adams:
            return make_cvode_backend(system, settings, std::move(error_sink), std::move(event_sink));
        case IntegrationMethod::automatic:
        case IntegrationMethod::dormand_prince:
        case IntegrationMethod::rosenbrock:
            break;
    }
    return std::make_unique<OneStepIntegrator>(system, settings, std::move(error_sink), std::move(event_sink));
}

}  // namespace gimbal
