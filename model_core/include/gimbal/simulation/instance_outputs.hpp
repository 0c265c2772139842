// Publishing an instance's outputs (simulation/instance_outputs.cpp): the output variables at one
// point of a run, and the 19 continuous states and their derivatives in full form whatever the
// fidelity (a state a reduced model does not integrate is computed from the others).
#pragma once

#include <cstdint>

#include "gimbal/hybrid_system/gimbal_hybrid_system.hpp"
#include "gimbal/integrators/integrator.hpp"
#include "gimbal/model/variables.hpp"

namespace gimbal {

// The point the outputs are published at.
struct OutputPoint {
    const ModelParameters& params;
    GimbalHybridSystem& system;  // its modes, inputs and counters; evaluated at (clock, state)
    const HybridIntegrator& integrator;  // its statistics
    const double* state;
    double clock;              // model time
    double epoch;              // the host's time at clock 0
    std::int64_t zeno_holds;   // the continuous-time interface's chattering holds (the integrator counts its own)
};

// Writes every calculated output of the model (not the states' derivatives alone: angles, currents,
// torques, energies, modes, event counters, solver statistics).
void publish_outputs(const OutputPoint& point, double (&reals)[kRealVariableCount],
                     int (&integers)[kIntegerVariableCount]);

// The 19 continuous states (kContinuousStateCount) in full form, and their derivatives from the integrated ones'.
void full_state_vector(const ModelParameters& params, const Dynamics& dynamics, const double* state, double* states);
void full_state_derivative(const ModelParameters& params, const Modes& modes, const Dynamics& dynamics,
                           const double* derivative, double* out);

// Currents within their limits and backlash angles within their play: between a host's step that
// overshoots a stop or a limit and the event update that projects the state back, the outputs
// already show the physical values.
void clamp_published_to_bounds(const ModelParameters& params, double (&reals)[kRealVariableCount]);

}  // namespace gimbal
