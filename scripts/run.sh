#!/usr/bin/env bash
# The main job: install what running needs (not the test tool chain), build the FMU, and run the default scene (free swing of
# the payload under gravity on a fixed base), writing results/free_swing.csv and .png.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
GIMBAL_SETUP_FOR=run bash "$repo/scripts/setup.sh"
"$repo/.venv/bin/python" "$repo/scripts/run_scene.py" "$@"
