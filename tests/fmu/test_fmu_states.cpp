// FMU states from the host's side, as hostile or careless importers hand them over:
//
//   test_fmu_states <Gimbal2Axis.so> <modelDescription.xml>
//
// - pointers that are not this instance's states (FMI4j's uninitialised fmi2FMUstate into
//   fmi2GetFMUstate, fmusim's state-instead-of-its-address into fmi2FreeFMUstate, stale, foreign
//   and garbage pointers) are refused or replaced, never dereferenced;
// - serialized blobs that were altered are refused with a logged reason: every single-bit flip of a
//   real blob, every truncation, random payloads, crafted headers with a valid checksum, huge size
//   claims; blobs whose payload words were overwritten (checksum recomputed, as an attacker would)
//   are refused or, if they decode to a possible state, run without a crash;
// - after every refusal the instance is where it was: its next step gives the same bits as before.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "check.hpp"
#include "fmu_loader.hpp"

extern "C" {
#include "fmi_layer/fmu_state.h"
}

namespace {

using fmu_loader::Api;
using fmu_loader::Log;
using fmu_loader::ModelDescription;

Api api;
ModelDescription model;

const char* const kOutputs[] = {"alpha", "alpha_m", "beta", "beta_m", "alpha_dot", "beta_dot", "i_R1", "i_R2",
                                "theta_b1", "theta_b2", "T_E2"};

struct Instance {
    Log log;
    fmi2CallbackFunctions callbacks;
    fmi2Component component = nullptr;

    explicit Instance(const char* name) : callbacks(fmu_loader::callbacks_for(log)) {
        component = api.instantiate(name, fmi2CoSimulation, model.guid.c_str(), "file:///tmp", &callbacks, fmi2False,
                                    fmi2False);
    }
    ~Instance() { api.freeInstance(component); }

    void set(const char* name, double value) {
        const fmi2ValueReference vr = model.vr(name);
        CHECK(api.setReal(component, &vr, 1, &value) == fmi2OK);
    }

    // Initialized, with voltages that drive both gears through their backlash: the state then holds
    // contact modes, event counters and a running step-size controller.
    void start(double steps) {
        CHECK(api.setupExperiment(component, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK);
        CHECK(api.enterInitializationMode(component) == fmi2OK);
        set("u_R1", 2.0);
        set("u_R2", -1.5);
        CHECK(api.exitInitializationMode(component) == fmi2OK);
        for (int k = 0; k < steps; ++k) step();
    }

    double time = 0.0;
    void step() {
        CHECK(api.doStep(component, time, 1e-3, fmi2True) == fmi2OK);
        time += 1e-3;
    }

    std::vector<double> outputs() {
        std::vector<double> values;
        for (const char* name : kOutputs) {
            const fmi2ValueReference vr = model.vr(name);
            double value = NAN;
            CHECK(api.getReal(component, &vr, 1, &value) == fmi2OK);
            values.push_back(value);
        }
        return values;
    }

    std::vector<char> serialize(fmi2FMUstate state) {
        size_t size = 0;
        CHECK(api.serializedFMUstateSize(component, state, &size) == fmi2OK);
        std::vector<char> blob(size);
        CHECK(api.serializeFMUstate(component, state, blob.data(), size) == fmi2OK);
        return blob;
    }
};

// The outputs one step after the instance's current point, leaving the instance at that point.
std::vector<double> next_step_outputs(Instance& instance) {
    fmi2FMUstate here = nullptr;
    CHECK(api.getFMUstate(instance.component, &here) == fmi2OK);
    const double time = instance.time;
    instance.step();
    std::vector<double> values = instance.outputs();
    CHECK(api.setFMUstate(instance.component, here) == fmi2OK);
    instance.time = time;
    CHECK(api.freeFMUstate(instance.component, &here) == fmi2OK);
    return values;
}

void reseal(std::vector<char>& blob) {
    const uint64_t checksum = fmu_state_checksum(reinterpret_cast<const unsigned char*>(blob.data()), blob.size());
    std::memcpy(blob.data() + offsetof(StateHeader, checksum), &checksum, sizeof checksum);
}

// A refused fmi2DeSerializeFMUstate: fmi2Error, a logged reason, and no state handed out.
bool refused(Instance& instance, const std::vector<char>& blob, size_t size, const char* reason = nullptr) {
    instance.log.clear();
    fmi2FMUstate state = nullptr;
    const fmi2Status status = api.deSerializeFMUstate(instance.component, blob.data(), size, &state);
    const bool ok = status == fmi2Error && state == nullptr && !instance.log.messages.empty() &&
                    instance.log.messages.back().first == fmi2Error &&
                    instance.log.last_contains("fmi2DeSerializeFMUstate") &&
                    (reason == nullptr || instance.log.last_contains(reason));
    if (!ok) {
        std::fprintf(stderr, "  not refused as expected (status %d, expected reason '%s'): %s\n", static_cast<int>(status),
                     reason != nullptr ? reason : "any", instance.log.last().c_str());
        if (state != nullptr) api.freeFMUstate(instance.component, &state);
    }
    return ok;
}

void test_host_pointers_are_looked_up_not_trusted() {
    Instance instance("pointers"), other("other");
    instance.start(20);
    other.start(5);

    // FMI4j: an uninitialised fmi2FMUstate. It must be replaced by a new state, not read or freed.
    fmi2FMUstate garbage = reinterpret_cast<fmi2FMUstate>(static_cast<uintptr_t>(0xdeadbeefdeadbeefULL));
    CHECK(api.getFMUstate(instance.component, &garbage) == fmi2OK);
    CHECK(garbage != reinterpret_cast<fmi2FMUstate>(static_cast<uintptr_t>(0xdeadbeefdeadbeefULL)));
    fmi2FMUstate state = garbage;

    // Even a pointer to a perfect copy of a state is not one of this instance's states.
    std::vector<char> copy = instance.serialize(state);
    fmi2FMUstate imitation = copy.data();
    CHECK(api.getFMUstate(instance.component, &imitation) == fmi2OK);
    CHECK(imitation != copy.data());
    CHECK(api.freeFMUstate(instance.component, &imitation) == fmi2OK && imitation == nullptr);
    instance.log.clear();
    CHECK(api.setFMUstate(instance.component, copy.data()) == fmi2Error);
    CHECK(instance.log.last_contains("is not an FMU state of instance 'pointers'"));

    // fmusim: the state where its address is expected.
    instance.log.clear();
    CHECK(api.freeFMUstate(instance.component, reinterpret_cast<fmi2FMUstate*>(state)) == fmi2Error);
    CHECK(instance.log.last_contains("not the address of one"));
    CHECK(api.setFMUstate(instance.component, state) == fmi2OK);  // still a valid state

    // Garbage, another instance's state, and a freed one, in every function that takes a state.
    fmi2FMUstate foreign = nullptr;
    CHECK(api.getFMUstate(other.component, &foreign) == fmi2OK);
    fmi2FMUstate freed = nullptr;
    CHECK(api.getFMUstate(instance.component, &freed) == fmi2OK);
    fmi2FMUstate stale = freed;
    CHECK(api.freeFMUstate(instance.component, &freed) == fmi2OK && freed == nullptr);
    char stack_bytes[64] = {};
    for (fmi2FMUstate bad : {static_cast<fmi2FMUstate>(stack_bytes), foreign, stale,
                             reinterpret_cast<fmi2FMUstate>(static_cast<uintptr_t>(0x10))}) {
        size_t size = 0;
        char buffer[16];
        instance.log.clear();
        CHECK(api.setFMUstate(instance.component, bad) == fmi2Error);
        CHECK(api.serializedFMUstateSize(instance.component, bad, &size) == fmi2Error && size == 0);
        CHECK(api.serializeFMUstate(instance.component, bad, buffer, sizeof buffer) == fmi2Error);
        fmi2FMUstate alias = bad;
        CHECK(api.freeFMUstate(instance.component, &alias) == fmi2Error && alias == bad);
        CHECK(instance.log.messages.size() == 4);
        for (const auto& message : instance.log.messages) CHECK(message.first == fmi2Error);
    }
    // The foreign state still belongs to its instance.
    CHECK(api.setFMUstate(other.component, foreign) == fmi2OK);
    CHECK(api.freeFMUstate(other.component, &foreign) == fmi2OK);

    // Reuse of a state this instance handed out (allowed by the standard) overwrites it in place.
    fmi2FMUstate reused = state;
    instance.step();
    CHECK(api.getFMUstate(instance.component, &reused) == fmi2OK && reused == state);
    CHECK(api.freeFMUstate(instance.component, &state) == fmi2OK);
    // States left behind are freed with the instance (the sanitizer pass would see a leak or a
    // double free).
    fmi2FMUstate left = nullptr;
    CHECK(api.getFMUstate(instance.component, &left) == fmi2OK);
}

void test_altered_blobs_are_refused() {
    Instance instance("blobs");
    instance.start(60);
    fmi2FMUstate saved = nullptr;
    CHECK(api.getFMUstate(instance.component, &saved) == fmi2OK);
    const std::vector<char> blob = instance.serialize(saved);
    CHECK(api.freeFMUstate(instance.component, &saved) == fmi2OK);
    const std::vector<double> expected = next_step_outputs(instance);
    auto still_where_it_was = [&] { CHECK(next_step_outputs(instance) == expected); };

    // The blob itself is accepted and continues bit for bit.
    {
        fmi2FMUstate state = nullptr;
        CHECK(api.deSerializeFMUstate(instance.component, blob.data(), blob.size(), &state) == fmi2OK);
        CHECK(api.setFMUstate(instance.component, state) == fmi2OK);
        CHECK(api.freeFMUstate(instance.component, &state) == fmi2OK);
        still_where_it_was();
    }

    long flips = 0, flips_refused = 0;
    for (size_t bit = 0; bit < 8 * blob.size(); ++bit) {
        std::vector<char> flipped = blob;
        flipped[bit / 8] = static_cast<char>(flipped[bit / 8] ^ (1 << (bit % 8)));
        ++flips;
        if (refused(instance, flipped, flipped.size())) ++flips_refused;
        if (bit % 4096 == 0) still_where_it_was();
    }
    CHECK(flips_refused == flips);

    long truncations_refused = 0;
    for (size_t size = 0; size < blob.size(); ++size) truncations_refused += refused(instance, blob, size, "size");
    CHECK(truncations_refused == static_cast<long>(blob.size()));
    std::vector<char> longer = blob;
    longer.resize(2 * blob.size());
    CHECK(refused(instance, longer, blob.size() + 1, "size"));
    CHECK(refused(instance, longer, longer.size(), "size"));
    // A size claim far beyond the buffer is refused before a byte is read.
    CHECK(refused(instance, blob, SIZE_MAX, "size"));
    CHECK(refused(instance, blob, size_t{1} << 40, "size"));
    still_where_it_was();

    // Random payloads: raw, and with a valid header and checksum.
    std::mt19937_64 random(20261122);
    long random_refused = 0;
    for (int k = 0; k < 500; ++k) {
        std::vector<char> payload(blob.size());
        for (char& byte : payload) byte = static_cast<char>(random());
        random_refused += refused(instance, payload, payload.size());
        std::memcpy(payload.data(), blob.data(), sizeof(StateHeader));
        reseal(payload);
        random_refused += refused(instance, payload, payload.size(), "refused");
    }
    CHECK(random_refused == 1000);
    still_where_it_was();

    // Crafted headers with a valid checksum.
    struct Craft {
        const char* what;
        void (*apply)(StateHeader&);
        const char* reason;
    };
    const Craft crafts[] = {
        {"state 0", [](StateHeader& h) { h.state = 0; }, "instance state"},
        {"two states", [](StateHeader& h) { h.state = 4 | 8; }, "instance state"},
        {"error state", [](StateHeader& h) { h.state = 32; }, "instance state"},
        {"unknown state", [](StateHeader& h) { h.state = 1 << 20; }, "instance state"},
        {"negative state", [](StateHeader& h) { h.state = -4; }, "instance state"},
        {"instantiated, initialized model", [](StateHeader& h) { h.state = 1; }, "contradicts"},
        {"stop-time flag 2", [](StateHeader& h) { h.stop_time_defined = 2; }, "stop-time flag"},
        {"status 7", [](StateHeader& h) { h.last_step_status = 7; }, "status"},
        {"status -1", [](StateHeader& h) { h.last_step_status = -1; }, "status"},
        {"time NaN", [](StateHeader& h) { h.time = NAN; }, "not finite"},
        {"time inf", [](StateHeader& h) { h.last_successful_time = INFINITY; }, "not finite"},
        {"beyond stop time", [](StateHeader& h) { h.stop_time_defined = 1, h.stop_time = h.time - 1.0; }, "stop time"},
        {"huge recorded size", [](StateHeader& h) { h.size = uint64_t{1} << 62; }, "recorded size"},
        {"other version", [](StateHeader& h) { h.format_version += 1; }, "version"},
        {"other GUID", [](StateHeader& h) { h.guid[1] ^= 1; }, "GUID"},
        {"unterminated GUID", [](StateHeader& h) { std::memset(h.guid, 'x', sizeof h.guid); }, "GUID"},
    };
    for (const Craft& craft : crafts) {
        std::vector<char> crafted = blob;
        StateHeader header;
        std::memcpy(&header, crafted.data(), sizeof header);
        craft.apply(header);
        std::memcpy(crafted.data(), &header, sizeof header);
        reseal(crafted);
        if (!refused(instance, crafted, crafted.size(), craft.reason)) std::fprintf(stderr, "  craft: %s\n", craft.what);
    }
    still_where_it_was();

    // Payload words overwritten as an attacker would (checksum recomputed): all-ones (NaN, -1, 0xff
    // flags) and NaN in every 8-byte word of the core's snapshot. Refused, or a possible state that
    // then runs cleanly: finite outputs, or a clean refusal of the step.
    long overwritten = 0, overwritten_refused = 0, accepted_ran = 0;
    for (uint64_t pattern : {~uint64_t{0}, uint64_t{0x7ff8000000000000ULL}}) {
        for (size_t offset = sizeof(StateHeader); offset + 8 <= blob.size(); offset += 8) {
            std::vector<char> crafted = blob;
            std::memcpy(crafted.data() + offset, &pattern, 8);
            reseal(crafted);
            ++overwritten;
            instance.log.clear();
            fmi2FMUstate state = nullptr;
            if (api.deSerializeFMUstate(instance.component, crafted.data(), crafted.size(), &state) != fmi2OK) {
                CHECK(state == nullptr && instance.log.last_contains("refused"));
                ++overwritten_refused;
                continue;
            }
            Instance runner("runner");
            std::vector<char> bytes = crafted;
            fmi2FMUstate moved = nullptr;
            CHECK(api.deSerializeFMUstate(runner.component, bytes.data(), bytes.size(), &moved) == fmi2OK);
            if (api.setFMUstate(runner.component, moved) == fmi2OK) {
                StateHeader header;
                std::memcpy(&header, crafted.data(), sizeof header);
                runner.time = header.time;
                bool finite = true;
                for (int k = 0; k < 3; ++k) {
                    const fmi2Status status = api.doStep(runner.component, runner.time, 1e-3, fmi2True);
                    CHECK(status == fmi2OK || status == fmi2Warning || status == fmi2Discard || status == fmi2Error);
                    if (status != fmi2OK && status != fmi2Warning) break;
                    runner.time += 1e-3;
                    for (double value : runner.outputs()) finite = finite && std::isfinite(value);
                }
                CHECK(finite);
            }
            api.freeFMUstate(runner.component, &moved);
            api.freeFMUstate(instance.component, &state);
            ++accepted_ran;
        }
    }
    still_where_it_was();
    std::printf("  %ld single-bit flips refused of %ld; %zu truncations and 4 oversize claims refused; 1000 random "
                "payloads refused; %zu crafted headers; %ld of %ld overwritten payload words refused, %ld accepted "
                "as possible states and ran cleanly\n",
                flips_refused, flips, blob.size(), sizeof crafts / sizeof crafts[0], overwritten_refused, overwritten,
                accepted_ran);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s <fmu.so> <modelDescription.xml>\n", argv[0]);
        return 2;
    }
    if (!model.read(argv[2]) || !api.load(argv[1])) return 2;
    test_host_pointers_are_looked_up_not_trusted();
    test_altered_blobs_are_refused();
    return check_report("fmu_states");
}
