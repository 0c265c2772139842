// GimbalInstance's FMU state: what it saves, and a checked snapshot restored. The bytes, their checks
// and the table of fields they come from are snapshot.cpp's; here is only where each value lives in
// an instance.
#include <algorithm>
#include <cstring>
#include <memory>
#include <string>

#include "gimbal/simulation/gimbal_instance.hpp"
#include "gimbal/simulation/parameter_swap.hpp"
#include "gimbal/simulation/snapshot.hpp"
#include "gimbal/simulation/step_inputs.hpp"

namespace gimbal {

std::size_t GimbalInstance::snapshot_size() { return snapshot_bytes(); }

void GimbalInstance::save(void* buffer) {
    SnapshotContent snap;
    std::memset(static_cast<void*>(&snap), 0, sizeof snap);
    std::copy(reals_, reals_ + kRealVariableCount, snap.reals);
    std::copy(integers_, integers_ + kIntegerVariableCount, snap.integers);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) snap.booleans[vr] = booleans_[vr] ? 1 : 0;
    snap.initialized = integrator_ != nullptr;
    snap.rtol_set = rtol_set_;
    snap.master_tolerance_defined = master_tolerance_defined_;
    snap.master_tolerance = master_tolerance_;
    snap.time = time_;
    snap.clock = clock_;
    std::copy(state_, state_ + kMaxStateSize, snap.state);
    snap.pending_voltage_rate[0] = voltage_rate_[0];
    snap.pending_voltage_rate[1] = voltage_rate_[1];
    snap.epoch = epoch_;
    snap.integrator_memory = IntegratorMemory{};
    snap.continuous_time = continuous_time_;
    snap.decided_here = decided_here_;
    std::copy(decided_side_, decided_side_ + kIndicatorCount, snap.decided_side);
    std::copy(reference_guards_, reference_guards_ + kIndicatorCount, snap.reference_guards);
    snap.last_event_time = chattering_.last_event_time;
    snap.dwell_until = chattering_.dwell_until;
    snap.rapid_events = chattering_.rapid_events;
    snap.zeno_holds = zeno_holds_;
    if (snap.initialized) save_run(snap);
    encode_snapshot(snap, buffer);
}

// The parts of a snapshot only an initialized instance has: modes, counters, the running inputs and
// the integrator.
void GimbalInstance::save_run(SnapshotContent& snap) {
    snap.modes = system_->modes();
    snap.counters = system_->counters();
    snap.statistics = integrator_->statistics();
    const StepInputs& in = system_->inputs();
    for (int axis = 0; axis < 2; ++axis) {
        snap.voltage[axis] = in.voltage[axis];
        snap.commanded_voltage[axis] = in.commanded_voltage[axis];
        snap.voltage_rate[axis] = in.voltage_rate[axis];
    }
    write_base_motion(in.base, snap.base);
    snap.arc_start_time = in.step_start_time;
    snap.at_rest = at_rest_;
    if (integrator_->resumable()) {
        // The one-step methods carry only their step-size controller: the snapshot holds it, and a
        // restored copy continues exactly as this instance does.
        snap.integrator_running = integrator_running_;
        snap.integrator_memory = integrator_->memory();
    } else {
        // A multistep method's history does not fit in a snapshot: end the integration segment here,
        // so that this instance and a restored copy both restart the integrator at the next step.
        const IntegratorStatistics totals = integrator_->statistics();
        create_integrator();
        integrator_->set_statistics(totals);
        snap.integrator_running = false;
    }
}

GimbalStatus GimbalInstance::read_snapshot(const void* buffer, SnapshotContent& snap) const {
    const bool format_ok = decode_snapshot(buffer, snap);
    const std::string reason = check_snapshot_content(snap, format_ok, continuous_time_);
    if (!reason.empty()) return refuse(GIMBAL_ERROR, "the FMU state is refused: " + reason);
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::check_snapshot(const void* buffer, bool& initialized) const {
    SnapshotContent snap;
    const GimbalStatus status = read_snapshot(buffer, snap);
    if (status != GIMBAL_OK) return status;
    initialized = snap.initialized != 0;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::restore(const void* buffer) {
    SnapshotContent snap;
    const GimbalStatus checked = read_snapshot(buffer, snap);
    if (checked != GIMBAL_OK) return checked;
    const bool initialized = snap.initialized != 0;

    // Everything is built aside first: a refusal (or running out of memory) leaves the instance as it was.
    std::unique_ptr<GimbalHybridSystem> system;
    std::unique_ptr<HybridIntegrator> integrator;
    ParameterSwap swap(params_, params_);
    if (initialized) {
        const GimbalStatus built = rebuild_run(snap, system, integrator);
        if (built != GIMBAL_OK) return built;
    }

    std::copy(snap.reals, snap.reals + kRealVariableCount, reals_);
    std::copy(snap.integers, snap.integers + kIntegerVariableCount, integers_);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) booleans_[vr] = snap.booleans[vr] != 0;
    preview_current_ = false;
    rtol_set_ = snap.rtol_set != 0;
    master_tolerance_defined_ = snap.master_tolerance_defined != 0;
    master_tolerance_ = snap.master_tolerance;
    time_ = snap.time;
    epoch_ = snap.epoch;
    clock_ = snap.clock;
    std::copy(snap.state, snap.state + kMaxStateSize, state_);
    voltage_rate_[0] = snap.pending_voltage_rate[0];
    voltage_rate_[1] = snap.pending_voltage_rate[1];
    decided_here_ = snap.decided_here != 0;
    std::copy(snap.decided_side, snap.decided_side + kIndicatorCount, decided_side_);
    std::copy(snap.reference_guards, snap.reference_guards + kIndicatorCount, reference_guards_);
    chattering_.last_event_time = snap.last_event_time;
    chattering_.dwell_until = snap.dwell_until;
    chattering_.rapid_events = snap.rapid_events;
    zeno_holds_ = snap.zeno_holds;
    inputs_stale_ = outputs_stale_ = true;
    integrator_running_ = initialized && snap.integrator_running && integrator->resumable();
    at_rest_ = integrator_running_ && snap.at_rest;
    swap.commit();
    if (initialized) map_integrated_states();
    system_ = std::move(system);
    integrator_ = std::move(integrator);
    return GIMBAL_OK;
}

// The hybrid system and the integrator of a checked snapshot's run, its parameters put in place (the
// caller's ParameterSwap puts the previous ones back unless it commits).
GimbalStatus GimbalInstance::rebuild_run(const SnapshotContent& snap, std::unique_ptr<GimbalHybridSystem>& system,
                                         std::unique_ptr<HybridIntegrator>& integrator) {
    ModelParameters params;
    std::string error;
    if (!snapshot_parameters(snap, params, error)) return refuse(GIMBAL_ERROR, error);
    params_ = params;
    system = std::make_unique<GimbalHybridSystem>(params_);
    system->hold_inputs_at_any_time(continuous_time_);
    StepInputs in;
    for (int axis = 0; axis < 2; ++axis) {
        in.voltage[axis] = snap.voltage[axis];
        in.commanded_voltage[axis] = snap.commanded_voltage[axis];
        in.voltage_rate[axis] = snap.voltage_rate[axis];
    }
    in.base = read_base_motion(snap.base);
    in.step_start_time = snap.arc_start_time;
    system->set_inputs(in);
    system->restore(snap.modes, snap.counters);
    integrator = make_integrator(*system, params_);
    if (snap.integrator_running && integrator->resumable() &&
        !integrator->resume(snap.clock, snap.state, snap.integrator_memory)) {
        return refuse(GIMBAL_ERROR, "the integrator cannot continue from the saved state (" +
                                        last_integrator_error_ + ")");
    }
    integrator->set_statistics(snap.statistics);
    return GIMBAL_OK;
}

}  // namespace gimbal
