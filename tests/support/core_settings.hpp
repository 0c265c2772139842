// What the C++ tests that build a GimbalCore from values share: the logger that keeps the last refusal
// (and prints every message when $GIMBAL_TEST_LOG is set), the settings of the C API's three value types,
// and the integration methods' names in IntegrationMethod's order.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

#include "gimbal/gimbal_c_api.h"
#include "gimbal/model/variables.hpp"

namespace core_settings {

inline std::string last_error;

inline void record(void*, GimbalStatus status, const char*, const char* message) {
    if (status >= GIMBAL_DISCARD) last_error = message;
    if (std::getenv("GIMBAL_TEST_LOG")) std::fprintf(stderr, "[%d] %s\n", status, message);
}
inline int always(void*, const char*) { return 1; }

struct Setting {
    GimbalType type;
    unsigned vr;
    double value;
};
inline Setting real(gimbal::RealVariable vr, double value) { return {GIMBAL_REAL, static_cast<unsigned>(vr), value}; }
inline Setting integer(gimbal::IntegerVariable vi, int value) {
    return {GIMBAL_INTEGER, static_cast<unsigned>(vi), double(value)};
}
inline Setting flag(gimbal::BooleanVariable vb, bool value) {
    return {GIMBAL_BOOLEAN, static_cast<unsigned>(vb), value ? 1.0 : 0.0};
}

inline const char* const kMethodNames[] = {"CVODE BDF", "CVODE BDF (dq)", "CVODE Adams", "ARKODE ERK",
                                           "automatic", "Dormand-Prince", "RODAS4",      "real time"};

}  // namespace core_settings
