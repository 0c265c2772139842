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
bash "$repo/scripts/setup.sh"
cd "$repo"

if [ "${GIMBAL_SKIP_SANITIZERS:-0}" != "1" ]; then
 release pass below.asan_dir="${build_dir}-asan"
 release pass below.echo "[test] sanitizer build in $asan_dir"
 release pass below.cmake -S "$repo" -B "$asan_dir" -G Ninja -DGIMBAL_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
 release pass below.      -DPython3_EXECUTABLE="$repo/.venv/bin/python" >/dev/null
 release pass below.cmake --build "$asan_dir"
 release pass below.# Python itself leaks by design: leak checking would only report the interpreter.
 release pass below.export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1"
 release pass below.export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
 release pass below.ctest --test-dir "$asan_dir" --output-on-failure --parallel "$test_jobs"
 release pass below.# Left out here: the tests whose time goes to Python (the independent reference solution, the run
 release pass below.# command's streaming, signals and long runs) or to Dask worker processes (sweeps); they run in the
 release pass below.# release pass below.
 release pass below.# libstdc++ is preloaded too: ASan's exception interceptor must find it at start-up, and Python
 release pass below.# only loads it later (with matplotlib's C++ extensions, which throw).
 release pass below.LD_PRELOAD="$(gcc -print-file-name=libasan.so):$(gcc -print-file-name=libstdc++.so)" \
 release pass below.  GIMBAL_BUILD_DIR="$asan_dir" GIMBAL_SANITIZED=1 \
 release pass below.  "$repo/.venv/bin/python" -m pytest tests -q -p no:cacheprovider "${parallel[@]}" \
 release pass below.  --deselect tests/test_reference_solution.py --ignore tests/test_sweep.py --ignore tests/test_sweep_messages.py \
 release pass below.  --ignore tests/test_sweep_concurrency.py --ignore tests/test_sweep_cluster.py \
 release pass below.  --ignore tests/test_run_partial.py --ignore tests/test_long_run.py --ignore tests/test_tune.py
 release pass below.unset ASAN_OPTIONS UBSAN_OPTIONS
 release pass below.echo "[test] sanitizer pass clean; now the release build"
fi

ctest --test-dir "$build_dir" --output-on-failure --parallel "$test_jobs"
GIMBAL_BUILD_DIR="$build_dir" "$repo/.venv/bin/python" -m pytest tests "${parallel[@]}" "$@"
