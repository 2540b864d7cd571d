"""Table and JSON for bench/solver_presets.sh: per preset, the median ms per step of three runs, CG
iterations and capped solves, and the distance of every vertex from the accurate preset's at the
frames given. Usage: solver_presets.py OUT FRAME [FRAME ...]"""
import glob
import json
import os
import statistics
import sys


def vertices(path):
    with open(path) as f:
        return [tuple(map(float, line.split()[1:4])) for line in f if line.startswith("v ")]


def frame_file(out, preset, frame):
    files = glob.glob(os.path.join(out, preset, f"frame_{frame:04d}_*.obj"))
    if not files:
        sys.exit(f"solver_presets.py: no frame {frame} for preset {preset} in {out}")
    return sorted(files)[0]


def main():
    out, frames = sys.argv[1], [int(f) for f in sys.argv[2:]]
    presets = ["loose", "interactive", "balanced", "accurate"]
    rows = []
    for preset in presets:
        runs = [json.load(open(f)) for f in sorted(glob.glob(os.path.join(out, f"{preset}-*.json")))]
        row = {
            "preset": preset,
            "device": runs[0]["device"],
            "triangles": runs[0]["triangles"],
            "ms_per_step_median": statistics.median(1000.0 * r["simulation_seconds"] / r["steps"] for r in runs),
            "cg_iterations_mean": runs[0]["cg_iterations"]["mean"],
            "cg_capped": runs[0]["cg_not_converged"],
            "steps": runs[0]["steps"],
            "error_mm": {},
        }
        for frame in frames:
            ref = vertices(frame_file(out, "accurate", frame))
            x = vertices(frame_file(out, preset, frame))
            d = [sum((a - b) ** 2 for a, b in zip(u, v)) ** 0.5 for u, v in zip(x, ref)]
            row["error_mm"][frame] = {"mean": 1000.0 * statistics.mean(d), "max": 1000.0 * max(d)}
        rows.append(row)
    balanced = next(r for r in rows if r["preset"] == "balanced")["ms_per_step_median"]
    print(f"{rows[0]['triangles']} triangles, {rows[0]['device']}")
    header = "| preset | ms/step (median of 3) | vs balanced | CG it./solve | capped | " + " | ".join(
        f"frame {f}: mean / max from accurate" for f in frames) + " |"
    print(header)
    print("|" + "---|" * (5 + len(frames)))
    for r in rows:
        errors = " | ".join(f"{r['error_mm'][f]['mean']:.3g} / {r['error_mm'][f]['max']:.3g} mm" for f in frames)
        print(f"| {r['preset']} | {r['ms_per_step_median']:.2f} | {balanced / r['ms_per_step_median']:.2f}x | "
              f"{r['cg_iterations_mean']:.0f} | {r['cg_capped']}/{r['steps']} | {errors} |")
    with open(os.path.join(out, "solver_presets.json"), "w") as f:
        json.dump(rows, f, indent=1)
    print(f"JSON: {os.path.join(out, 'solver_presets.json')}")


if __name__ == "__main__":
    main()
