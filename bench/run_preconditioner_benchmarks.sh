#!/usr/bin/env bash
# Block-Jacobi against the multilevel additive Schwarz preconditioner (solver.preconditioner =
# "jacobi" | "mas") on the CUDA backend, side by side in one run on one GPU (docs/results.md):
#
#   bench/run_preconditioner_benchmarks.sh BUILD_DIR OUT_DIR
#
#   flag_{20k,80k,320k,1200k}_step   flag, dt 0.004 s, 1 substep (P-Cloth's setting): iterations
#                                    against resolution (cells [125,80], [250,160], [500,320], [1000,600])
#   flag_80k_frame                   flag, cells [250,160], dt 1/60 s, 2 substeps (the game setting)
#   sphere_200k                      sphere, cells [316,316]: self-contact and a collider
# each as NAME_jacobi and NAME_mas (JSON and log in OUT_DIR), then a summary table (summary.txt).
# Exit status: the number of runs that failed.
set -uo pipefail

source "$(dirname "$0")/common/bench_dirs.sh"
bench_dirs exact "" "$@"
WEFT="$BUILD/bin/weft"
[[ -x "$WEFT" ]] || { echo "$0: $WEFT not found (build first)" >&2; exit 2; }

FRAMES=${FRAMES:-40}
LARGE_FRAMES=${LARGE_FRAMES:-15}
SPHERE_FRAMES=${SPHERE_FRAMES:-10}
STEP='--set solver.dt=0.004 --set solver.substeps=1'
failed=0

run() {  # run NAME LIMIT FRAMES WARMUP SCENE ARGS...
    local name=$1 limit=$2 frames=$3 warmup=$4 scene=$5
    shift 5
    for pre in jacobi mas; do
        echo "== ${name}_$pre"
        # shellcheck disable=SC2086
        timeout --signal=INT --kill-after=15 "$limit" "$WEFT" bench "$scene" --backend cuda "$@" \
            --set "solver.preconditioner=$pre" --frames "$frames" --warmup "$warmup" \
            --json "$OUT/${name}_$pre.json" >"$OUT/${name}_$pre.log" 2>&1 || {
            echo "   failed (rc $?), see ${name}_$pre.log"
            failed=$((failed + 1))
        }
    done
}

{ nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || true; } | tee "$OUT/gpu.txt"
# shellcheck disable=SC2086
run flag_20k_step 60 "$FRAMES" 5 flag --set 'cloth.flag.mesh.grid.cells=[125,80]' $STEP
# shellcheck disable=SC2086
run flag_80k_step 60 "$FRAMES" 5 flag --set 'cloth.flag.mesh.grid.cells=[250,160]' $STEP
# shellcheck disable=SC2086
run flag_320k_step 90 "$LARGE_FRAMES" 3 flag --set 'cloth.flag.mesh.grid.cells=[500,320]' $STEP
# shellcheck disable=SC2086
run flag_1200k_step 120 "$LARGE_FRAMES" 3 flag --set 'cloth.flag.mesh.grid.cells=[1000,600]' $STEP
run flag_80k_frame 60 "$FRAMES" 5 flag --set 'cloth.flag.mesh.grid.cells=[250,160]'
run sphere_200k 120 "$SPHERE_FRAMES" 2 sphere --set 'cloth.sheet.mesh.grid.cells=[316,316]'

python3 - "$OUT" <<'PY' | tee "$OUT/summary.txt"
import json, os, sys
out = sys.argv[1]
print(f"{'run':<16} {'pre':<7} {'tri':>9} {'fps':>8} {'step ms':>8} {'setup ms':>8} {'solve ms':>8} "
      f"{'CG it/step':>10} {'it/solve max':>12} {'not conv':>8} {'solves':>6} {'B/tri':>6}")
for name in ("flag_20k_step", "flag_80k_step", "flag_320k_step", "flag_1200k_step", "flag_80k_frame", "sphere_200k"):
    for pre in ("jacobi", "mas"):
        try:
            with open(os.path.join(out, f"{name}_{pre}.json")) as f:
                r = json.load(f)[0]
        except (OSError, ValueError, IndexError):
            print(f"{name:<16} {pre:<7} no results")
            continue
        st = r["stage_ms"]
        med = lambda k: st.get(k, {}).get("median", 0.0)
        cg = r["cg_iterations"]
        print(f"{name:<16} {pre:<7} {r['triangles']:>9} {r['fps']:>8.2f} {med('step'):>8.2f} {med('precondition'):>8.2f} "
              f"{med('solve'):>8.2f} {cg['mean']:>10.1f} {cg['max_solve']:>12} "
              f"{r['cg_not_converged']:>8} {cg['solves']:>6} {r['memory_bytes_per_triangle']:>6.0f}")
PY
exit "$failed"
