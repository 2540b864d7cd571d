#!/usr/bin/env bash
# The multi-GPU measurements of docs/multi-gpu.md in one run:
#
#   bench/run_multi_gpu_benchmarks.sh BUILD_DIR OUT_DIR
#
# the partition's cut against METIS and the preconditioner built per part (host), then, where a GPU is
# present, the product across GPUs (exchange, exchange-then-product, pipelined, as graphs) and the
# single-reduction CG per iteration, for flag 1.2M and 2.4M triangles and twist 200K, with the parts
# on separate GPUs and all on GPU 0 (the test mode). Tables on stdout and in OUT_DIR/summary.txt, JSON
# beside them. Exit status: the number of runs that failed.
set -uo pipefail

source "$(dirname "$0")/common/bench_dirs.sh"
bench_dirs exact "" "$@"
ROOT=$(cd "$(dirname "$0")/.." && pwd)
PARTITION="$BUILD/bin/weft_partition_bench"
SPMV="$BUILD/bin/weft_multi_gpu_spmv_bench"
[[ -x "$PARTITION" ]] || { echo "$0: $PARTITION not found (build first)" >&2; exit 2; }
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

{
    run partition_flag "$PARTITION" "$ROOT/assets/scenes/flag.toml" "${FLAG[@]}" --parts 2,4,8
    run partition_twist "$PARTITION" "$ROOT/assets/scenes/twist.toml" "${TWIST[@]}" --parts 2,4,8
    run preconditioner_flag "$PARTITION" "$ROOT/assets/scenes/flag.toml" --set 'cloth.flag.mesh.grid.cells=[500,300]' \
        --parts 2,4,8 --cg
    if [[ -x "$SPMV" ]] && command -v nvidia-smi >/dev/null 2>&1 && nvidia-smi -L >/dev/null 2>&1; then
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
} | tee "$OUT/summary.txt"
exit "$failed"
