#!/usr/bin/env bash
# Long runs (docs/results.md, "Soak"): every shipped scene (or those named) for STEPS frames with the
# exact intersection check, then a quarter of them, on one backend:
#
#   bench/run_soak_benchmarks.sh BUILD_DIR OUT_DIR [STEPS] [BACKEND] [SCENES]
#
# STEPS default 10000 (the issue's soak); BACKEND cpu or cuda (default: cpu); SCENES space-separated
# names (default: every scene in assets/scenes). Environment: JOBS scenes at a time (default 1),
# THREADS CPU threads a run (default 0: all cores),
# SECONDS_PER_RUN a time limit per run (SIGTERM: the frames done are reported, marked as cut short). Per scene it reports NaN frames, frames whose energy
# grew beyond the external work (after the guard's redo), intersections left, the step time of the
# first and last tenth of the run (median ms) and their ratio (a slowdown shows as > 1), and the peak
# host memory (max RSS) of the full run against the quarter run (growth after warm-up shows as a
# ratio above 1). Markdown on stdout and OUT_DIR/summary.md; exit status: the scenes that failed.
set -uo pipefail
source "$(dirname "$0")/common/bench_dirs.sh"
bench_dirs "" "[STEPS] [BACKEND] [SCENES]" "$@"
STEPS=${3:-10000}
BACKEND=${4:-cpu}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SCENES=${5:-$(find "$ROOT/assets/scenes" -name '*.toml' -printf '%f\n' | sed 's|\.toml$||' | sort | tr '\n' ' ')}
WEFT="$BUILD/bin/weft"
[[ -x $WEFT ]] || { echo "$0: $WEFT not found (build first)" >&2; exit 2; }
[[ -x /usr/bin/time ]] || { echo "$0: /usr/bin/time is needed for the peak memory (Debian: time)" >&2; exit 2; }
quarter=$((STEPS / 4 > 0 ? STEPS / 4 : 1))
failed=0
soak_scene() {  # the quarter run and the full one, side by side
    local scene=$1 n
    for n in "$quarter" "$STEPS"; do
        echo "== $scene: $n frames on $BACKEND" >&2
        # shellcheck disable=SC2086  # LIMIT is "timeout -s TERM SECONDS" or empty
        /usr/bin/time -f "%M" -o "$OUT/${scene}_$n.rss" $LIMIT "$WEFT" run "$scene" --backend "$BACKEND" --threads "$THREADS" --frames "$n" --check --quiet \
            --stats "$OUT/${scene}_$n.json" > "$OUT/${scene}_$n.txt" 2>&1 &
    done
    wait
}
# JOBS scenes at once (default 1; each is two runs; on a GPU host the scenes share the device); SECONDS_PER_RUN stops
# a run with SIGTERM after that long, which writes the stats of the frames done (reported as such).
JOBS=${JOBS:-1}
THREADS=${THREADS:-0}  # CPU threads a run (0: all cores; give fewer when JOBS runs share the host)
LIMIT=${SECONDS_PER_RUN:+timeout -s TERM $SECONDS_PER_RUN}
running=0
for scene in $SCENES; do
    soak_scene "$scene" &
    running=$((running + 1))
    if ((running >= JOBS)); then
        wait -n
        running=$((running - 1))
    fi
done
wait
# shellcheck disable=SC2086  # the scene names, one argument each
python3 - "$OUT" "$STEPS" "$quarter" $SCENES <<'PY' | tee "$OUT/summary.md"
import json, statistics, sys
out, steps, quarter, scenes = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4:]
print(f"| scene | frames | NaN frames | energy gained (frames) | intersections left | ms first tenth | ms last tenth | slowdown | peak RSS MB, {quarter} / {steps} frames | growth | backend MB at the end, {quarter} / {steps} |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
bad = 0
for s in scenes:
    try:
        r = json.load(open(f"{out}/{s}_{steps}.json"))
        rss = [int(open(f"{out}/{s}_{n}.rss").read().split()[-1]) / 1024 for n in (quarter, steps)]
        # What the backend holds (device memory on a GPU backend) at the end of each run.
        held = [json.load(open(f"{out}/{s}_{n}.json"))["memory_bytes"]["backend"] / 2**20 for n in (quarter, steps)]
    except (OSError, ValueError, IndexError) as e:
        print(f"| {s} | — | run failed: {type(e).__name__} | | | | | | | | |"); bad += 1; continue
    ms = r["series"]["step_ms"]; tenth = max(1, len(ms) // 10)
    first, last = statistics.median(ms[:tenth]), statistics.median(ms[-tenth:])
    gained = sum(1 for e in r["series"]["energy_gained"] if e)
    left = r.get("remaining_intersections")
    # A scene without cloth collisions (self-contact off) may pass through itself: the check counts
    # it, but it is not a failure of the contact pipeline.
    modelled = "broad_phase" in r.get("stages_run", [])  # the cloth-collision stages ran
    ok = r["non_finite_frames"] == 0 and gained == 0 and (not left or not modelled)
    if left and not modelled: left = f"{left} (self-contact off)"
    bad += 0 if ok else 1
    frames = f"{r['steps']}" if r['steps'] >= steps else f"{r['steps']} (cut short)"
    print(f"| {s} | {frames} | {r['non_finite_frames']} | {gained} | {left if left is not None else 'not checked'} | "
          f"{first:.2f} | {last:.2f} | {last / first:.2f}× | {rss[0]:.0f} / {rss[1]:.0f} | {rss[1] / rss[0]:.2f}× | {held[0]:.1f} / {held[1]:.1f} |")
sys.exit(bad)
PY
failed=$?
exit "$failed"
