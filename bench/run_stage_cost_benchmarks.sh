#!/usr/bin/env bash
# What each stage costs a step, switched on one at a time on one scene (issue 22: a scene pays only
# for what it models):
#
#   bench/run_stage_cost_benchmarks.sh BUILD_DIR OUT_DIR [BACKEND] [CELLS]
#
# `hanging` (a sheet pinned at two corners: no contact, no collider, no wind) as it ships, then with
# wind, with self-collision, with both; CELLS (default 32) cells a side. BACKEND: cpu or cuda (default
# cuda where a GPU is, else cpu). Each run is `weft bench --json`; the table (median ms per frame and
# what the stage adds to the plain sheet) goes to stdout and OUT_DIR/summary.md. Exit status: the
# number of runs that failed.
set -uo pipefail

source "$(dirname "$0")/common/bench_dirs.sh"
bench_dirs "" "[BACKEND] [CELLS]" "$@"
WEFT="$BUILD/bin/weft"
[[ -x "$WEFT" ]] || { echo "$0: $WEFT not found (build first)" >&2; exit 2; }
BACKEND=${3:-}
if [[ -z $BACKEND ]]; then
    BACKEND=cpu
    command -v nvidia-smi >/dev/null 2>&1 && nvidia-smi -L >/dev/null 2>&1 && BACKEND=cuda
fi
CELLS=${4:-32}
case $CELLS in '' | *[!0-9]*) echo "$0: CELLS '$CELLS' is not a whole number" >&2; exit 2 ;; esac
SIZE=(--set "cloth.sheet.mesh.grid.cells=[$CELLS,$CELLS]")
WIND=(--set 'wind.velocity=[3.0,0.0,1.0]')
SELF=(--set collision.self=true)
failed=0
run() {  # run NAME ARGS...
    local name=$1
    shift
    echo "== $name" >&2
    if ! "$WEFT" bench hanging --backend "$BACKEND" "${SIZE[@]}" "$@" --warmup 5 --frames 30 --json "$OUT/$name.json" \
        > "$OUT/$name.txt" 2>&1; then
        echo "   failed, see $name.txt" >&2
        failed=$((failed + 1))
    fi
}
run plain
run wind "${WIND[@]}"
run self_collision "${SELF[@]}"
run wind_and_self_collision "${WIND[@]}" "${SELF[@]}"

python3 - "$OUT" "$BACKEND" "$CELLS" <<'PY' | tee "$OUT/summary.md"
import json, sys, os
out, backend, cells = sys.argv[1:4]
rows = []
for name in ("plain", "wind", "self_collision", "wind_and_self_collision"):
    try:
        r = json.load(open(os.path.join(out, name + ".json")))[0]
    except (OSError, ValueError, IndexError):
        continue
    stages = {k: v["median"] for k, v in r["stage_ms"].items() if k != "step" and v["median"] > 0}
    rows.append((name.replace("_", " "), r["stage_ms"]["step"]["median"], stages, r.get("device", "")))
if rows:
    print(f"hanging, {cells}² cells, backend {backend} ({rows[0][3]}), median ms per frame")
    print()
    print("| stages on | ms per frame | added to the plain sheet | stages that ran (ms) |")
    print("|---|---|---|---|")
    base = rows[0][1]
    for name, ms, stages, _ in rows:
        ran = ", ".join(f"{k} {v:.3f}" for k, v in stages.items())
        print(f"| {name} | {ms:.3f} | {ms - base:+.3f} | {ran} |")
PY
exit "$failed"
