#include "gimbal/hybrid_system/event_handling.hpp"

#include <sstream>

namespace gimbal {

int switch_modes(HybridSystem& system, double time, double* state, const int* directions,
                 const EventHandlingSettings& settings, const MessageSink& event_sink, double reported_time) {
    const int changes = system.update_modes(time, state, directions);
    if (changes > 0 && settings.events_logged()) {
        std::ostringstream s;
        s.precision(17);
        s << "t = " << reported_time << ": " << changes << " mode change(s)";
        const std::string what = system.describe_last_changes();
        if (!what.empty()) s << ": " << what;
        event_sink(s.str());
    }
    return changes;
}

bool record_mode_change(ChatteringMemory& memory, const EventHandlingSettings& settings, double time,
                        double resolution, const MessageSink& event_sink, double reported_offset) {
    const double window = std::max(settings.zeno_window, resolution);
    memory.rapid_events = time - memory.last_event_time <= window ? memory.rapid_events + 1 : 0;
    memory.last_event_time = time;
    if (memory.rapid_events < settings.zeno_event_limit) return false;
    memory.dwell_until = time + settings.zeno_dwell;
    memory.rapid_events = 0;
    if (settings.events_logged()) {
        std::ostringstream s;
        s.precision(17);
        s << "t = " << reported_offset + time << ": " << settings.zeno_event_limit
          << " events without progress in time (chattering); modes held until t = "
          << reported_offset + memory.dwell_until;
        event_sink(s.str());
    }
    return true;
}

}  // namespace gimbal
