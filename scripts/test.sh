#!/usr/bin/env bash
# Install what is missing, build, and run every test: C++ through CTest, Python through pytest,
# then the same again on an AddressSanitizer + UndefinedBehaviorSanitizer build
# (set GIMBAL_SKIP_SANITIZERS=1 to skip that second pass on a quick local run).
# pytest runs the test files on GIMBAL_TEST_JOBS processes (default: one per core), a file's tests
# together in one process (--dist loadfile: a file's module fixtures, its Dask cluster, are built once).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${GIMBAL_BUILD_DIR:-$repo/build}"
test_jobs="${GIMBAL_TEST_JOBS:-$(nproc)}"
parallel=(-n "$test_jobs" --dist loadfile)
# The tests that build an FMU from its sources/ (fmpy's build: CMake) use every core too.
export CMAKE_BUILD_PARALLEL_LEVEL="${CMAKE_BUILD_PARALLEL_LEVEL:-$test_jobs}"
bash "$repo/scripts/setup.sh"
cd "$repo"

if [ "${GIMBAL_SKIP_SANITIZERS:-0}" != "1" ]; then
  asan_dir="${build_dir}-asan"
  echo "[test] sanitizer build in $asan_dir"
  cmake -S "$repo" -B "$asan_dir" -G Ninja -DGIMBAL_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DPython3_EXECUTABLE="$repo/.venv/bin/python" >/dev/null
  cmake --build "$asan_dir"
  # Python itself leaks by design: leak checking would only report the interpreter.
  export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  ctest --test-dir "$asan_dir" --output-on-failure --parallel "$test_jobs"
  # Left out here, by their markers (registered in pyproject.toml, tests/README.md): the tests whose time
  # goes to Python (python_bound: analysis, reports, documentation, layout and build checks, the command's
  # messages, the independent reference solution), to Dask worker processes (dask_workers: sweeps,
  # tuning), or that run under an address-space limit (memory_limit: RLIMIT_AS, which AddressSanitizer's
  # shadow memory cannot live under). They run in the release pass below, and the native code they call
  # runs here in the other tests.
  # libstdc++ is preloaded too: ASan's exception interceptor must find it at start-up, and Python
  # only loads it later (with matplotlib's C++ extensions, which throw).
  LD_PRELOAD="$(gcc -print-file-name=libasan.so):$(gcc -print-file-name=libstdc++.so)" \
    GIMBAL_BUILD_DIR="$asan_dir" GIMBAL_SANITIZED=1 \
    "$repo/.venv/bin/python" -m pytest tests -q -p no:cacheprovider "${parallel[@]}" \
    -m "not python_bound and not dask_workers and not memory_limit"
  unset ASAN_OPTIONS UBSAN_OPTIONS
  echo "[test] sanitizer pass clean; now the release build"
fi

ctest --test-dir "$build_dir" --output-on-failure --parallel "$test_jobs"
GIMBAL_BUILD_DIR="$build_dir" "$repo/.venv/bin/python" -m pytest tests "${parallel[@]}" "$@"
