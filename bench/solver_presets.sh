#!/bin/bash
# The editor's solver presets (editor/src/presets.cpp), measured with `weft run` on one scene: three
# runs each for the median ms per step, then bench/solver_presets.py compares every preset's
# positions with the accurate preset's at a few frames and prints a table and JSON.
# 'loose' is the CG tolerance the fast preset does not use (1e-2), kept to show why.
#
#   bench/solver_presets.sh [SCENE] [FRAMES] [WEFT] [OUT]     (defaults: drape 60 build/bin/weft out/presets)
set -euo pipefail
scene=${1:-drape}
frames=${2:-60}
weft=${3:-build/bin/weft}
out=${4:-out/presets}
declare -A presets
common='--set solver.newton_iterations=1 --set solver.hessian="fast"'
presets[loose]="--set solver.substeps=1 $common --set solver.cg_tolerance=1e-2 --set solver.cg_max_iterations=50 --set solver.precision=\"float\""
presets[fast]="--set solver.substeps=1 $common --set solver.cg_tolerance=1e-3 --set solver.cg_max_iterations=100 --set solver.precision=\"float\""
presets[balanced]="--set solver.substeps=1 $common --set solver.cg_tolerance=1e-4 --set solver.cg_max_iterations=500 --set solver.precision=\"double\""
presets[accurate]="--set solver.substeps=4 --set solver.newton_iterations=3 --set solver.cg_tolerance=1e-6 --set solver.cg_max_iterations=2000 --set solver.precision=\"double\" --set solver.hessian=\"projected\""
rm -rf "$out"
mkdir -p "$out"
for preset in loose fast balanced accurate; do
  for run in 1 2 3; do
    # A preset that trips a warning (CG capped) still measures: the exit code says so, the JSON counts it.
    eval "$weft" run "$scene" --backend cpu --frames "$frames" --quiet ${presets[$preset]} \
      --stats "$out/$preset-$run.json" --out "$out/$preset" --format obj > /dev/null 2>&1 || true
  done
done
python3 "$(dirname "$0")/solver_presets.py" "$out" 20 40 "$frames"
