#include "gimbal/simulation/step_checks.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace gimbal {

// Fixed L-stable steps damp an oscillation they do not resolve instead of following it; at a gear's
// contact that turns bounces into sticking and, with the contact's onset located only to the
// substep's precision, feeds energy in (docs/real_time.md has the measurements). The contact
// oscillation of each compliant gear, the load against the rotor reflected through N^2, must be
// resolved by the substeps: omega h <= kRealTimeContactResolution.
// An armature whose time constant L/R is far below the substep crosses from one current limit to
// the other, after a voltage jump, inside one substep: RODAS4's step end is right (it is L-stable and
// stiffly accurate), but the limit is then located on its continuous extension, which does not follow
// that transient, and the torque before it is wrong. Measured (docs/real_time.md): L/R = 4e-5 s at a
// 1 ms substep put beta 1.7e-3 rad off, converging at first order in the substeps; from (L/R)/h = 0.12
// on, the method keeps its order. The quasi-static motor is the limit L -> 0 of such a motor.
static bool armatures_resolved(const ModelParameters& params, double step_size, std::string& why) {
    const double substep = step_size / params.substeps;
    double unresolved[2] = {0.0, 0.0};  // the time constant of each armature the substeps do not resolve
    double needed = 0.0;
    for (int axis = 0; axis < 2; ++axis) {
        const MotorParameters& motor = params.motor[axis];
        const double time_constant = motor.inductance / motor.resistance;
        if (params.fidelity.motor[axis] != MotorModel::inductive || !(time_constant < kRealTimeArmatureResolution * substep))
            continue;
        unresolved[axis] = time_constant;
        needed = std::max(needed, std::ceil(kRealTimeArmatureResolution * step_size / time_constant));
    }
    if (needed == 0.0) return true;  // every doStep: nothing formatted
    std::ostringstream s;
    s.precision(4);
    s << "the real-time method cannot resolve ";
    const char* separator = "";
    for (int axis = 0; axis < 2; ++axis) {
        if (unresolved[axis] == 0.0) continue;
        s << separator << "motor" << axis + 1 << "'s armature transient (L/R = " << unresolved[axis]
          << " s at L = " << params.motor[axis].inductance << " H)";
        separator = "; ";
    }
    s << " with substeps of " << substep << " s (L/R at least " << kRealTimeArmatureResolution
      << " substep): a current limit reached within it would be located on an interpolant that does not "
      << "follow it. Set solver.substeps >= " << static_cast<long long>(needed)
      << " for this communication step, or make the motor quasi-static (motor<k>.model = 0, the limit L -> 0)";
    why = s.str();
    return false;
}

bool real_time_resolution_ok(const ModelParameters& params, const Dynamics& dynamics, double step_size,
                             std::string& why) {
    if (!armatures_resolved(params, step_size, why)) return false;
    const double substep = step_size / params.substeps;
    double contact_frequency[2] = {0.0, 0.0};
    double needed = 0.0;
    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params.gear[axis];
        if (params.fidelity.gear[axis] == GearModel::rigid || gear.stiffness == 0.0) continue;
        const double load_inertia = dynamics.reduced_mass(load_index(axis), load_index(axis));
        const double rotor_inertia = dynamics.reduced_mass(rotor_index(axis), rotor_index(axis));
        contact_frequency[axis] =
            std::sqrt(gear.stiffness * (1.0 / load_inertia + 1.0 / (gear.ratio * gear.ratio * rotor_inertia)));
        if (contact_frequency[axis] * substep > kRealTimeContactResolution)
            needed = std::max(needed, std::ceil(contact_frequency[axis] * step_size / kRealTimeContactResolution));
    }
    if (needed == 0.0) return true;  // every doStep: nothing formatted
    std::ostringstream s;
    s.precision(4);
    s << "the real-time method cannot resolve ";
    const char* separator = "";
    for (int axis = 0; axis < 2; ++axis) {
        if (!(contact_frequency[axis] * substep > kRealTimeContactResolution)) continue;
        s << separator << "gear" << axis + 1 << "'s contact oscillation (" << contact_frequency[axis]
          << " rad/s at k_s = " << params.gear[axis].stiffness
          << " N.m/rad: omega h = " << contact_frequency[axis] * substep << ")";
        separator = "; ";
    }
    s << " with substeps of " << substep << " s (omega h at most " << kRealTimeContactResolution
      << "): set solver.substeps >= " << static_cast<long long>(needed)
      << " for this communication step, or make a gear rigid (gear<k>.model = 0) if the scene does not need its shaft";
    why = s.str();
    return false;
}

bool StepWorkMonitor::over_budget(const StepWork& work, const ModelParameters& params, std::string& report) {
    const IntegratorStatistics& before = work.before;
    const IntegratorStatistics& after = work.after;
    const std::int64_t rhs = after.rhs_evaluations - before.rhs_evaluations;
    if (rhs <= kStepWorkBudget) return false;
    ++over_budget_;
    if ((over_budget_ & (over_budget_ - 1)) != 0) return true;
    const std::int64_t steps = after.steps - before.steps, rejected = after.rejected_steps - before.rejected_steps;
    const std::int64_t events = work.events;
    const auto method = static_cast<IntegrationMethod>(params.method);
    std::ostringstream s;
    s.precision(6);
    s << "the step to t = " << work.time << " (h = " << work.step_size << ") took " << rhs
      << " right-hand-side evaluations (budget " << kStepWorkBudget << "), " << steps << " steps, " << rejected
      << " rejected, " << events << " mode changes";
    if (events > steps / 4) {
        s << ". Likely cause: the switching elements change mode " << events
          << " times in one step (backlash impacts of a stiff gear, stick-slip or limiter chatter)";
    } else if (method == IntegrationMethod::dormand_prince || method == IntegrationMethod::explicit_runge_kutta) {
        s << ". Likely cause: the problem is stiff (a stiff gear k_s, a small motor inductance L) and solver.method = "
          << params.method << " is explicit: its steps are held by stability, not accuracy; solver.method = 4 or 6 "
          << "handles stiffness";
    } else if (rejected > steps / 2) {
        s << ". Likely cause: most steps are rejected (discontinuities the integrator has to resolve)";
    } else {
        s << ". Likely cause: solver.rtol = " << params.relative_tolerance << " and solver.atol = "
          << params.absolute_tolerance << " ask for more accuracy than the step affords";
    }
    if (over_budget_ > 1) s << " [" << over_budget_ << " steps over budget so far]";
    report = s.str();
    return true;
}

}  // namespace gimbal
