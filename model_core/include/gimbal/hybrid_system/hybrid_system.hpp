// What a hybrid (mode-switching) system offers an integrator: a right-hand side that is smooth
// within the current modes, event functions whose sign changes mark mode changes, and the mode
// update at an event. Independent of the integrator behind it.
#pragma once

#include <string>

namespace gimbal {

// A state that, under the current modes, relaxes exponentially onto a combination of two others and
// acts on no other state: with s = state[numerator] / divisor - state[subtrahend],
// d(s - state[index])/dt = -rate (s - state[index]) exactly, whatever the rest of the system does. An
// integrator may take it exactly, state[index](t) = s(t) - (s - state[index])(t0) exp(-rate (t - t0)),
// instead of resolving the relaxation with its steps (a gear's shaft end in the free play,
// docs/physics.md section 4.2, whose rate k_s / c_s reaches 1e10 1/s).
struct RelaxingState {
    int index;
    double rate;
    int numerator;
    double divisor;
    int subtrahend;
    double source(const double* state) const { return state[numerator] / divisor - state[subtrahend]; }
};

class HybridSystem {
public:
    virtual ~HybridSystem() = default;
    virtual int state_size() const = 0;
    virtual int event_count() const = 0;
    // dx/dt under the current modes; false if it cannot be evaluated (non-finite values).
    virtual bool derivative(double time, const double* state, double* derivative) = 0;
    // d(dx/dt)/dx under the current modes, column-major (size x size), or false if the system offers
    // none (the integrator then uses difference quotients). It may approximate terms that do not
    // make the system stiff: Newton's method only needs the iteration matrix to be close.
    virtual bool has_jacobian() const { return false; }
    virtual bool jacobian(double time, const double* state, double* column_major) {
        (void)time, (void)state, (void)column_major;
        return false;
    }
    // Pairs of states whose derivative is exactly another state (a coordinate and its rate):
    // position[k]' = state[velocity[k]]. An implicit method may eliminate them first. Returns the count.
    virtual int kinematic_pairs(int* position, int* velocity) const {
        (void)position, (void)velocity;
        return 0;
    }
    // The relaxing states under the current modes (at most kMaxRelaxingStates), written to `out`.
    static constexpr int kMaxRelaxingStates = 4;
    virtual int relaxing_states(RelaxingState* out) const {
        (void)out;
        return 0;
    }
    virtual void event_functions(double time, const double* state, double* values) = 0;
    // Re-selects the modes at `time`. `directions[k]` is +1 / -1 when event function k has just
    // crossed zero upward / downward, 0 otherwise; nullptr when re-selecting after an input change.
    // May project the state onto the new modes' constraints (e.g. theta_b = eta at contact).
    // Returns the number of mode changes.
    virtual int update_modes(double time, double* state, const int* directions) = 0;
    // Whether the right-hand side depends on time explicitly (a Rosenbrock method then needs df/dt).
    virtual bool time_dependent() const { return true; }
    // What the last update_modes switched, named, for the event log ("gear1 backlash: gap -> +eta").
    virtual std::string describe_last_changes() const { return std::string(); }
};

}  // namespace gimbal
