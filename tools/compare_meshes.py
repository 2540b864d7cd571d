#!/usr/bin/env python3
"""Largest vertex distance between two OBJ files of the same mesh (e.g. the same frame written by
`weft run --format obj` on two backends), relative to the first mesh's bounding-box diagonal.

    tools/compare_meshes.py A.obj B.obj
"""
import math
import sys


def vertices(path):
    out = []
    with open(path, encoding="ascii") as f:
        for line in f:
            if line.startswith("v "):
                out.append(tuple(float(x) for x in line.split()[1:4]))
    return out


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    a, b = vertices(argv[1]), vertices(argv[2])
    if len(a) != len(b) or not a:
        sys.exit(f"compare_meshes: {argv[1]} has {len(a)} vertices, {argv[2]} has {len(b)}")
    worst = max(math.dist(p, q) for p, q in zip(a, b))
    lo = [min(p[k] for p in a) for k in range(3)]
    hi = [max(p[k] for p in a) for k in range(3)]
    diag = math.dist(lo, hi)
    print(f"{len(a)} vertices: max distance {worst:.3e} m = {worst / diag:.3e} of the bounding-box diagonal {diag:.3f} m")


if __name__ == "__main__":
    main(sys.argv)
