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
    std::copy(run_.reals, run_.reals + kRealVariableCount, snap.reals);
    std::copy(run_.integers, run_.integers + kIntegerVariableCount, snap.integers);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) snap.booleans[vr] = run_.booleans[vr] ? 1 : 0;
    snap.initialized = run_.integrator != nullptr;
    snap.rtol_set = run_.rtol_set;
    snap.master_tolerance_defined = run_.master_tolerance_defined;
    snap.master_tolerance = run_.master_tolerance;
    snap.time = run_.time;
    snap.clock = run_.clock;
    std::copy(run_.state, run_.state + kMaxStateSize, snap.state);
    snap.pending_voltage_rate[0] = run_.voltage_rate[0];
    snap.pending_voltage_rate[1] = run_.voltage_rate[1];
    snap.epoch = run_.epoch;
    snap.integrator_memory = IntegratorMemory{};
    snap.continuous_time = run_.continuous_time;
    snap.decided_here = run_.decided_here;
    std::copy(run_.decided_side, run_.decided_side + kIndicatorCount, snap.decided_side);
    std::copy(run_.reference_guards, run_.reference_guards + kIndicatorCount, snap.reference_guards);
    snap.last_event_time = run_.chattering.last_event_time;
    snap.dwell_until = run_.chattering.dwell_until;
    snap.rapid_events = run_.chattering.rapid_events;
    snap.zeno_holds = run_.zeno_holds;
    if (snap.initialized) save_run(snap);
    encode_snapshot(snap, buffer);
}

// The parts of a snapshot only an initialized instance has: modes, counters, the running inputs and
// the integrator.
void GimbalInstance::save_run(SnapshotContent& snap) {
    snap.modes = run_.system->modes();
    snap.counters = run_.system->counters();
    snap.statistics = run_.integrator->statistics();
    const StepInputs& in = run_.system->inputs();
    for (int axis = 0; axis < 2; ++axis) {
        snap.voltage[axis] = in.voltage[axis];
        snap.commanded_voltage[axis] = in.commanded_voltage[axis];
        snap.voltage_rate[axis] = in.voltage_rate[axis];
        snap.current_command[axis] = in.current_command[axis];
        snap.commanded_current[axis] = in.commanded_current[axis];
    }
    write_base_motion(in.base, snap.base);
    snap.arc_start_time = in.step_start_time;
    snap.at_rest = run_.at_rest;
    if (run_.integrator->resumable()) {
        // The one-step methods carry only their step-size controller: the snapshot holds it, and a
        // restored copy continues exactly as this instance does.
        snap.integrator_running = run_.integrator_running;
        snap.integrator_memory = run_.integrator->memory();
    } else {
        // A multistep method's history does not fit in a snapshot: end the integration segment here,
        // so that this instance and a restored copy both restart the integrator at the next step.
        const IntegratorStatistics totals = run_.integrator->statistics();
        create_integrator();
        run_.integrator->set_statistics(totals);
        snap.integrator_running = false;
    }
}

GimbalStatus GimbalInstance::read_snapshot(const void* buffer, SnapshotContent& snap) const {
    const bool format_ok = decode_snapshot(buffer, snap);
    const std::string reason = check_snapshot_content(snap, format_ok, run_.continuous_time);
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
    ModelSwap swap(model_, model_);
    if (initialized) {
        const GimbalStatus built = rebuild_run(snap, system, integrator);
        if (built != GIMBAL_OK) return built;
    }

    std::copy(snap.reals, snap.reals + kRealVariableCount, run_.reals);
    std::copy(snap.integers, snap.integers + kIntegerVariableCount, run_.integers);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) run_.booleans[vr] = snap.booleans[vr] != 0;
    run_.preview_current = false;
    run_.rtol_set = snap.rtol_set != 0;
    run_.master_tolerance_defined = snap.master_tolerance_defined != 0;
    run_.master_tolerance = snap.master_tolerance;
    run_.time = snap.time;
    run_.epoch = snap.epoch;
    run_.clock = snap.clock;
    std::copy(snap.state, snap.state + kMaxStateSize, run_.state);
    run_.voltage_rate[0] = snap.pending_voltage_rate[0];
    run_.voltage_rate[1] = snap.pending_voltage_rate[1];
    run_.decided_here = snap.decided_here != 0;
    std::copy(snap.decided_side, snap.decided_side + kIndicatorCount, run_.decided_side);
    std::copy(snap.reference_guards, snap.reference_guards + kIndicatorCount, run_.reference_guards);
    run_.chattering.last_event_time = snap.last_event_time;
    run_.chattering.dwell_until = snap.dwell_until;
    run_.chattering.rapid_events = snap.rapid_events;
    run_.zeno_holds = snap.zeno_holds;
    run_.inputs_stale = run_.outputs_stale = true;
    run_.integrator_running = initialized && snap.integrator_running && integrator->resumable();
    run_.at_rest = run_.integrator_running && snap.at_rest;
    swap.commit();
    run_.system = std::move(system);
    run_.integrator = std::move(integrator);
    return GIMBAL_OK;
}

// The hybrid system and the integrator of a checked snapshot's run, the model built from its
// parameters put in place (the caller's ModelSwap puts the previous one back unless it commits).
GimbalStatus GimbalInstance::rebuild_run(const SnapshotContent& snap, std::unique_ptr<GimbalHybridSystem>& system,
                                         std::unique_ptr<HybridIntegrator>& integrator) {
    ModelParameters params;
    std::string error;
    if (!snapshot_parameters(snap, params, error)) return refuse(GIMBAL_ERROR, error);
    model_ = make_instance_model(params);
    system = std::make_unique<GimbalHybridSystem>(model_.params);
    system->hold_inputs_at_any_time(run_.continuous_time);
    StepInputs in;
    for (int axis = 0; axis < 2; ++axis) {
        in.voltage[axis] = snap.voltage[axis];
        in.commanded_voltage[axis] = snap.commanded_voltage[axis];
        in.voltage_rate[axis] = snap.voltage_rate[axis];
        in.current_command[axis] = snap.current_command[axis];
        in.commanded_current[axis] = snap.commanded_current[axis];
    }
    in.base = read_base_motion(snap.base);
    in.step_start_time = snap.arc_start_time;
    system->set_inputs(in);
    system->restore(snap.modes, snap.counters);
    integrator = make_integrator(*system, model_.params);
    if (snap.integrator_running && integrator->resumable() &&
        !integrator->resume(snap.clock, snap.state, snap.integrator_memory)) {
        return refuse(GIMBAL_ERROR, "the integrator cannot continue from the saved state (" +
                                        run_.last_integrator_error + ")");
    }
    integrator->set_statistics(snap.statistics);
    return GIMBAL_OK;
}

}  // namespace gimbal
