#!/usr/bin/env bash
# Strong and weak scaling across the GPUs of one host (docs/multi-gpu.md, "Scaling"):
#
#   bench/run_scaling_benchmarks.sh BUILD_DIR OUT_DIR [strong|weak|all] [GPU_COUNTS]
#
# strong: the same scene on 1, 2, 4, 8 GPUs (those the host has; GPU_COUNTS, e.g. 1,2,4, to choose):
#   flag 1.2M triangles with self-contact at dt 1/250 (and weft_multi_gpu_spmv_bench on its pattern:
#   the time the pipelined product hides, bytes between GPUs, CG time per iteration), the twist 317² (200K) over its first second
#   (the winding after it takes minutes a run on one GPU: docs/results.md, "Offset geometric contact"),
#   and a skirt of 1M triangles on the turning mannequin (tools/make_skirt.py, self-contact and the
#   body as a mesh collider);
# weak: the flag at the same 2 mm spacing with 600K triangles per GPU (1.41 × 0.85 m on one GPU,
#   2 × 1.2 m on two, 2.83 × 1.70 m on four, 4 × 2.4 m on eight), and the issue-20 pair: the 1.2M
#   flag on one GPU against a 2.4M flag of the same spacing on two.
# Default: all, on every GPU the host has. Every run is `weft bench --json`; the tables
# (bench/common/scaling_table.py) go to stdout and OUT_DIR/summary.md. Exit status: the number of
# runs that failed. RUN_TIMEOUT=SECONDS stops any one run after that long (counted as failed).
set -uo pipefail

source "$(dirname "$0")/common/bench_dirs.sh"
bench_dirs "" "[strong|weak|all] [GPU_COUNTS]" "$@"
SECTION=${3:-all}
case $SECTION in strong | weak | all) ;; *) echo "$0: unknown section '$SECTION' (strong, weak or all)" >&2; exit 2 ;; esac
WEFT="$BUILD/bin/weft"
ROOT=$(cd "$(dirname "$0")/.." && pwd)
TABLE="$ROOT/bench/common/scaling_table.py"
[[ -x "$WEFT" ]] || { echo "$0: $WEFT not found (build first)" >&2; exit 2; }
if ! command -v nvidia-smi >/dev/null 2>&1 || ! nvidia-smi -L >/dev/null 2>&1; then
    echo "$0: no GPU here: nothing to scale" >&2
    exit 0
fi
HOST_GPUS=$(nvidia-smi -L | wc -l)
if [[ -n ${4:-} ]]; then
    COUNTS=$4
else
    COUNTS=1
    for g in 2 4 8; do [[ $g -le $HOST_GPUS ]] && COUNTS="$COUNTS,$g"; done
fi
wants() { [[ $SECTION == all || $SECTION == "$1" ]]; }
failed=0
run() {  # run NAME ARGS... (to weft bench)
    local name=$1
    shift
    echo "== $name: weft bench $*" >&2
    if ! timeout "${RUN_TIMEOUT:-0}" "$WEFT" bench "$@" --json "$OUT/$name.json" > "$OUT/$name.txt" 2>&1; then
        echo "   failed, see $name.txt" >&2
        failed=$((failed + 1))
    fi
}
# The flag at 2 mm spacing, W × H metres (cells 500·W × 500·H), its left edge at the pole.
flag_of() {  # flag_of CELLS_X CELLS_Y
    local w h
    w=$(awk "BEGIN { printf \"%.4f\", $1 / 500 }")
    h=$(awk "BEGIN { printf \"%.4f\", $2 / 500 }")
    echo "--set cloth.flag.mesh.grid.cells=[$1,$2] --set cloth.flag.mesh.grid.width=$w --set cloth.flag.mesh.grid.height=$h \
--set cloth.flag.position=[$(awk "BEGIN { printf \"%.4f\", $w / 2 }"),2.4,0.0]"
}
SELF=(--set collision.self=true --set solver.dt=0.004 --set solver.substeps=1)
TWIST=(--set 'cloth.sheet.mesh.grid.cells=[316,316]' --set cloth.sheet.mesh.grid.width=3.16 --set cloth.sheet.mesh.grid.height=3.16)

{
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
  nvidia-smi topo -m 2>/dev/null | head -12
} > "$OUT/host.txt" 2>&1
cat "$OUT/host.txt"
if wants strong; then
    run strong_flag flag --set 'cloth.flag.mesh.grid.cells=[1000,600]' "${SELF[@]}" --gpus "$COUNTS" --warmup 2 --frames 6
    run strong_twist twist "${TWIST[@]}" --gpus "$COUNTS" --warmup 20 --frames 580
    SKIRT=${SKIRT:-$OUT/skirt_1m.obj}  # the 1M-triangle skirt (made once; SKIRT=FILE puts it elsewhere)
    [[ -s $SKIRT ]] || python3 "$ROOT/tools/make_skirt.py" --segments 1000 --rings 500 -o "$SKIRT"
    # The pipelined product on the strong flag's pattern: time hidden, bytes between GPUs, CG time per
    # iteration (the reductions), per GPU count.
    SPMV="$BUILD/bin/weft_multi_gpu_spmv_bench"
    if [[ -x $SPMV ]]; then
        echo "== spmv: $SPMV flag --parts $COUNTS" >&2
        timeout "${RUN_TIMEOUT:-0}" "$SPMV" "$ROOT/assets/scenes/flag.toml" --set 'cloth.flag.mesh.grid.cells=[1000,600]' \
            --parts "$COUNTS" --json "$OUT/spmv.json" > "$OUT/spmv.txt" 2>&1 || { echo "   failed, see spmv.txt" >&2; failed=$((failed + 1)); }
    fi
    run strong_garment garment --set "cloth.skirt.mesh.file=\"$SKIRT\"" --gpus "$COUNTS" --warmup 1 --frames 3
fi
if wants weak; then
    IFS=, read -r -a counts <<< "$COUNTS"
    for g in "${counts[@]}"; do
        case $g in 1) c="707 424" ;; 2) c="1000 600" ;; 4) c="1414 849" ;; 8) c="2000 1200" ;; *) continue ;; esac
        # shellcheck disable=SC2046
        run "weak_flag_$g" flag $(flag_of $c) "${SELF[@]}" --gpus "$g" --warmup 2 --frames 6
    done
    if [[ ",$COUNTS," == *,2,* && -f $OUT/strong_flag.json ]]; then
        # shellcheck disable=SC2046
        run weak_pair_2 flag $(flag_of 1414 849) "${SELF[@]}" --gpus 2 --warmup 2 --frames 6
    fi
fi

{
  if wants strong; then
      echo "## Strong scaling"
      python3 "$TABLE" strong "$OUT"/strong_*.json
      if [[ -s $OUT/spmv.txt ]]; then
          echo
          echo "## The pipelined product A·x on the strong flag's pattern (weft_multi_gpu_spmv_bench)"
          grep '^|' "$OUT/spmv.txt"
      fi
  fi
  if wants weak; then
      echo
      echo "## Weak scaling: 600K triangles per GPU"
      python3 "$TABLE" weak "$OUT"/weak_flag_*.json
      if [[ -f $OUT/weak_pair_2.json ]]; then
          echo
          echo "## Weak scaling: 1.2M triangles per GPU (the strong run's 1.2M flag on one GPU, 2.4M on two)"
          python3 "$TABLE" weak "$OUT/strong_flag.json@1" "$OUT/weak_pair_2.json"
      fi
  fi
} | tee "$OUT/summary.md"
exit "$failed"
