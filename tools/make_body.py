#!/usr/bin/env python3
"""Writes a low-poly mannequin (torso, neck, head and two legs; no arms, like a dress form on legs) as a
Wavefront OBJ, to be used as a mesh collider under a garment (assets/scenes/garment.toml). Standard
library only.

    tools/make_body.py -o assets/meshes/body.obj

The figure is 1.76 m tall, stands on y = 0 and faces +z; its axis is the y axis. Units are metres.

How it is built, and why the result is a closed 2-manifold by construction:
  * The surface is lofted through horizontal cross-sections (superellipses whose half-width,
    half-depth, centre and roundness vary smoothly with height: monotone cubic interpolation of a few
    key sections, an elliptical dome over the head and under each foot). Rings of vertices are placed
    at equal steps of arc length along the profile, finer where the body is narrow.
  * The torso's lowest ring (the crotch) is split into the two legs "pair of pants" fashion: a
    straight bridge of vertices runs from the back centre to the front centre at x = 0, and each leg's
    first ring is one half of the torso ring plus that bridge. Every bridge edge is then shared by
    exactly one face of each leg, every torso-ring edge by one torso face and one leg face, so the
    surface stays closed and manifold (genus 0: V - E + F = 2).
  * Below the crotch each leg blends from its half of the torso section into its own ellipse over a
    few centimetres. The legs never cross x = 0, so they cannot touch each other; rings at different
    heights bound disjoint slabs, so the surface cannot intersect itself.
  * The top of the head and the sole of each foot are closed by a fan around a pole vertex.
  * Faces are wound counter-clockwise seen from outside (outward normals). The script checks it all
    before writing: each directed edge once and its reverse once, one fan per vertex, Euler
    characteristic 2, positive enclosed volume, no zero-area triangle. tests/scene checks that the
    written OBJ has no self-intersection and fits inside assets/meshes/skirt.obj with clearance.
"""
import argparse
import bisect
import math
import sys

# Key cross-sections of the torso, neck and head, bottom (crotch) to the head's centre:
#   (y, half-width a along x, half-depth b along z, centre z, superellipse exponent p)
TORSO = [
    (0.800, 0.160, 0.112, -0.006, 2.2),  # crotch: this ring is split into the legs
    (0.860, 0.166, 0.122, -0.012, 2.3),
    (0.910, 0.170, 0.122, -0.014, 2.3),  # hips and seat, the widest point
    (0.980, 0.156, 0.110, -0.008, 2.3),
    (1.050, 0.134, 0.097, 0.000, 2.3),   # natural waist
    (1.140, 0.141, 0.104, 0.006, 2.3),
    (1.240, 0.157, 0.114, 0.010, 2.4),   # bust
    (1.340, 0.168, 0.104, 0.000, 2.6),
    (1.400, 0.178, 0.090, -0.010, 2.8),  # shoulders (no arms: rounded off)
    (1.445, 0.148, 0.076, -0.010, 2.6),
    (1.475, 0.082, 0.064, -0.005, 2.2),
    (1.495, 0.058, 0.058, 0.000, 2.0),   # neck
    (1.550, 0.055, 0.058, 0.006, 2.0),
    (1.585, 0.068, 0.080, 0.016, 2.0),   # jaw
    (1.655, 0.078, 0.095, 0.008, 2.0),   # head, widest: the dome starts here
]
HEAD_TOP = 1.760

# Key cross-sections of the +x leg, crotch to the top of the sole dome:
#   (y, centre x, centre z, half-width along x, half-depth along z)
LEG = [
    (0.800, 0.080, -0.006, 0.080, 0.112),  # half of the crotch ring (only the blend's target there)
    (0.760, 0.084, -0.006, 0.078, 0.090),
    (0.660, 0.088, 0.000, 0.071, 0.077),   # thigh
    (0.560, 0.088, 0.005, 0.059, 0.062),
    (0.480, 0.087, 0.010, 0.049, 0.051),   # knee
    (0.400, 0.086, 0.000, 0.049, 0.057),   # calf
    (0.300, 0.085, -0.005, 0.047, 0.054),
    (0.180, 0.084, 0.000, 0.036, 0.040),
    (0.100, 0.084, 0.004, 0.031, 0.035),   # ankle
    (0.060, 0.084, 0.034, 0.040, 0.085),   # foot: the sole dome starts here
]
FOOT_BOTTOM = 0.0
CROTCH_BLEND = 0.10  # m below the crotch over which a leg turns from half a torso section into an ellipse
SPREAD_BLEND = 0.25  # m below the crotch over which a leg's vertices even out around it


def pchip(xs, ys):
    """Monotone piecewise cubic Hermite interpolant (Fritsch-Carlson): smooth, and no overshoot
    between key sections, so a profile never bulges past its keys."""
    n = len(xs)
    h = [xs[i + 1] - xs[i] for i in range(n - 1)]
    d = [(ys[i + 1] - ys[i]) / h[i] for i in range(n - 1)]
    m = [0.0] * n
    m[0], m[-1] = d[0], d[-1]
    for i in range(1, n - 1):
        if d[i - 1] * d[i] <= 0.0:
            m[i] = 0.0
        else:
            w1, w2 = 2 * h[i] + h[i - 1], h[i] + 2 * h[i - 1]
            m[i] = (w1 + w2) / (w1 / d[i - 1] + w2 / d[i])

    def f(x):
        i = min(max(bisect.bisect_right(xs, x) - 1, 0), n - 2)
        t = (x - xs[i]) / h[i]
        t2, t3 = t * t, t * t * t
        return ((2 * t3 - 3 * t2 + 1) * ys[i] + (t3 - 2 * t2 + t) * h[i] * m[i] + (-2 * t3 + 3 * t2) * ys[i + 1]
                + (t3 - t2) * h[i] * m[i + 1])

    return f


def channels(keys):
    """One interpolant per column of a key table, as functions of y (keys sorted by y)."""
    keys = sorted(keys)
    ys = [k[0] for k in keys]
    return [pchip(ys, [k[c] for k in keys]) for c in range(1, len(keys[0]))]


def signed_power(v, e):
    return math.copysign(abs(v) ** e, v)


def smoothstep(t):
    t = min(max(t, 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


def rings_along(profile, spacing):
    """Parameters of rings placed along a profile polyline [(param, radius, y)], evenly in
    arc length / spacing(radius): returns the params of ring 0 (the first point) to the last point."""
    s = [0.0]
    for (_, r0, y0), (_, r1, y1) in zip(profile, profile[1:]):
        ds = math.hypot(r1 - r0, y1 - y0)
        s.append(s[-1] + ds / spacing(0.5 * (r0 + r1)))
    count = max(2, round(s[-1]))
    out = []
    for j in range(count + 1):
        target = s[-1] * j / count
        k = min(max(bisect.bisect_right(s, target) - 1, 0), len(s) - 2)
        t = (target - s[k]) / (s[k + 1] - s[k]) if s[k + 1] > s[k] else 0.0
        out.append(profile[k][0] + t * (profile[k + 1][0] - profile[k][0]))
    return out


def build(around, bridge, scale):
    """Vertices and triangles of the mannequin; `around` vertices per torso ring (even), `bridge`
    segments across the crotch, `scale` multiplies the ring spacing."""
    ta, tb, tz, tp = channels(TORSO)
    lx, lz, lrx, lrz = channels(LEG)
    y_crotch, y_head = TORSO[0][0], TORSO[-1][0]
    y_foot = LEG[-1][0]
    head = TORSO[-1]
    foot = LEG[-1]

    def torso_section(y):
        if y <= y_head:
            return ta(y), tb(y), tz(y), tp(y)
        c = math.sqrt(max(0.0, 1.0 - ((y - y_head) / (HEAD_TOP - y_head)) ** 2))
        return head[1] * c, head[2] * c, head[3], head[4]

    def leg_section(y):
        if y >= y_foot:
            return lx(y), lz(y), lrx(y), lrz(y)
        c = math.sqrt(max(0.0, 1.0 - ((y_foot - y) / (y_foot - FOOT_BOTTOM)) ** 2))
        return foot[1], foot[2], foot[3] * c, foot[4] * c

    def spacing_for(count):
        # Rings 1.4 times as far apart as the vertices around them, within [2, 4] cm.
        return lambda r: scale * min(max(2.0 * math.pi * r / count * 1.4, 0.02), 0.04)

    positions = []

    def add(p):
        positions.append(p)
        return len(positions) - 1

    def ring_point(a, b, zc, p, theta):
        e = 2.0 / p
        return (a * signed_power(math.sin(theta), e), zc + b * signed_power(math.cos(theta), e))

    # --- torso: rings from the crotch up; the dome over the head is sampled by angle ---
    profile = []
    for i in range(1201):
        y = y_crotch + (y_head - y_crotch) * i / 1200
        a, b, _, _ = torso_section(y)
        profile.append((y, 0.5 * (a + b), y))
    for i in range(1, 301):
        y = y_head + (HEAD_TOP - y_head) * math.sin(0.5 * math.pi * i / 300)
        a, b, _, _ = torso_section(y)
        profile.append((y, 0.5 * (a + b), y))
    torso_y = rings_along(profile, spacing_for(around))
    torso_rings = []
    for y in torso_y[:-1]:
        a, b, zc, p = torso_section(y)
        ring = []
        for i in range(around):
            x, z = ring_point(a, b, zc, p, 2.0 * math.pi * i / around)
            ring.append(add((x, y, z)))
        torso_rings.append(ring)
    top = add((0.0, HEAD_TOP, head[3]))

    # --- crotch: the bridge from the back centre to the front centre, at x = 0 ---
    crotch = torso_rings[0]
    half = around // 2
    back, front = positions[crotch[half]], positions[crotch[0]]
    bridge_ids = []  # back to front, interior points only
    for m in range(1, bridge):
        t = m / bridge
        bridge_ids.append(add((0.0, y_crotch, back[2] + (front[2] - back[2]) * t)))
    left_top = crotch[: half + 1] + bridge_ids  # front, the +x side, back, then the bridge to the front
    count = len(left_top)

    # --- the +x leg; the -x leg is its mirror image ---
    cx0, cz0, rx0, rz0 = leg_section(y_crotch)
    start = [positions[v] for v in left_top]
    phi0 = []
    for (x, _, z) in start:
        phi = math.atan2((x - cx0) / rx0, (z - cz0) / rz0)
        while phi0 and phi < phi0[-1]:
            phi += 2.0 * math.pi
        phi0.append(phi)
    even = [phi0[0] + 2.0 * math.pi * i / count for i in range(count)]
    profile = []
    for i in range(1201):
        y = y_crotch - (y_crotch - y_foot) * i / 1200
        _, _, rx, rz = leg_section(y)
        profile.append((y, 0.5 * (rx + rz), y))
    for i in range(1, 301):
        y = y_foot - (y_foot - FOOT_BOTTOM) * math.sin(0.5 * math.pi * i / 300)
        _, _, rx, rz = leg_section(y)
        profile.append((y, 0.5 * (rx + rz), y))
    leg_y = rings_along(profile, spacing_for(count))
    left_rings = [left_top]
    # The -x leg's first ring: the mirror of left_top, reversed so that it runs the same way round
    # (mirroring flips orientation): front, the bridge to the back, back, the -x side to the front.
    right_top = [crotch[0]] + bridge_ids[::-1] + crotch[half:]
    right_rings = [right_top]
    for y in leg_y[1:-1]:
        s = smoothstep((y_crotch - y) / CROTCH_BLEND)
        u = smoothstep((y_crotch - y) / SPREAD_BLEND)
        cx, cz, rx, rz = leg_section(y)
        left, right = [], []
        pts = []
        for i in range(count):
            phi = (1.0 - u) * phi0[i] + u * even[i]
            ex, ez = cx + rx * math.sin(phi), cz + rz * math.cos(phi)
            x = (1.0 - s) * start[i][0] + s * ex
            z = (1.0 - s) * start[i][2] + s * ez
            pts.append((x, z))
        for i in range(count):
            left.append(add((pts[i][0], y, pts[i][1])))
        for i in range(count):
            x, z = pts[(count - i) % count]
            right.append(add((-x, y, z)))
        left_rings.append(left)
        right_rings.append(right)
    left_sole = add((foot[1], FOOT_BOTTOM, foot[2]))
    right_sole = add((-foot[1], FOOT_BOTTOM, foot[2]))

    triangles = []

    def band(lower, upper):
        # Quads (lower_i, lower_i+1, upper_i+1, upper_i), split along the shorter diagonal.
        n = len(lower)
        for i in range(n):
            a, b, c, d = lower[i], lower[(i + 1) % n], upper[(i + 1) % n], upper[i]
            if dist2(positions[a], positions[c]) <= dist2(positions[b], positions[d]):
                triangles.append((a, b, c))
                triangles.append((a, c, d))
            else:
                triangles.append((a, b, d))
                triangles.append((b, c, d))

    def fan(ring, pole, pole_above):
        n = len(ring)
        for i in range(n):
            a, b = ring[i], ring[(i + 1) % n]
            triangles.append((a, b, pole) if pole_above else (pole, b, a))

    for lower, upper in zip(torso_rings, torso_rings[1:]):
        band(lower, upper)
    fan(torso_rings[-1], top, True)
    for rings, sole in ((left_rings, left_sole), (right_rings, right_sole)):
        for upper, lower in zip(rings, rings[1:]):
            band(lower, upper)
        fan(rings[-1], sole, False)

    if signed_volume(positions, triangles) < 0.0:
        triangles = [(a, c, b) for (a, b, c) in triangles]
    return positions, triangles


def dist2(p, q):
    return sum((p[k] - q[k]) ** 2 for k in range(3))


def cross(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def sub(p, q):
    return (p[0] - q[0], p[1] - q[1], p[2] - q[2])


def signed_volume(positions, triangles):
    v = 0.0
    for a, b, c in triangles:
        p, q, r = positions[a], positions[b], positions[c]
        v += (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) + p[2] * (q[0] * r[1] - q[1] * r[0]))
    return v / 6.0


def check(positions, triangles):
    """Raises ValueError unless the mesh is a closed, consistently oriented 2-manifold of genus 0
    with outward normals and no zero-area triangle. Returns (volume, worst triangle quality)."""
    directed = {}
    for t, (a, b, c) in enumerate(triangles):
        for e in ((a, b), (b, c), (c, a)):
            if e[0] == e[1]:
                raise ValueError(f"triangle {t} repeats vertex {e[0]}")
            if e in directed:
                raise ValueError(f"edge {e} is used twice in the same direction (inconsistent winding or non-manifold)")
            directed[e] = t
    for (a, b) in directed:
        if (b, a) not in directed:
            raise ValueError(f"edge {(a, b)} has one face only (a hole)")
    # One fan per vertex: the faces around a vertex form a single cycle.
    nxt = {}
    for a, b, c in triangles:
        for v, p, q in ((a, b, c), (b, c, a), (c, a, b)):
            nxt.setdefault(v, {})[p] = q
    for v, links in nxt.items():
        start = next(iter(links))
        p, steps = start, 0
        while True:
            p = links[p]
            steps += 1
            if p == start:
                break
            if steps > len(links):
                raise ValueError(f"vertex {v}: its faces do not close into one fan")
        if steps != len(links):
            raise ValueError(f"vertex {v}: its faces form {len(links)} links but one fan has {steps} (non-manifold vertex)")
    if len(nxt) != len(positions):
        raise ValueError(f"{len(positions) - len(nxt)} vertices belong to no triangle")
    euler = len(positions) - len(directed) // 2 + len(triangles)
    if euler != 2:
        raise ValueError(f"Euler characteristic {euler}, expected 2 (a closed surface of genus 0)")
    volume = signed_volume(positions, triangles)
    if volume <= 0.0:
        raise ValueError(f"enclosed volume {volume} is not positive (normals point inwards)")
    worst = float("inf")
    for t, (a, b, c) in enumerate(triangles):
        p, q, r = positions[a], positions[b], positions[c]
        n = cross(sub(q, p), sub(r, p))
        area2 = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
        longest = max(dist2(p, q), dist2(q, r), dist2(r, p))
        quality = area2 / longest  # 2·area / longest², sqrt(3)/2 for an equilateral triangle
        if quality < 1e-6:
            raise ValueError(f"triangle {t} is degenerate (2·area / longest edge² = {quality:g})")
        worst = min(worst, quality)
    return volume, worst


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--around", type=int, default=32, help="vertices around each torso ring, even (default 32)")
    ap.add_argument("--bridge", type=int, default=6, help="segments across the crotch (default 6)")
    ap.add_argument("--spacing", type=float, default=1.0,
                    help="multiplies the distance between rings: above 1 coarser, below 1 finer (default 1)")
    ap.add_argument("-o", "--output", default="-", help="output file (default stdout)")
    a = ap.parse_args()
    if a.around < 8 or a.around % 2 != 0:
        ap.error("--around must be even and at least 8")
    if a.bridge < 2:
        ap.error("--bridge must be at least 2")
    if not 0.2 <= a.spacing <= 5.0:
        ap.error("--spacing must be in [0.2, 5]")

    positions, triangles = build(a.around, a.bridge, a.spacing)
    # Check what is written: positions as the file will hold them (10 µm).
    positions = [tuple(round(c, 5) + 0.0 for c in p) for p in positions]
    try:
        volume, worst = check(positions, triangles)
    except ValueError as e:
        print(f"make_body.py: the mesh is broken: {e}", file=sys.stderr)
        return 1
    lo = [min(p[k] for p in positions) for k in range(3)]
    hi = [max(p[k] for p in positions) for k in range(3)]
    out = [
        "# weft mannequin (mesh collider), generated by tools/make_body.py",
        f"# around {a.around} bridge {a.bridge} spacing {a.spacing}",
        f"# vertices {len(positions)}, triangles {len(triangles)}; closed 2-manifold of genus 0, outward normals",
        f"# bounds [{lo[0]:.3f}, {lo[1]:.3f}, {lo[2]:.3f}] to [{hi[0]:.3f}, {hi[1]:.3f}, {hi[2]:.3f}] m, "
        f"volume {volume * 1000:.1f} L, worst 2*area/longest^2 {worst:.3f}",
        "o body",
    ]
    out += [f"v {x:.5f} {y:.5f} {z:.5f}" for (x, y, z) in positions]
    out += [f"f {i + 1} {j + 1} {k + 1}" for (i, j, k) in triangles]
    text = "\n".join(out) + "\n"
    if a.output == "-":
        sys.stdout.write(text)
    else:
        with open(a.output, "w", encoding="ascii", newline="\n") as f:
            f.write(text)
    print(f"make_body.py: {len(positions)} vertices, {len(triangles)} triangles, volume {volume * 1000:.1f} L, "
          f"height {hi[1] - lo[1]:.3f} m, hips {hi[0] - lo[0]:.3f} m wide", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
