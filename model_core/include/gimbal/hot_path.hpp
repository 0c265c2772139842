// GIMBAL_HOT_PART marks a helper split out of a function on the doStep path for reading (one job
// each), defined in the same source file and called from there only: it is forced back inline, so
// that the split costs no call per step (measured with callgrind, docs/benchmarks.md).
#pragma once

#if defined(__GNUC__) || defined(__clang__)
#define GIMBAL_HOT_PART inline __attribute__((always_inline))
#else
#define GIMBAL_HOT_PART inline
#endif
