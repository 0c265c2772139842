#!/usr/bin/env bash
# The main job: install what running needs (not the test tool chain), build the FMU, and run a scene with
# the gimbal2axis command (`gimbal2axis run`, whose options it passes on): the default scene, free swing
# of the payload under gravity on a fixed base, unless a scene file (*.toml) is given, and the results
# in the repository's results/ unless --out says otherwise: results/free_swing.csv and .png.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
GIMBAL_SETUP_FOR=run bash "$repo/scripts/setup.sh"
scene_given=no
for argument in "$@"; do
  case "$argument" in *.toml) scene_given=yes ;; esac
done
[ "$scene_given" = yes ] || set -- "$repo/scenes/free_swing.toml" "$@"
# --out first: one given among the arguments comes later and wins.
"$repo/.venv/bin/gimbal2axis" run --out "$repo/results" "$@"
