#!/usr/bin/env python3
"""Writes quad.gltf: a unit square (two triangles) as glTF 2.0 JSON with its buffer embedded as a
base64 data URI, placed by a node translation of +1 m along Y (the loader must apply node transforms).
Standard library only: python3 make_gltf.py > quad.gltf"""
import base64
import json
import struct
import sys

positions = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 0.0, -1.0), (0.0, 0.0, -1.0)]
indices = [0, 1, 2, 0, 2, 3]
pos_bytes = b"".join(struct.pack("<3f", *p) for p in positions)
idx_bytes = struct.pack("<6H", *indices) + b"\0\0"  # pad to a multiple of 4
blob = pos_bytes + idx_bytes
doc = {
    "asset": {"version": "2.0", "generator": "weft tests/scene/data/make_gltf.py"},
    "scene": 0,
    "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0, "translation": [0.0, 1.0, 0.0]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
    "buffers": [{"byteLength": len(blob),
                 "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode("ascii")}],
    "bufferViews": [
        {"buffer": 0, "byteOffset": 0, "byteLength": len(pos_bytes), "target": 34962},
        {"buffer": 0, "byteOffset": len(pos_bytes), "byteLength": 12, "target": 34963},
    ],
    "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
         "min": [0.0, 0.0, -1.0], "max": [1.0, 0.0, 0.0]},
        {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
    ],
}
json.dump(doc, sys.stdout, indent=1)
sys.stdout.write("\n")
