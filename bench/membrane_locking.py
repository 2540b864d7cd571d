#!/usr/bin/env python3
"""Membrane locking on coarse meshes (issue 22, item 1): does a coarse cloth fall into folds like the
fine one, or hold its shape? Drapes the `drape` table cloth (1.6 m square onto a 0.5 m ball) at
several resolutions with each bending model, lets it settle, and compares the final shapes:

  footprint  area of the convex hull of the cloth projected on the floor, over the flat cloth's area
             (1.0: the cloth stayed flat; a cloth that falls around the ball covers less)
  height     mean height of the vertices, m
  rim        mean height of the boundary vertices, m (a locked cloth's rim stays up)

Usage: membrane_locking.py WEFT OUT [--cells 8,12,16,24,48,96] [--models hinge,shell] [--frames 240]
       [--backend cpu] [--set KEY=VALUE ...]
Writes OUT/membrane_locking.json and prints a table (one row per model and resolution).
"""
import argparse
import glob
import json
import os
import subprocess
import sys


def last_frame(directory):
    files = sorted(glob.glob(os.path.join(directory, "frame_*_cloth.obj")))
    if not files:
        sys.exit(f"membrane_locking.py: no frames written in {directory}")
    with open(files[-1]) as f:
        return [tuple(map(float, line.split()[1:4])) for line in f if line.startswith("v ")]


def hull_area(points):
    """Area of the convex hull of 2D points (Andrew's monotone chain)."""
    pts = sorted(set(points))
    if len(pts) < 3:
        return 0.0

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    hull = lower[:-1] + upper[:-1]
    return 0.5 * abs(sum(hull[i][0] * hull[i - 1][1] - hull[i - 1][0] * hull[i][1] for i in range(len(hull))))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("weft")
    parser.add_argument("out")
    parser.add_argument("--cells", default="8,12,16,24,48,96")
    parser.add_argument("--models", default="hinge,shell")
    parser.add_argument("--frames", type=int, default=240)
    parser.add_argument("--backend", default="cpu")
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    width = 1.6  # the drape scene's cloth, m
    rows = []
    for model in args.models.split(","):
        for cells in (int(c) for c in args.cells.split(",")):
            directory = os.path.join(args.out, f"{model}_{cells}")
            os.makedirs(directory, exist_ok=True)
            for old in glob.glob(os.path.join(directory, "frame_*.obj")):
                os.remove(old)
            command = [args.weft, "run", "drape", "--backend", args.backend, "--quiet", "--frames", str(args.frames),
                       "--set", f"cloth.cloth.mesh.grid.cells=[{cells},{cells}]", "--set", f'solver.bending="{model}"',
                       "--out", directory, "--format", "obj", "--stats", os.path.join(directory, "stats.json")]
            for o in args.overrides:
                command += ["--set", o]
            run = subprocess.run(command, capture_output=True, text=True)
            if run.returncode != 0:
                sys.exit(f"membrane_locking.py: {' '.join(command)} failed ({run.returncode}):\n{run.stderr}")
            x = last_frame(directory)
            n = cells + 1
            rim = [x[j * n + i] for j in range(n) for i in range(n) if i in (0, n - 1) or j in (0, n - 1)]
            with open(os.path.join(directory, "stats.json")) as f:
                stats = json.load(f)
            rows.append({
                "model": model,
                "cells": cells,
                "vertices": n * n,
                "footprint": hull_area([(p[0], p[2]) for p in x]) / (width * width),
                "height_m": sum(p[1] for p in x) / len(x),
                "rim_height_m": sum(p[1] for p in rim) / len(rim),
                "seconds": stats.get("simulation_seconds"),
            })
            r = rows[-1]
            print(f"{model:6s} {cells:4d}² {r['vertices']:6d} vertices  footprint {r['footprint']:.3f}  "
                  f"height {r['height_m']:.3f} m  rim {r['rim_height_m']:.3f} m  ({r['seconds']:.1f} s)", flush=True)
    with open(os.path.join(args.out, "membrane_locking.json"), "w") as f:
        json.dump({"scene": "drape", "frames": args.frames, "backend": args.backend, "rows": rows}, f, indent=1)


if __name__ == "__main__":
    main()
