#!/usr/bin/env python3
"""Draws PLY meshes written by `weft run --out` to a PNG, with nothing but the Python standard library.

A stopgap picture-maker until the Vulkan renderer lands (rendering issue): a perspective camera,
flat two-sided shading (front faces warm, back faces cool), a z-buffer and a ground line.

    tools/render_mesh.py out/demo/frame_0150_flag.ply -o flag.png --eye 1,2.2,4.5 --target 1,2.2,0
Several meshes may be given (e.g. every cloth of one frame); they are drawn into one image.
"""
import argparse
import math
import struct
import sys
import zlib


def read_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.find(b"end_header\n")
    if end < 0:
        sys.exit(f"{path}: not a PLY file (no end_header)")
    header = data[:end].decode("ascii", "replace").splitlines()
    if "format binary_little_endian 1.0" not in header:
        sys.exit(f"{path}: only binary little-endian PLY as written by weft is supported")
    nv = nf = 0
    for line in header:
        parts = line.split()
        if parts[:2] == ["element", "vertex"]:
            nv = int(parts[2])
        elif parts[:2] == ["element", "face"]:
            nf = int(parts[2])
    off = end + len(b"end_header\n")
    verts = [struct.unpack_from("<3f", data, off + 12 * i) for i in range(nv)]
    off += 12 * nv
    faces = []
    for _ in range(nf):
        n = data[off]
        idx = struct.unpack_from(f"<{n}i", data, off + 1)
        off += 1 + 4 * n
        for k in range(1, n - 1):
            faces.append((idx[0], idx[k], idx[k + 1]))
    return verts, faces


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    length = math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) or 1.0
    return (a[0] / length, a[1] / length, a[2] / length)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def write_png(path, width, height, pixels):
    raw = b"".join(b"\x00" + bytes(pixels[y * width * 3:(y + 1) * width * 3]) for y in range(height))

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--eye", default="0,1,3")
    ap.add_argument("--target", default="0,0.5,0")
    ap.add_argument("--fov", type=float, default=45.0)
    ap.add_argument("--size", default="640x400")
    args = ap.parse_args()
    eye = tuple(float(v) for v in args.eye.split(","))
    target = tuple(float(v) for v in args.target.split(","))
    width, height = (int(v) for v in args.size.split("x"))
    fwd = norm(sub(target, eye))
    right = norm(cross(fwd, (0.0, 1.0, 0.0)))
    up = cross(right, fwd)
    focal = 0.5 * height / math.tan(math.radians(args.fov) / 2)
    light = norm((0.4, 0.8, 0.5))

    pixels = bytearray()
    for y in range(height):  # sky gradient
        t = y / height
        pixels += bytes((int(200 - 60 * t), int(215 - 50 * t), int(235 - 40 * t))) * width
    depth = [math.inf] * (width * height)

    def project(p):
        d = sub(p, eye)
        z = dot(d, fwd)
        if z <= 1e-4:
            return None
        return (width / 2 + focal * dot(d, right) / z, height / 2 - focal * dot(d, up) / z, z)

    for path in args.meshes:
        verts, faces = read_ply(path)
        proj = [project(v) for v in verts]
        for a, b, c in faces:
            pa, pb, pc = proj[a], proj[b], proj[c]
            if pa is None or pb is None or pc is None:
                continue
            n = norm(cross(sub(verts[b], verts[a]), sub(verts[c], verts[a])))
            front = dot(n, sub(eye, verts[a])) > 0
            if not front:
                n = (-n[0], -n[1], -n[2])
            shade = 0.35 + 0.65 * max(0.0, dot(n, light))
            base = (220, 90, 60) if front else (70, 110, 190)
            colour = bytes(min(255, int(ch * shade)) for ch in base)
            xmin = max(0, int(min(pa[0], pb[0], pc[0])))
            xmax = min(width - 1, int(max(pa[0], pb[0], pc[0])) + 1)
            ymin = max(0, int(min(pa[1], pb[1], pc[1])))
            ymax = min(height - 1, int(max(pa[1], pb[1], pc[1])) + 1)
            area = (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pb[1] - pa[1]) * (pc[0] - pa[0])
            if abs(area) < 1e-12:
                continue
            for y in range(ymin, ymax + 1):
                for x in range(xmin, xmax + 1):
                    px, py = x + 0.5, y + 0.5
                    w0 = ((pb[0] - px) * (pc[1] - py) - (pb[1] - py) * (pc[0] - px)) / area
                    w1 = ((pc[0] - px) * (pa[1] - py) - (pc[1] - py) * (pa[0] - px)) / area
                    w2 = 1.0 - w0 - w1
                    if w0 < 0 or w1 < 0 or w2 < 0:
                        continue
                    z = w0 * pa[2] + w1 * pb[2] + w2 * pc[2]
                    i = y * width + x
                    if z < depth[i]:
                        depth[i] = z
                        pixels[3 * i:3 * i + 3] = colour
    write_png(args.output, width, height, pixels)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
