#!/usr/bin/env bash
# The multi-GPU measurements of docs/multi-gpu.md in one run:
#
#   bench/run_multi_gpu_benchmarks.sh BUILD_DIR OUT_DIR [parts|products|steps|all]
#
# parts: the partition's cut against METIS and the preconditioner built per part (host);
# products (where a GPU is present): the product across GPUs (exchange, exchange-then-product,
#   pipelined, as graphs) and the single-reduction CG per iteration, for flag 1.2M and 2.4M triangles
#   and twist 200K, with the parts on separate GPUs and all on GPU 0 (the test mode);
# steps (where a GPU is present): whole steps with self-contact on 1 and 2 GPUs (`weft bench --gpus`):
#   flag 1.2M and 2.4M at dt 1/250 (strong and weak scaling) and twist 200K over its first second.
# Default: all. Tables on stdout and in OUT_DIR/summary.txt, JSON beside them. Exit status: the number
# of runs that failed.
set -uo pipefail

source "$(dirname "$0")/common/bench_dirs.sh"
bench_dirs "" "[parts|products|steps|all]" "$@"
SECTION=${3:-all}
case $SECTION in parts | products | steps | all) ;; *) echo "$0: unknown section '$SECTION' (parts, products, steps or all)" >&2; exit 2 ;; esac
WEFT="$BUILD/bin/weft"
ROOT=$(cd "$(dirname "$0")/.." && pwd)
has_gpu() { command -v nvidia-smi >/dev/null 2>&1 && nvidia-smi -L >/dev/null 2>&1; }
wants() { [[ $SECTION == all || $SECTION == "$1" ]]; }
PARTITION="$BUILD/bin/weft_partition_bench"
SPMV="$BUILD/bin/weft_multi_gpu_spmv_bench"
if wants parts && [[ ! -x "$PARTITION" ]]; then echo "$0: $PARTITION not found (build first)" >&2; exit 2; fi
FLAG=(--set 'cloth.flag.mesh.grid.cells=[1000,600]')
FLAG_2X=(--set 'cloth.flag.mesh.grid.cells=[1414,849]')
TWIST=(--set 'cloth.sheet.mesh.grid.cells=[316,316]' --set cloth.sheet.mesh.grid.width=3.16 --set cloth.sheet.mesh.grid.height=3.16)
failed=0

run() {  # run NAME COMMAND...
    local name=$1
    shift
    echo "== $name"
    if ! "$@" --json "$OUT/$name.json" 2>&1 | tee "$OUT/$name.txt"; then
        echo "   failed, see $name.txt"
        failed=$((failed + 1))
    fi
}

SELF=(--set collision.self=true --set solver.dt=0.004 --set solver.substeps=1)

{
  if wants parts; then
    run partition_flag "$PARTITION" "$ROOT/assets/scenes/flag.toml" "${FLAG[@]}" --parts 2,4,8
    run partition_twist "$PARTITION" "$ROOT/assets/scenes/twist.toml" "${TWIST[@]}" --parts 2,4,8
    run preconditioner_flag "$PARTITION" "$ROOT/assets/scenes/flag.toml" --set 'cloth.flag.mesh.grid.cells=[500,300]' \
        --parts 2,4,8 --cg
  fi
  if wants products; then
    if [[ -x "$SPMV" ]] && has_gpu; then
        nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
        nvidia-smi topo -m 2>/dev/null || true
        gpus=$(nvidia-smi -L | wc -l)
        parts=1,2
        [[ $gpus -ge 4 ]] && parts=1,2,4
        [[ $gpus -ge 8 ]] && parts=1,2,4,8
        run product_flag "$SPMV" "$ROOT/assets/scenes/flag.toml" "${FLAG[@]}" --parts "$parts"
        run product_flag_2x "$SPMV" "$ROOT/assets/scenes/flag.toml" "${FLAG_2X[@]}" --parts "$parts"
        run product_twist "$SPMV" "$ROOT/assets/scenes/twist.toml" "${TWIST[@]}" --parts "$parts"
        run product_flag_one_gpu "$SPMV" "$ROOT/assets/scenes/flag.toml" "${FLAG[@]}" --parts 1,2,4,8 --one-gpu
    else
        echo "== no GPU (or no $SPMV): the products across GPUs are not measured"
    fi
  fi
  if wants steps; then
    if [[ -x "$WEFT" ]] && has_gpu; then
        gpus=1,2
        [[ $(nvidia-smi -L | wc -l) -lt 2 ]] && gpus=1
        run steps_flag_self "$WEFT" bench flag "${FLAG[@]}" "${SELF[@]}" --gpus "$gpus" --warmup 2 --frames 6
        run steps_flag_2x_self "$WEFT" bench flag "${FLAG_2X[@]}" "${SELF[@]}" --gpus "$gpus" --warmup 2 --frames 6
        run steps_twist_self "$WEFT" bench twist "${TWIST[@]}" --gpus "$gpus" --warmup 20 --frames 600
    else
        echo "== no GPU (or no $WEFT): whole steps across GPUs are not measured"
    fi
  fi
} | tee "$OUT/summary.txt"
exit "$failed"
