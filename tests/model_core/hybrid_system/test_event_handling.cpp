// The event handling every integration family shares (event_handling.hpp): the chattering guard and
// the settling of guards left exactly on zero, on small systems whose answers are known.
#include <cmath>
#include <string>
#include <vector>

#include "check.hpp"
#include "gimbal/hybrid_system/event_handling.hpp"

using namespace gimbal;

namespace {

// x' = v, v' = -1 + push; one guard g = x with a mode "resting" (push = 1, the floor holds the mass)
// or "free" (push = 0). Deciding "free" at x = 0 makes it fall through the floor (departs below), so
// the settling must see the departure and decide again.
class Floor final : public HybridSystem {
public:
    int state_size() const override { return 2; }
    int event_count() const override { return 1; }
    bool derivative(double, const double* x, double* dx) override {
        dx[0] = x[1];
        dx[1] = resting ? 0.0 : -1.0;
        return true;
    }
    void event_functions(double, const double* x, double* g) override { g[0] = resting ? 1.0 : x[0]; }
    int update_modes(double, double* x, const int* directions) override {
        ++decisions;
        const bool before = resting;
        // Falling onto the floor (crossing downward, or about to) makes it rest there.
        if (directions != nullptr && directions[0] < 0) resting = true, x[0] = 0.0, x[1] = 0.0;
        return before != resting ? 1 : 0;
    }
    std::string describe_last_changes() const override { return resting ? "free -> resting" : ""; }
    bool resting = false;
    int decisions = 0;
};

void chattering_guard_engages_after_the_limit_and_only_then() {
    EventHandlingSettings settings;  // 50 changes, each within 1 ns, hold for 1 us
    std::vector<std::string> said;
    const MessageSink sink = [&said](const std::string& m) { said.push_back(m); };
    ChatteringMemory memory;
    double t = 1.0;
    bool engaged = false;
    int count = 0;
    // The first change starts the run; 50 more within 1 ns each engage the hold.
    for (; count < 60 && !engaged; ++count, t += 0.5e-9) engaged = record_mode_change(memory, settings, t, 0.0, sink);
    CHECK(engaged);
    CHECK(count == settings.zeno_event_limit + 1);
    CHECK(memory.holding());
    CHECK_NEAR(memory.dwell_until, t - 0.5e-9 + settings.zeno_dwell, 1e-15);
    CHECK(said.size() == 1 && said[0].find("chattering") != std::string::npos);
    // Changes further apart than the window never engage it.
    ChatteringMemory spaced;
    bool ever = false;
    for (int k = 0; k < 500; ++k) ever = ever || record_mode_change(spaced, settings, 2.0 + 2e-9 * k, 0.0, sink);
    CHECK(!ever && !spaced.holding());
    // A coarser time resolution widens the window (integrators that cannot tell the times apart).
    ChatteringMemory coarse;
    bool wide = false;
    for (int k = 0; k < 60; ++k) wide = wide || record_mode_change(coarse, settings, 3.0 + 1e-8 * k, 2e-8, sink);
    CHECK(wide);
    // The reported times carry the offset (a host's clock).
    said.clear();
    ChatteringMemory offset;
    for (int k = 0; k < 60; ++k) record_mode_change(offset, settings, 1e-10 * k, 0.0, sink, 100.0);
    CHECK(!said.empty() && said[0].find("t = 100.000000005") == 0);
}

void a_guard_left_on_zero_is_decided_by_where_it_goes() {
    Floor floor;
    EventHandlingSettings settings;
    std::vector<std::string> said;
    const MessageSink sink = [&said](const std::string& m) { said.push_back(m); };
    GuardSettling settling;
    double x[2] = {0.0, -1.0};  // at the floor, moving down, free: it would fall through
    double derivative[2], guards[1];
    int changes = -1;
    const bool ok = settling.settle(
        0.0, x, 2, 1, 1e-6, nullptr, derivative, guards, changes,
        [&](double t, const double* s, double* d) { return floor.derivative(t, s, d); },
        [&](double t, const double* s, double* g) {
            floor.event_functions(t, s, g);
            return true;
        },
        [&](const int* directions) { return switch_modes(floor, 0.0, x, directions, settings, sink, 0.0); });
    CHECK(ok);
    CHECK(floor.resting);            // decided again with the downward departure
    CHECK(changes == 1);
    CHECK(guards[0] == 1.0);          // the resting mode's guard
    CHECK(said.size() == 1 && said[0] == "t = 0: 1 mode change(s): free -> resting");

    // Already decided for the side it leaves to: nothing is decided again, and the zero guard gets
    // that side's sign.
    Floor rising;
    double y[2] = {0.0, 1.0};  // on the floor, moving up
    const int up[1] = {1};
    changes = -1;
    settling.settle(
        0.0, y, 2, 1, 1e-6, up, derivative, guards, changes,
        [&](double t, const double* s, double* d) { return rising.derivative(t, s, d); },
        [&](double t, const double* s, double* g) {
            rising.event_functions(t, s, g);
            return true;
        },
        [&](const int* directions) { return rising.update_modes(0.0, y, directions); });
    CHECK(changes == 0 && rising.decisions == 0 && !rising.resting);
    CHECK(guards[0] > 0.0);

    // A failed evaluation is reported, not settled.
    double z[2] = {0.0, 0.0};
    CHECK(!settling.settle(
        0.0, z, 2, 1, 1e-6, nullptr, derivative, guards, changes, [](double, const double*, double*) { return false; },
        [](double, const double*, double*) { return true; }, [](const int*) { return 0; }));
}

}  // namespace

int main() {
    chattering_guard_engages_after_the_limit_and_only_then();
    a_guard_left_on_zero_is_decided_by_where_it_goes();
    return check_report("event_handling");
}
