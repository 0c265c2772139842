#!/usr/bin/env bash
# Installs what a fresh machine lacks (Debian packages, a Python virtual environment), then
# configures and builds the FMU. Safe to run again: it only does what is missing.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${GIMBAL_BUILD_DIR:-$repo/build}"

need_apt=()
dpkg -s libsundials-dev >/dev/null 2>&1 || need_apt+=(libsundials-dev)
dpkg -s libeigen3-dev >/dev/null 2>&1 || need_apt+=(libeigen3-dev)
dpkg -s libtbb12 >/dev/null 2>&1 || need_apt+=(libtbb12)
command -v ninja >/dev/null 2>&1 || need_apt+=(ninja-build)
# FMI4j, one of the masters of the test suite, is a Java library built with Maven.
command -v javac >/dev/null 2>&1 || need_apt+=(default-jdk-headless)
command -v mvn >/dev/null 2>&1 || need_apt+=(maven)
# fmi-sim, another master of the test suite, is built by cargo; its FMI bindings are generated with
# bindgen, which loads libclang.
dpkg -s libclang-dev >/dev/null 2>&1 || need_apt+=(libclang-dev)
if [ ${#need_apt[@]} -gt 0 ]; then
  echo "[setup] installing Debian packages: ${need_apt[*]}"
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${need_apt[@]}" >/dev/null
fi

venv="$repo/.venv"
if [ ! -x "$venv/bin/python" ]; then
  echo "[setup] creating the Python virtual environment in .venv"
  python3 -m venv "$venv"
fi
if ! "$venv/bin/python" -c "import fmpy, numpy, scipy, sympy, matplotlib, pytest, libcosimpy, ecospy, dask.distributed, pyarrow, tqdm, nbclient, ipykernel" >/dev/null 2>&1 ||
   [ "$repo/requirements.txt" -nt "$venv/.requirements-installed" ]; then
  echo "[setup] installing Python packages (requirements.txt)"
  "$venv/bin/pip" install -q --disable-pip-version-check -r "$repo/requirements.txt"
  # ecospy's wheel ships its proxyfmu server without the executable bit.
  chmod +x "$venv"/lib/python3*/site-packages/ecospy/binaries/proxyfmu "$venv"/lib/python3*/site-packages/ecospy/binaries/ecos 2>/dev/null || true
  touch "$venv/.requirements-installed"
fi

echo "[setup] building in $build_dir"
cmake -S "$repo" -B "$build_dir" -G Ninja -DPython3_EXECUTABLE="$venv/bin/python" >/dev/null
cmake --build "$build_dir"
echo "[setup] FMU ready: $build_dir/Gimbal2Axis.fmu"
