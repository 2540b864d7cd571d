#!/usr/bin/env python3
"""Writes a small rigged character as glTF 2.0 (one .gltf file, its buffer embedded): a blocky
runner 1.75 m tall, facing +Z, Y up, metres, with a skeleton of 12 joints, linear-blend skin weights
and two clips, "run" (a 0.8 s loop) and "jump" (1.0 s). Weft's own asset, generated here so that no
third-party model ships with the project; it is a collider for cloth, so it is built from closed
boxes, one chain per limb, the boxes' end rings weighted half to the next joint so that knees and
elbows bend smoothly.

    tools/make_character.py [OUT.gltf]      (default: assets/characters/runner.gltf)

Only the Python standard library is used.
"""

import base64
import json
import math
import struct
import sys
from pathlib import Path

# Joints: name, parent, rest translation relative to the parent (m). Parents come first.
JOINTS = [
    ("hips", -1, (0.0, 0.95, 0.0)),
    ("spine", 0, (0.0, 0.12, 0.0)),
    ("chest", 1, (0.0, 0.22, 0.0)),
    ("head", 2, (0.0, 0.28, 0.0)),
    ("upper_arm.L", 2, (0.21, 0.20, 0.0)),
    ("forearm.L", 4, (0.0, -0.29, 0.0)),
    ("upper_arm.R", 2, (-0.21, 0.20, 0.0)),
    ("forearm.R", 6, (0.0, -0.29, 0.0)),
    ("thigh.L", 0, (0.10, -0.06, 0.0)),
    ("shin.L", 8, (0.0, -0.43, 0.0)),
    ("thigh.R", 0, (-0.10, -0.06, 0.0)),
    ("shin.R", 10, (0.0, -0.43, 0.0)),
]
INDEX = {name: k for k, (name, _, _) in enumerate(JOINTS)}


def world_positions():
    out = []
    for name, parent, t in JOINTS:
        base = out[parent] if parent >= 0 else (0.0, 0.0, 0.0)
        out.append(tuple(b + d for b, d in zip(base, t)))
    return out


WORLD = world_positions()

# Boxes: joint, the joint whose end ring is shared half-and-half (or None), centre of the box's bottom
# and top along Y in the joint's frame (m), half width X and half depth Z, segments along Y.
BOXES = [
    ("hips", "spine", -0.08, 0.12, 0.16, 0.11, 2),
    ("spine", "chest", 0.0, 0.22, 0.15, 0.10, 2),
    ("chest", None, 0.0, 0.30, 0.19, 0.12, 2),
    ("head", None, 0.02, 0.26, 0.10, 0.11, 2),
    ("upper_arm.L", "forearm.L", -0.29, 0.02, 0.05, 0.05, 3),
    ("forearm.L", None, -0.30, 0.0, 0.045, 0.045, 3),
    ("upper_arm.R", "forearm.R", -0.29, 0.02, 0.05, 0.05, 3),
    ("forearm.R", None, -0.30, 0.0, 0.045, 0.045, 3),
    ("thigh.L", "shin.L", -0.43, 0.02, 0.07, 0.07, 3),
    ("shin.L", None, -0.45, 0.0, 0.055, 0.06, 3),
    ("thigh.R", "shin.R", -0.43, 0.02, 0.07, 0.07, 3),
    ("shin.R", None, -0.45, 0.0, 0.055, 0.06, 3),
]


def build_mesh():
    positions, joints, weights, triangles = [], [], [], []
    for name, blend, y0, y1, hx, hz, segments in BOXES:
        j = INDEX[name]
        cx, cy, cz = WORLD[j]
        first = len(positions)
        rings = segments + 1
        corners = [(-hx, -hz), (hx, -hz), (hx, hz), (-hx, hz)]
        for r in range(rings):
            y = y0 + (y1 - y0) * r / segments
            # The ring nearest the child joint is shared: the bottom of a limb hanging down, the top
            # of the hips and the spine.
            above = blend is not None and WORLD[INDEX[blend]][1] > cy
            shared = blend is not None and r == (segments if above else 0)
            for dx, dz in corners:
                positions.append((cx + dx, cy + y, cz + dz))
                if shared:
                    joints.append((j, INDEX[blend], 0, 0))
                    weights.append((0.5, 0.5, 0.0, 0.0))
                else:
                    joints.append((j, 0, 0, 0))
                    weights.append((1.0, 0.0, 0.0, 0.0))
        # Sides (outward, counter-clockwise seen from outside), then the two caps.
        for r in range(segments):
            for c in range(4):
                a = first + 4 * r + c
                b = first + 4 * r + (c + 1) % 4
                a2, b2 = a + 4, b + 4
                triangles += [(a, a2, b), (b, a2, b2)]
        bottom, top = first, first + 4 * segments
        triangles += [(bottom, bottom + 1, bottom + 2), (bottom, bottom + 2, bottom + 3)]
        triangles += [(top, top + 2, top + 1), (top, top + 3, top + 2)]
    return positions, joints, weights, triangles


def quat_x(degrees):
    a = math.radians(degrees) / 2.0
    return (math.sin(a), 0.0, 0.0, math.cos(a))  # glTF order x, y, z, w


def run_clip():
    """A 0.8 s loop: legs and arms swing in opposition, knees and elbows bend, the hips bob."""
    times = [0.0, 0.2, 0.4, 0.6, 0.8]
    swing = [35.0, 0.0, -35.0, 0.0, 35.0]  # the left thigh forward (−X rotation lifts it toward +Z)
    tracks = {}
    tracks["thigh.L"] = ("rotation", times, [quat_x(-s) for s in swing])
    tracks["thigh.R"] = ("rotation", times, [quat_x(s) for s in swing])
    tracks["shin.L"] = ("rotation", times, [quat_x(b) for b in [10.0, 60.0, 20.0, 5.0, 10.0]])
    tracks["shin.R"] = ("rotation", times, [quat_x(b) for b in [20.0, 5.0, 10.0, 60.0, 20.0]])
    tracks["upper_arm.L"] = ("rotation", times, [quat_x(0.8 * s) for s in swing])
    tracks["upper_arm.R"] = ("rotation", times, [quat_x(-0.8 * s) for s in swing])
    tracks["forearm.L"] = ("rotation", times, [quat_x(-50.0)] * 5)
    tracks["forearm.R"] = ("rotation", times, [quat_x(-50.0)] * 5)
    hips = WORLD[INDEX["hips"]]
    tracks["hips"] = ("translation", times, [(hips[0], hips[1] + dy, hips[2]) for dy in [0.0, 0.035, 0.0, 0.035, 0.0]])
    return "run", tracks


def jump_clip():
    """1.0 s: crouch, push off, tuck in the air, land. Shaped around the clothes it wears: the arms
    swing forward and up, never back (swung back in the crouch they went through the cape and threw
    it off the shoulders), and the thighs rise 20-25 degrees (at 45-60 they pinched the skirt against
    the hips and the skirt's own folds went through each other), and the hips rise 0.18 m over the
    root's own jump (0.35 m made the crouch's first frame a 5-7 s one for the skirt pinned to
    them): examples/README.md."""
    times = [0.0, 0.25, 0.45, 0.7, 1.0]
    hips = WORLD[INDEX["hips"]]
    tracks = {}
    tracks["hips"] = ("translation", times, [(hips[0], hips[1] + dy, hips[2]) for dy in [0.0, -0.17, 0.12, 0.18, 0.0]])
    for side in ("L", "R"):
        tracks["thigh." + side] = ("rotation", times, [quat_x(-a) for a in [0.0, 20.0, 0.0, 25.0, 0.0]])
        tracks["shin." + side] = ("rotation", times, [quat_x(a) for a in [0.0, 80.0, 0.0, 90.0, 0.0]])
        tracks["upper_arm." + side] = ("rotation", times, [quat_x(a) for a in [0.0, -30.0, -150.0, -120.0, 0.0]])
    return "jump", tracks


class Buffer:
    def __init__(self):
        self.data = bytearray()
        self.views, self.accessors = [], []

    def add(self, fmt, values, count, kind, component, target=None, minmax=None):
        while len(self.data) % 4:
            self.data.append(0)
        offset = len(self.data)
        for v in values:
            self.data += struct.pack("<" + fmt, *(v if isinstance(v, (tuple, list)) else (v,)))
        view = {"buffer": 0, "byteOffset": offset, "byteLength": len(self.data) - offset}
        if target is not None:
            view["target"] = target
        self.views.append(view)
        accessor = {"bufferView": len(self.views) - 1, "componentType": component, "count": count, "type": kind}
        if minmax is not None:
            accessor["min"], accessor["max"] = minmax
        self.accessors.append(accessor)
        return len(self.accessors) - 1


def main():
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent / "assets/characters/runner.gltf"
    positions, joints, weights, triangles = build_mesh()
    buf = Buffer()
    FLOAT, USHORT, UINT = 5126, 5123, 5125
    lo = [min(p[k] for p in positions) for k in range(3)]
    hi = [max(p[k] for p in positions) for k in range(3)]
    pos = buf.add("3f", positions, len(positions), "VEC3", FLOAT, 34962, (lo, hi))
    jnt = buf.add("4H", joints, len(joints), "VEC4", USHORT, 34962)
    wgt = buf.add("4f", weights, len(weights), "VEC4", FLOAT, 34962)
    idx = buf.add("3I", triangles, 3 * len(triangles), "SCALAR", UINT, 34963)
    # Inverse bind matrices: the bind pose has no rotation, so each is a translation by −world (column-major).
    ibm = [(1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -w[0], -w[1], -w[2], 1) for w in WORLD]
    ibm_accessor = buf.add("16f", ibm, len(ibm), "MAT4", FLOAT)

    nodes = []
    for k, (name, parent, t) in enumerate(JOINTS):
        node = {"name": name, "translation": list(t)}
        children = [c for c, (_, p, _) in enumerate(JOINTS) if p == k]
        if children:
            node["children"] = children
        nodes.append(node)
    mesh_node = len(nodes)
    nodes.append({"name": "runner", "mesh": 0, "skin": 0})

    animations = []
    for name, tracks in (run_clip(), jump_clip()):
        samplers, channels = [], []
        for joint, (path, times, values) in tracks.items():
            t_acc = buf.add("f", times, len(times), "SCALAR", FLOAT, None, ([min(times)], [max(times)]))
            kind, fmt = ("VEC4", "4f") if path == "rotation" else ("VEC3", "3f")
            v_acc = buf.add(fmt, values, len(values), kind, FLOAT)
            samplers.append({"input": t_acc, "output": v_acc, "interpolation": "LINEAR"})
            channels.append({"sampler": len(samplers) - 1, "target": {"node": INDEX[joint], "path": path}})
        animations.append({"name": name, "samplers": samplers, "channels": channels})

    gltf = {
        "asset": {"version": "2.0", "generator": "weft tools/make_character.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, mesh_node]}],
        "nodes": nodes,
        "meshes": [{"name": "runner", "primitives": [{"attributes": {"POSITION": pos, "JOINTS_0": jnt, "WEIGHTS_0": wgt},
                                                      "indices": idx, "mode": 4}]}],
        "skins": [{"name": "runner", "joints": list(range(len(JOINTS))), "inverseBindMatrices": ibm_accessor,
                   "skeleton": 0}],
        "animations": animations,
        "accessors": buf.accessors,
        "bufferViews": buf.views,
        "buffers": [{"byteLength": len(buf.data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(buf.data)).decode()}],
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(gltf, indent=1) + "\n")
    print(f"{out}: {len(positions)} vertices, {len(triangles)} triangles, {len(JOINTS)} joints, clips run and jump")


if __name__ == "__main__":
    main()
