#!/usr/bin/env bash
# Install what is missing, build, and run every test (C++ through CTest, then Python through pytest).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${GIMBAL_BUILD_DIR:-$repo/build}"
bash "$repo/scripts/setup.sh"
ctest --test-dir "$build_dir" --output-on-failure
cd "$repo"
GIMBAL_BUILD_DIR="$build_dir" "$repo/.venv/bin/python" -m pytest tests "$@"
