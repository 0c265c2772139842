// What happens at a mode change, the same whoever integrates: the project's one-step methods, the
// SUNDIALS reference methods (both in the Co-Simulation step) and the host of the continuous-time
// interface (Model Exchange). Each of them finds the event its own way; from there on these decide:
// - switch_modes: the hybrid system re-selects its modes with the crossing directions, logged;
// - GuardSettling: guards left exactly on zero (a state projected onto a stop, a ramp starting on
//   its clamp) get the side they leave to, and the modes are decided once more with it;
// - the chattering guard: a run of mode changes that makes no progress in time holds the modes.
//
// Its settings and the chattering guard's memory live here too, not with the integrators: the host
// of the continuous-time interface uses them without any integrator, and the integrators carry them
// (IntegratorSettings::event_handling, IntegratorMemory::chattering) from this layer below theirs.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "gimbal/hybrid_system/hybrid_system.hpp"

namespace gimbal {

// Where event and error messages go (the FMU's logger, a test's list).
using MessageSink = std::function<void(const std::string&)>;

struct EventHandlingSettings {
    // Chattering guard: this many located roots in a row, each within `zeno_window` seconds of the
    // previous one, freeze the event functions for `zeno_dwell` seconds; modes are then re-selected
    // from the functions' signs. Switches further apart than the window (chatter below 1 GHz) are
    // never affected. Absolute durations: results must not depend on where time starts.
    int zeno_event_limit = 50;
    double zeno_window = 1e-9;
    double zeno_dwell = 1e-6;
    // Whether anyone listens to event messages: they are only formatted (and allocated) if so.
    std::function<bool()> events_logged = [] { return true; };
};

// The chattering guard's memory (record_mode_change).
struct ChatteringMemory {
    double last_event_time = -1e300;
    int rapid_events = 0;
    double dwell_until = -1e300;  // the modes are held before this time
    bool holding() const { return dwell_until > -1e300; }
};

// Re-selects the modes at (time, state) (hybrid_system.hpp, update_modes) and, if any changed and
// someone listens, sends "t = <reported_time>: n mode change(s): what" to the sink.
int switch_modes(HybridSystem& system, double time, double* state, const int* directions,
                 const EventHandlingSettings& settings, const MessageSink& event_sink, double reported_time);

// The chattering guard: settings.zeno_event_limit mode changes in a row, each within
// max(settings.zeno_window, resolution) of the previous one (resolution: how closely the integrator
// tells two event times apart), hold the modes for settings.zeno_dwell.
// Records a mode change at `time`; true when it engages the hold (then memory.dwell_until is set and
// the message says so, with `reported_offset` added to the times it names).
bool record_mode_change(ChatteringMemory& memory, const EventHandlingSettings& settings, double time,
                        double resolution, const MessageSink& event_sink, double reported_offset = 0.0);

// Settles the guards that sit exactly on zero at a point where the modes have just been decided.
// Scratch space of fixed capacity: no allocation on the step path.
class GuardSettling {
public:
    static constexpr int kMaxStates = 24;
    static constexpr int kMaxGuards = 64;

    // At (time, state): evaluates the derivative into `derivative` and the guards into `guards`. A guard
    // exactly at zero has no sign to change: the side it departs to, seen `lookahead` ahead along the
    // derivative, is where it goes, and where the modes were decided blind to that side (or for the
    // other one), they are decided again with it (once). Then each zero guard is replaced by a value
    // of the side decided, so that a return to zero within the next step is seen as a crossing.
    // `decided[k]`: +1 / -1 when the event just decided guard k for that side, else 0 (nullptr: none).
    // evaluate(time, state, derivative) and guards_at(time, state, guards) return false on failure;
    // decide(directions) re-selects the modes and returns the number of changes. Returns false on a
    // failed evaluation; `changes` counts the changes it made.
    template <class Evaluate, class GuardsAt, class Decide>
    bool settle(double time, double* state, int state_size, int guard_count, double lookahead, const int* decided,
                double* derivative, double* guards, int& changes, Evaluate&& evaluate, GuardsAt&& guards_at,
                Decide&& decide) {
        changes = 0;
        for (int k = 0; k < guard_count; ++k) decided_side_[k] = decided != nullptr ? decided[k] : 0;
        for (int round = 0;; ++round) {
            if (!evaluate(time, state, derivative)) return false;
            if (!guards_at(time, state, guards)) return false;
            bool on_surface = false;
            for (int k = 0; k < guard_count; ++k) on_surface = on_surface || guards[k] == 0.0;
            if (!on_surface) return true;
            for (int i = 0; i < state_size; ++i) ahead_state_[i] = state[i] + lookahead * derivative[i];
            if (!guards_at(time + lookahead, ahead_state_, ahead_)) return false;
            if (round == 0) {
                bool departs = false;
                for (int k = 0; k < guard_count; ++k) {
                    directions_[k] = 0;
                    if (guards[k] != 0.0 || ahead_[k] == 0.0) continue;
                    const int departure = ahead_[k] > 0.0 ? 1 : -1;
                    // Decided for the side it now leaves to (a bounce's reset, a ramp leaving the clamp):
                    // nothing to do. Undecided, or decided for the other side: decide again with it.
                    if (decided_side_[k] == departure) continue;
                    directions_[k] = departure;
                    decided_side_[k] = departure;
                    departs = true;
                }
                if (departs) {
                    const int more = decide(directions_);
                    changes += more;
                    if (more > 0) continue;  // new modes: evaluate again under them
                }
            }
            // The baseline is the side the modes were decided for: if the modes push the guard back
            // across (a sliding surface), the next step sees that crossing and the chattering guard
            // deals with it, instead of the guard leaving on the wrong side unseen.
            for (int k = 0; k < guard_count; ++k) {
                if (guards[k] != 0.0) continue;
                const double size = ahead_[k] != 0.0 ? std::fabs(ahead_[k]) : std::numeric_limits<double>::min();
                guards[k] = decided_side_[k] != 0 ? std::copysign(size, static_cast<double>(decided_side_[k])) : ahead_[k];
            }
            return true;
        }
    }

private:
    double ahead_state_[kMaxStates];
    double ahead_[kMaxGuards];
    int decided_side_[kMaxGuards];
    int directions_[kMaxGuards];
};

}  // namespace gimbal
