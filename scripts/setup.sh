#!/usr/bin/env bash
# Installs what a fresh machine lacks (Debian packages, a Python virtual environment with the
# project's package of pyproject.toml), then configures and builds. Safe to run again: it only does
# what is missing.
#   GIMBAL_SETUP_FOR=run   what running needs (scripts/run.sh): requirements-run.txt, the FMUs only
#   GIMBAL_SETUP_FOR=test  (default) also the test tool chain and the other masters, and every target
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${GIMBAL_BUILD_DIR:-$repo/build}"
setup_for="${GIMBAL_SETUP_FOR:-test}"

need_apt=()
need_apt_bare=()
dpkg -s libsundials-dev >/dev/null 2>&1 || need_apt+=(libsundials-dev)
dpkg -s libeigen3-dev >/dev/null 2>&1 || need_apt+=(libeigen3-dev)
command -v ninja >/dev/null 2>&1 || need_apt+=(ninja-build)
if [ "$setup_for" = test ]; then
  dpkg -s libtbb12 >/dev/null 2>&1 || need_apt+=(libtbb12)   # ecospy's native library
  # FMI4j, one of the masters of the test suite, is a Java library built with Maven.
  command -v javac >/dev/null 2>&1 || need_apt+=(default-jdk-headless)
  command -v mvn >/dev/null 2>&1 || need_apt+=(maven)
  # fmi-sim, another master of the test suite, is built by cargo; its FMI bindings are generated with
  # bindgen, which loads libclang.
  dpkg -s libclang-dev >/dev/null 2>&1 || need_apt+=(libclang-dev)
  # xmllint checks the model description against the FMI schemas (fmpy ships them).
  command -v xmllint >/dev/null 2>&1 || need_apt+=(libxml2-utils)
  # The FMU's win64 binary is cross-compiled with mingw-w64 (the win32 thread model: no winpthread
  # DLL) and tested under Wine; without recommends, which would bring a desktop's worth of libraries.
  command -v x86_64-w64-mingw32-g++ >/dev/null 2>&1 || need_apt_bare+=(g++-mingw-w64-x86-64-win32)
  { [ -x /usr/lib/wine/wine64 ] || command -v wine64 >/dev/null 2>&1; } || need_apt_bare+=(wine64)
fi
if [ $((${#need_apt[@]} + ${#need_apt_bare[@]})) -gt 0 ]; then
  echo "[setup] installing Debian packages: ${need_apt[*]} ${need_apt_bare[*]}"
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  [ ${#need_apt[@]} -eq 0 ] ||
    DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${need_apt[@]}" >/dev/null
  [ ${#need_apt_bare[@]} -eq 0 ] ||
    DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${need_apt_bare[@]}" >/dev/null
fi

venv="$repo/.venv"
if [ ! -x "$venv/bin/python" ]; then
  echo "[setup] creating the Python virtual environment in .venv"
  python3 -m venv "$venv"
fi
if [ "$setup_for" = test ]; then
  requirements="$repo/requirements.txt"
  marker="$venv/.requirements-installed"
  modules="fmpy, numpy, scipy, sympy, matplotlib, pytest, xdist, libcosimpy, ecospy, dask.distributed, pyarrow, tqdm, control, nbclient, ipykernel"
else
  requirements="$repo/requirements-run.txt"
  marker="$venv/.requirements-run-installed"
  modules="fmpy, numpy, scipy, matplotlib, dask.distributed, pyarrow, tqdm, control, libcosimpy"
fi
if ! "$venv/bin/python" -c "import $modules" >/dev/null 2>&1 || [ "$requirements" -nt "$marker" ] ||
   [ "$repo/requirements-run.txt" -nt "$marker" ]; then
  echo "[setup] installing Python packages ($(basename "$requirements"))"
  "$venv/bin/pip" install -q --disable-pip-version-check -r "$requirements"
  # ecospy's wheel ships its proxyfmu server without the executable bit.
  chmod +x "$venv"/lib/python3*/site-packages/ecospy/binaries/proxyfmu "$venv"/lib/python3*/site-packages/ecospy/binaries/ecos 2>/dev/null || true
  touch "$marker"
fi
# The project's own package, gimbal2axis/ (pyproject.toml), with its command `gimbal2axis`, installed
# editable: .venv imports it from this checkout, so the command, the tests, the notebook's kernel and the
# sweeps' worker processes always run the working tree's code (a copy in site-packages would go stale
# at the first edit; its C kernels, an extension compiled from c_kernel/, are rebuilt here when their
# sources change).
# --no-deps: its dependencies are requirements-run.txt, installed above.
# Looked up (not imported) with -I: not fooled by the current directory or PYTHONPATH.
package_marker="$venv/.package-installed"
if ! "$venv/bin/python" -I -c "import importlib.util as u, sys
sys.exit(not u.find_spec('gimbal2axis'))" >/dev/null 2>&1 || [ ! -x "$venv/bin/gimbal2axis" ] ||
   [ "$repo/pyproject.toml" -nt "$package_marker" ] || [ "$repo/requirements-run.txt" -nt "$package_marker" ] ||
   [ "$repo/setup.py" -nt "$package_marker" ] ||
   [ -n "$(find "$repo/c_kernel" "$repo/gimbal2axis/native" -newer "$package_marker" 2>/dev/null)" ] ||
   [ "$repo/CMakeLists.txt" -nt "$package_marker" ] ||   # the package's version is the CMake project's
   ! ls "$repo"/gimbal2axis/native/_native*.so >/dev/null 2>&1; then
  echo "[setup] installing the project's Python package (gimbal2axis, its command and C kernels) into .venv, editable"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check --no-deps -e "$repo"
  touch "$package_marker"
fi

echo "[setup] building in $build_dir"
cmake -S "$repo" -B "$build_dir" -G Ninja -DPython3_EXECUTABLE="$venv/bin/python" >/dev/null
if [ "$setup_for" = test ]; then
  cmake --build "$build_dir"
else
  # Every FMU the README names (the gimbal, the ship-motion and the controller FMUs, each for FMI 2.0 and
  # 3.0; `gimbal2axis system` puts the latter two beside the gimbal) and the analysis library
  # `gimbal2axis linearize` loads; no tests, no fuzzer, no benchmarks. One line: tests/layout/test_main_job_builds.py
  # reads the targets from it.
  cmake --build "$build_dir" --target fmu fmu3 ship_motion_fmu ship_motion_fmu3 controller_fmu controller_fmu3 gimbal_probe
fi
echo "[setup] FMUs ready in $build_dir: Gimbal2Axis.fmu (FMI 2.0, the one the gimbal2axis command of .venv runs)," \
     "Gimbal2Axis-fmi3.fmu, Gimbal2Axis-ShipMotion.fmu, Gimbal2Axis-Controller.fmu and their -fmi3.fmu twins"
