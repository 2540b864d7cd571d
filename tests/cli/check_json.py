#!/usr/bin/env python3
"""Validates the JSON that `weft run --stats` and `weft bench --json` write.

    check_json.py stats FILE STEPS [MESH_DIR]   one run: docs/design.md keys, STEPS steps, frames 0..STEPS on disk
    check_json.py bench FILE SCENES             an array with one object per scene

Strict: NaN and Infinity (which Python's json accepts by default) are errors, since other readers reject them.
"""
import json
import pathlib
import sys

RUN_KEYS = ["scene", "backend", "device", "devices", "vertices", "triangles", "steps", "dt", "substeps", "stage_ms",
            "cg_iterations", "cg_not_converged", "non_finite_frames", "contacts", "impact_zones",
            "remaining_intersections", "memory_bytes", "fps"]
STAGES = ["kinematics", "forces", "assembly", "solve", "update", "step"]


def fail(message):
    print(f"check_json: {message}", file=sys.stderr)
    sys.exit(1)


def reject_constant(name):
    fail(f"non-standard JSON constant {name}")


def load(path):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f, parse_constant=reject_constant)
    except (OSError, json.JSONDecodeError) as e:
        fail(f"{path}: {e}")


def check_run(obj, where):
    for key in RUN_KEYS:
        if key not in obj:
            fail(f"{where}: missing key '{key}'")
    for stage in STAGES:
        entry = obj["stage_ms"].get(stage)
        if not isinstance(entry, dict) or "median" not in entry or "max" not in entry:
            fail(f"{where}: stage_ms.{stage} lacks median/max")
    if obj["vertices"] <= 0 or obj["triangles"] <= 0:
        fail(f"{where}: no vertices or triangles")
    if obj["remaining_intersections"] is not None:
        fail(f"{where}: remaining_intersections should be null until it is computed")
    for key in ["mean", "max", "total"]:
        if key not in obj["cg_iterations"]:
            fail(f"{where}: cg_iterations lacks '{key}'")


def main(argv):
    if len(argv) < 4:
        fail(__doc__)
    kind, path = argv[1], argv[2]
    data = load(path)
    if kind == "stats":
        steps = int(argv[3])
        check_run(data, path)
        if data["steps"] != steps:
            fail(f"{path}: steps is {data['steps']}, expected {steps}")
        for series in ["step_ms", "cg_iterations"]:
            if len(data["series"][series]) != steps:
                fail(f"{path}: series.{series} has {len(data['series'][series])} entries, expected {steps}")
        if len(argv) > 4:
            mesh_dir = pathlib.Path(argv[4])
            for frame in range(steps + 1):
                if not list(mesh_dir.glob(f"frame_{frame:04d}_*")):
                    fail(f"{mesh_dir}: no mesh for frame {frame}")
    elif kind == "bench":
        scenes = int(argv[3])
        if not isinstance(data, list) or len(data) != scenes:
            fail(f"{path}: expected an array of {scenes} objects")
        for i, obj in enumerate(data):
            check_run(obj, f"{path}[{i}]")
    else:
        fail(f"unknown kind '{kind}'")
    print(f"check_json: {path} OK")


if __name__ == "__main__":
    main(sys.argv)
