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
  # Left out here: the tests whose time goes to Python (the independent reference solution, the run
  # command's streaming, signals, failure paths and long runs, the fuzzing of the input files under a
  # memory limit (RLIMIT_AS, which AddressSanitizer's shadow memory cannot live under), the input bounds, the sensors page's comparison of 36 runs: 369 s under the
  # sanitizers; the README's commands and the reports, the notebook, the symbolic derivation, the
  # 40-MB scene key, the gyro's Allan deviations, the target geometry in numpy; the documentation,
  # layout and build checks; the command line's messages, exit statuses and progress; the frequency
  # responses' and spectra's analysis, whose simulations the FMU tests here run alike), or to Dask
  # worker processes (sweeps, tuning); they run in the release pass below, and the native code they
  # call runs here in the other tests.
  # libstdc++ is preloaded too: ASan's exception interceptor must find it at start-up, and Python
  # only loads it later (with matplotlib's C++ extensions, which throw).
  LD_PRELOAD="$(gcc -print-file-name=libasan.so):$(gcc -print-file-name=libstdc++.so)" \
    GIMBAL_BUILD_DIR="$asan_dir" GIMBAL_SANITIZED=1 \
    "$repo/.venv/bin/python" -m pytest tests -q -p no:cacheprovider "${parallel[@]}" \
    --deselect tests/model_core/model/test_reference_solution.py \
    --ignore tests/package/report/test_report.py --ignore tests/docs/test_readme_commands.py --ignore tests/docs/test_example_notebook.py \
    --ignore tests/model_core/multibody/test_rigid_body_symbolic.py --ignore tests/package/scene/test_scene_input_checks.py \
    --ignore tests/package/scene/test_gyro_model.py --ignore tests/package/target/test_target_geometry.py \
    --ignore tests/docs/test_documentation.py --ignore tests/docs/test_controller_api_page.py \
    --ignore tests/layout/test_package_layout.py --ignore tests/layout/test_include_directions.py \
    --ignore tests/layout/test_model_core_layers.py --ignore tests/layout/test_main_job_builds.py \
    --ignore tests/layout/test_build_locations.py --ignore tests/layout/test_installed_package.py \
    --ignore tests/package/cli/test_cli_exit_statuses.py --ignore tests/package/cli/test_cli_bench.py --ignore tests/package/cli/test_progress.py \
    --ignore tests/package/scene/test_scene_messages.py --ignore tests/package/test_hostile_names.py --ignore tests/package/master/test_run_lock.py \
    --ignore tests/package/analysis/test_frequency_response.py --ignore tests/package/analysis/test_freqresp_linearity.py \
    --ignore tests/package/analysis/test_isolation_prediction.py --ignore tests/package/master/test_spectra.py --ignore tests/package/scene/test_jitter.py \
    --ignore tests/package/cli/test_linearize_command.py --ignore tests/package/cli/test_system_command.py \
    --ignore tests/package/sweep/test_sweep.py --ignore tests/package/sweep/test_sweep_messages.py \
    --ignore tests/package/sweep/test_sweep_concurrency.py --ignore tests/package/sweep/test_sweep_cluster.py \
    --ignore tests/package/master/test_run_partial.py --ignore tests/package/master/test_long_run.py --ignore tests/package/tune/test_tune.py \
    --ignore tests/package/master/test_run_failure_paths.py --ignore tests/package/test_toml_fuzz.py --ignore tests/package/test_input_bounds.py \
    --ignore tests/package/scene/test_culprit_messages.py --ignore tests/package/target/test_target_inputs.py \
    --ignore tests/package/sweep/test_sweep_failure_paths.py --ignore tests/package/report/test_html_escaping.py \
    --ignore tests/package/analysis/test_lower_gain_margin.py --ignore tests/package/master/test_cumulative_rms.py
  unset ASAN_OPTIONS UBSAN_OPTIONS
  echo "[test] sanitizer pass clean; now the release build"
fi

ctest --test-dir "$build_dir" --output-on-failure --parallel "$test_jobs"
GIMBAL_BUILD_DIR="$build_dir" "$repo/.venv/bin/python" -m pytest tests "${parallel[@]}" "$@"
