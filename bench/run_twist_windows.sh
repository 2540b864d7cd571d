#!/bin/bash
# The twist of issue 20's table over its whole 0–4 s (twist 317², dt 1/600: 2400 steps) on each GPU
# count, in pieces that fit a time limit. Each call resumes every count from its last checkpoint,
# steps it until LIMIT seconds have passed and stops it cleanly (SIGINT: the frame finishes, the
# stats and a checkpoint are written); call it again until it prints "all done". The table (mean and
# max ms per step by 0.5 s window, and the speed-up of each count over the first) is printed every
# time from what has run so far (bench/twist_windows.py).
#
#   bench/run_twist_windows.sh BUILD_DIR OUT_DIR [GPU_COUNTS] [LIMIT_S]
#
# GPU_COUNTS: comma-separated, default 1,2. LIMIT_S: seconds per count per call, default 250.
# Environment: MODE (collision.mode, default offset: the wound twist is where impact zones
# collapse), FRAMES (default 2400), BACKEND (default cuda; cpu runs the logic on a machine without
# a GPU, GPU counts then ignored), EXTRA (more `weft run` arguments, e.g. a smaller sheet for a try).
set -uo pipefail

source "$(dirname "$0")/common/bench_dirs.sh"
bench_dirs more "[GPU_COUNTS] [LIMIT_S]" "$@"
COUNTS=${3:-1,2}
LIMIT=${4:-250}
WEFT="$BUILD/bin/weft"
[[ -x "$WEFT" ]] || { echo "$0: $WEFT not found (build first)" >&2; exit 2; }
MODE=${MODE:-offset}
FRAMES=${FRAMES:-2400}
BACKEND=${BACKEND:-cuda}
SHEET=(--set 'cloth.sheet.mesh.grid.cells=[316,316]' --set cloth.sheet.mesh.grid.width=3.16
       --set cloth.sheet.mesh.grid.height=3.16)
# shellcheck disable=SC2206 # EXTRA is a list of words on purpose
EXTRA_ARGS=(${EXTRA:-})

remaining=0
IFS=, read -r -a counts <<< "$COUNTS"
for g in "${counts[@]}"; do
    dir="$OUT/gpus_$g"
    mkdir -p "$dir/checkpoints"
    # The frame reached so far: the newest checkpoint's number.
    last=$(find "$dir/checkpoints" -name 'frame_*.state' 2>/dev/null | sort | tail -1)
    done_frames=0
    [[ -n $last ]] && done_frames=$((10#$(basename "$last" .state | sed 's/frame_//')))
    if ((done_frames >= FRAMES)); then
        echo "== $g GPU(s): done ($done_frames of $FRAMES frames)"
        continue
    fi
    echo "== $g GPU(s): frames $done_frames to $FRAMES, at most ${LIMIT} s"
    args=(run twist --backend "$BACKEND" --set "collision.mode=$MODE" "${SHEET[@]}" "${EXTRA_ARGS[@]}"
          --frames $((FRAMES - done_frames)) --checkpoint "$dir/checkpoints" --checkpoint-every 60 --quiet
          --stats "$dir/stats_$(printf %06d "$done_frames").json")
    [[ $BACKEND == cuda ]] && args+=(--gpus "$g")
    [[ -n $last ]] && args+=(--resume "$last")
    timeout --signal=INT --kill-after=60 "$LIMIT" "$WEFT" "${args[@]}" > "$dir/run_$(printf %06d "$done_frames").log" 2>&1
    rc=$?
    # 0: finished; 130 (or 124): stopped at the limit, resumable; 4: an intersection was reported.
    if [[ $rc -ne 0 && $rc -ne 4 && $rc -ne 124 && $rc -ne 130 ]]; then
        echo "   failed (rc $rc), see $dir/run_$(printf %06d "$done_frames").log"
    fi
    # Only the newest checkpoint is needed to go on.
    find "$dir/checkpoints" -name 'frame_*.state' | sort | head -n -1 | xargs -r rm -f
    last=$(find "$dir/checkpoints" -name 'frame_*.state' | sort | tail -1)
    reached=0
    [[ -n $last ]] && reached=$((10#$(basename "$last" .state | sed 's/frame_//')))
    echo "   reached frame $reached"
    ((reached < FRAMES)) && remaining=$((remaining + 1))
done
python3 "$(dirname "$0")/twist_windows.py" "$OUT" "$FRAMES" | tee "$OUT/summary.txt"
if ((remaining == 0)); then echo "all done"; else echo "$remaining count(s) to go on: call again"; fi
