#!/usr/bin/env python3
"""The table of bench/run_twist_windows.sh: for every GPU count (OUT/gpus_G), the per-frame step
times of its pieces (stats_FFFFFF.json, FFFFFF the frame the piece started from) joined in frame
order, then the mean and max ms per step in every 0.5 s window of simulated time and the speed-up of
each count's window mean over the first count's. A piece stopped at its time limit keeps the frames
it finished; frames run twice (a piece that ran past its last checkpoint, then resumed) count once,
from the later piece."""
import json
import os
import sys


def series(folder):
    """Per-frame step ms by frame number, and dt (s)."""
    ms, dt = {}, None
    pieces = sorted(f for f in os.listdir(folder) if f.startswith("stats_") and f.endswith(".json"))
    for name in pieces:
        first = int(name[len("stats_"):-len(".json")])
        try:
            with open(os.path.join(folder, name)) as f:
                d = json.load(f)
        except (OSError, ValueError):
            continue
        dt = d["dt"]
        for i, value in enumerate(d["series"]["step_ms"]):
            ms[first + i] = value
    return ms, dt


def main(out, frames):
    counts = sorted(int(f[len("gpus_"):]) for f in os.listdir(out) if f.startswith("gpus_"))
    runs = {g: series(os.path.join(out, f"gpus_{g}")) for g in counts}
    dt = next((d for _, d in runs.values() if d), None)
    if dt is None:
        print("no stats yet")
        return
    per_window = max(1, int(round(0.5 / dt)))
    head = "| window | " + " | ".join(f"{g} GPU{'s' if g > 1 else ''}: mean / max ms" for g in counts)
    head += "".join(f" | {g} against {counts[0]}" for g in counts[1:]) + " |"
    print(head)
    print("|---" * (1 + len(counts) + len(counts) - 1) + "|")
    for w in range(0, frames, per_window):
        cells, means = [], {}
        for g in counts:
            chunk = [runs[g][0][f] for f in range(w, w + per_window) if f in runs[g][0]]
            if chunk:
                means[g] = sum(chunk) / len(chunk)
                note = "" if len(chunk) == per_window else f" ({len(chunk)} steps)"
                cells.append(f"{means[g]:.1f} / {max(chunk):.1f}{note}")
            else:
                cells.append("not reached")
        ratios = [f"{means[counts[0]] / means[g]:.2f}×" if g in means and counts[0] in means else "—" for g in counts[1:]]
        print(f"| {w * dt:.1f}–{(w + per_window) * dt:.1f} s | " + " | ".join(cells + ratios) + " |")
    for g in counts:
        ms = runs[g][0]
        if ms:
            total = sum(ms.values())
            print(f"{g} GPU(s): {len(ms)} of {frames} frames, {total / 1000:.0f} s of steps, mean {total / len(ms):.1f} ms")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 2400)
