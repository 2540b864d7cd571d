#!/usr/bin/env python3
"""Tables of bench/run_contact_benchmarks.sh: per run the mean and max ms per step (one `weft run`
frame of dt), CG iterations,
contacts, truncations, reruns, fallbacks, impact zones and device memory per triangle; then per run
the mean ms per step of each stage above 1% of the step and the largest memory entries (bytes per
triangle); for the twist, mean and max ms per step in every 0.5 s window of simulated time (a run
stopped by its time limit shows the windows it finished)."""
import json
import os
import sys


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def main(out):
    names = sorted(f[:-5] for f in os.listdir(out) if f.endswith(".json"))
    print("| run | steps | ms/step mean | max | CG it./frame | contacts (median) | truncated | reruns | fallbacks | "
          "impact zones | B/triangle |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in names:
        d = load(os.path.join(out, name + ".json"))
        if d is None:
            print(f"| {name} | no stats (stopped before the end) |||||||||")
            continue
        steps = d["stage_ms"]["step"]
        col = d["collisions"]
        print(f"| {name} | {d['steps']} | {steps['mean']:.1f} | {steps['max']:.1f} | {d['cg_iterations']['mean']:.0f} | "
              f"{col['contacts']['median']:.0f} | {col.get('truncated_vertices', 0)} | {col.get('redetections', 0)} | "
              f"{col.get('bound_fallbacks', 0)} | {col['impact_zones']} | {d['memory_bytes_per_triangle']:.0f} |")
    for name in names:
        d = load(os.path.join(out, name + ".json"))
        if d is None:
            continue
        step = d["stage_ms"]["step"]["mean"]
        stages = [(k, v["mean"]) for k, v in d["stage_ms"].items() if k != "step" and v["mean"] > 0.01 * step]
        stages.sort(key=lambda kv: -kv[1])
        print(f"\n{name}: mean ms per step by stage: " + ", ".join(f"{k} {v:.1f}" for k, v in stages))
        triangles = max(1, d.get("triangles", 1))
        parts = sorted(d.get("backend_memory_breakdown", {}).items(), key=lambda kv: -kv[1])[:6]
        if parts:
            print(f"{name}: largest memory entries, B per triangle: " +
                  ", ".join(f"{k} {v / triangles:.0f}" for k, v in parts))
    for name in names:
        if not name.startswith("twist"):
            continue
        d = load(os.path.join(out, name + ".json"))
        if d is None:
            continue
        ms = d["series"]["step_ms"]
        frames_per_window = max(1, int(round(0.5 / d["dt"])))
        print(f"\n{name}: ms per step by 0.5 s window (mean / max)")
        print("| window | mean | max |")
        print("|---|---|---|")
        for w in range(0, len(ms), frames_per_window):
            chunk = ms[w:w + frames_per_window]
            lo, hi = w * d["dt"], (w + len(chunk)) * d["dt"]
            print(f"| {lo:.1f}–{hi:.1f} s | {sum(chunk) / len(chunk):.1f} | {max(chunk):.1f} |")


if __name__ == "__main__":
    main(sys.argv[1])
