#!/usr/bin/env bash
# The two contact modes (collision.mode = "ccd_zones" | "offset") side by side on the CUDA backend, in
# one run on one GPU (docs/results.md, "Offset geometric contact"):
#
#   bench/run_contact_benchmarks.sh BUILD_DIR OUT_DIR [CASE...]
#
#   twist      twist at 317 × 317 vertices (200K triangles), dt 1/600 s: 0–4 s (TWIST_FRAMES, 2400),
#              mean and max ms per step in every 0.5 s window
#   layers     layers with 50 sheets of 69² cells (476K triangles): LAYERS_FRAMES frames (20)
#   sphere     sphere at 316² cells (200K triangles): SPHERE_FRAMES frames (60)
#   flag       flag at 1000 × 600 cells (1.2M triangles) with self-contact, dt 1/250: FLAG_FRAMES (10)
# each as CASE_ccd_zones and CASE_offset (stats JSON and log in OUT_DIR), each under a time limit
# (LIMIT seconds, 240: a run that hits it is reported with the frames it finished), then the tables
# (summary.txt). Runs with `weft run --stats` (per-frame series); exit status: the number of runs
# that failed other than by the time limit. A variant: EXTRA (more `weft run` arguments for every run,
# e.g. "--set collision.max_query_radius=2") and TAG (appended to the run names).
set -uo pipefail

source "$(dirname "$0")/common/bench_dirs.sh"
bench_dirs more "[twist|layers|sphere|flag ...]" "$@"
shift 2
CASES=("$@")
[[ ${#CASES[@]} -gt 0 ]] || CASES=(twist layers sphere flag)
WEFT="$BUILD/bin/weft"
[[ -x "$WEFT" ]] || { echo "$0: $WEFT not found (build first)" >&2; exit 2; }
LIMIT=${LIMIT:-240}
MODES=${MODES:-"offset ccd_zones"}
failed=0

run() {  # run NAME FRAMES SCENE ARGS...
    local name=$1${TAG:-} frames=$2 scene=$3
    shift 3
    # shellcheck disable=SC2206 # EXTRA is a list of words on purpose
    local extra=(${EXTRA:-})
    for mode in $MODES; do
        echo "== ${name}_$mode"
        timeout --signal=INT --kill-after=15 "$LIMIT" "$WEFT" run "$scene" --backend cuda "$@" "${extra[@]}" \
            --set "collision.mode=$mode" --frames "$frames" --stats "$OUT/${name}_$mode.json" \
            >"$OUT/${name}_$mode.log" 2>&1
        local rc=$?
        if [[ $rc -eq 124 || $rc -eq 130 ]]; then
            echo "   stopped at the time limit (${LIMIT} s)"
        elif [[ $rc -ne 0 && $rc -ne 4 ]]; then
            echo "   failed (rc $rc), see ${name}_$mode.log"
            failed=$((failed + 1))
        fi
    done
}

{ nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || true; } | tee "$OUT/gpu.txt"
for c in "${CASES[@]}"; do
    case $c in
    twist) run twist "${TWIST_FRAMES:-2400}" twist --set 'cloth.sheet.mesh.grid.cells=[316,316]' \
        --set cloth.sheet.mesh.grid.width=3.16 --set cloth.sheet.mesh.grid.height=3.16 ;;
    layers) run layers "${LAYERS_FRAMES:-20}" layers --set cloth.sheets.repeat.count=50 \
        --set 'cloth.sheets.mesh.grid.cells=[69,69]' ;;
    sphere) run sphere "${SPHERE_FRAMES:-60}" sphere --set 'cloth.sheet.mesh.grid.cells=[316,316]' ;;
    flag) run flag "${FLAG_FRAMES:-10}" flag --set 'cloth.flag.mesh.grid.cells=[1000,600]' --set collision.self=true \
        --set solver.dt=0.004 --set solver.substeps=1 ;;
    *) echo "$0: unknown case '$c'" >&2; exit 2 ;;
    esac
done

python3 "$(dirname "$0")/contact_summary.py" "$OUT" | tee "$OUT/summary.txt"
exit "$failed"
