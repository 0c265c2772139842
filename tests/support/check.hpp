// Minimal checking for the C++ unit tests: report every failed expectation, exit non-zero if any.
#pragma once

#include <cstdio>

namespace check {
inline int failures = 0;
}

#define CHECK(condition)                                                                   \
    do {                                                                                   \
        if (!(condition)) {                                                                \
            std::fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #condition); \
            ++check::failures;                                                             \
        }                                                                                  \
    } while (0)

#define CHECK_NEAR(a, b, tolerance)                                                                          \
    do {                                                                                                     \
        const double check_a = (a), check_b = (b);                                                           \
        if (!(std::fabs(check_a - check_b) <= (tolerance))) {                                                \
            std::fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.17g, %s = %.17g\n", __FILE__, __LINE__, #a, \
                         check_a, #b, check_b);                                                              \
            ++check::failures;                                                                               \
        }                                                                                                    \
    } while (0)

inline int check_report(const char* suite) {
    std::printf("%s: %s (%d failed checks)\n", suite, check::failures == 0 ? "passed" : "FAILED", check::failures);
    return check::failures == 0 ? 0 : 1;
}
