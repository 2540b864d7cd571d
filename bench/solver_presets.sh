#!/bin/bash
# The solver presets (runtime/src/presets.cpp, `weft run --preset`), measured with `weft run` on one scene: three
# runs each for the median ms per step, then bench/solver_presets.py compares every preset's
# positions with the accurate preset's at a few frames and prints a table and JSON.
# 'loose' is the CG tolerance the interactive preset does not use (1e-2), kept to show why.
#
#   bench/solver_presets.sh [SCENE] [FRAMES] [WEFT] [OUT]     (defaults: drape 60 build/bin/weft out/presets)
set -euo pipefail
scene=${1:-drape}
frames=${2:-60}
weft=${3:-build/bin/weft}
out=${4:-out/presets}
# The shipped presets by name (weft/presets.h, `--preset`); 'loose' is interactive with CG to 1e-2, cap 50.
declare -A presets
presets[loose]="--preset interactive --set solver.cg_tolerance=1e-2 --set solver.cg_max_iterations=50"
presets[interactive]="--preset interactive"
presets[balanced]="--preset balanced"
presets[accurate]="--preset accurate"
rm -rf "$out"
mkdir -p "$out"
for preset in loose interactive balanced accurate; do
  for run in 1 2 3; do
    # A preset that trips a warning (CG capped) still measures: the exit code says so, the JSON counts it.
    eval "$weft" run "$scene" --backend cpu --frames "$frames" --quiet ${presets[$preset]} \
      --stats "$out/$preset-$run.json" --out "$out/$preset" --format obj > /dev/null 2>&1 || true
  done
done
python3 "$(dirname "$0")/solver_presets.py" "$out" 20 40 "$frames"
