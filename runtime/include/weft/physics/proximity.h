#pragma once
/// @file
/// Closest points between cloth primitives at one instant: point–segment, point–triangle (the
/// vertex–face pair) and segment–segment (the edge–edge pair). Each query returns the distance (m),
/// the parameters of the closest points, the closest points themselves and a unit contact normal.
///
/// Method: the minimum of a distance over a convex polytope is either at the unconstrained
/// minimiser (when it lies inside) or on the boundary (Ericson 2005, "Real-Time Collision
/// Detection" §5.1). Instead of Ericson's region case analysis, every query here evaluates the
/// interior candidate *and* every boundary candidate and keeps the nearest. That costs a few more
/// flops but is what makes the queries robust: a sliver triangle or two nearly parallel edges make
/// the interior solve ill-conditioned, and a badly rounded interior candidate is still a point of the
/// primitive (so it can only overestimate the distance) while the boundary candidates — point–segment
/// distances, always well-conditioned — bound the error by the width of the sliver. Degenerate
/// primitives (zero-area triangles, zero-length edges, parallel edges) need no special case: the
/// interior candidate is skipped when its determinant is zero, and a degenerate polytope is the
/// union of its boundary segments.
///
/// Never NaN for finite inputs whose squared coordinate differences do not overflow (|x| well below
/// √max of the scalar): parameters are clamped with comparisons that send a NaN to 0, and the normal
/// falls back to a fixed direction when the distance is zero.

#include <cmath>

#include "weft/math/host_device.h"
#include "weft/physics/scalar.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Closest point on the segment [a, b] to a point.
template <typename T>
struct PointSegmentProximity {
    T distance;       ///< |p − closest| (m)
    T s;              ///< segment parameter in [0, 1]: closest = a + s·(b − a); 0 for a zero-length segment
    Vec3<T> closest;  ///< closest point on the segment (m)
    Vec3<T> normal;   ///< unit vector from `closest` towards p (any unit vector ⟂ the segment if p is on it)
};

/// Closest point on the triangle (a, b, c) to a point (vertex–face proximity).
template <typename T>
struct PointTriangleProximity {
    T distance;       ///< |p − closest| (m)
    T u, v;           ///< barycentric parameters: closest = (1 − u − v)·a + u·b + v·c, u, v ≥ 0, u + v ≤ 1
    Vec3<T> closest;  ///< closest point on the triangle (m)
    /// Unit vector from `closest` towards p. When p lies on the triangle (distance 0): the triangle's
    /// normal (b − a)×(c − a), normalised; for a zero-area triangle a unit vector ⟂ its longest edge.
    Vec3<T> normal;
};

/// Closest points between the segments [e0, e1] and [f0, f1] (edge–edge proximity).
template <typename T>
struct EdgeEdgeProximity {
    T distance;         ///< |closest_e − closest_f| (m)
    T u;                ///< parameter on e: closest_e = e0 + u·(e1 − e0), in [0, 1]
    T v;                ///< parameter on f: closest_f = f0 + v·(f1 − f0), in [0, 1]
    Vec3<T> closest_e;  ///< closest point on e (m)
    Vec3<T> closest_f;  ///< closest point on f (m)
    /// Unit vector from closest_f towards closest_e. When the edges touch (distance 0): the
    /// normalised (e1 − e0)×(f1 − f0); for parallel or zero-length edges a unit vector ⟂ the longer edge.
    Vec3<T> normal;
};

namespace detail {

/// A unit vector perpendicular to `d` (the cross product with the coordinate axis least aligned
/// with d, which is never parallel to it); (0, 0, 1) when d is zero.
template <typename T>
WEFT_HD inline Vec3<T> any_perpendicular(Vec3<T> d) {
    const T ax = d.x < T(0) ? -d.x : d.x;
    const T ay = d.y < T(0) ? -d.y : d.y;
    const T az = d.z < T(0) ? -d.z : d.z;
    Vec3<T> axis{T(0), T(0), T(1)};
    if (ax <= ay && ax <= az) {
        axis = Vec3<T>{T(1), T(0), T(0)};
    } else if (ay <= az) {
        axis = Vec3<T>{T(0), T(1), T(0)};
    }
    const Vec3<T> n = normalized(cross(d, axis));
    return length_squared(n) > T(0) ? n : Vec3<T>{T(0), T(0), T(1)};
}

/// `d` normalised, or `fallback` when d is zero.
template <typename T>
WEFT_HD inline Vec3<T> direction_or(Vec3<T> d, Vec3<T> fallback) {
    const Vec3<T> n = normalized(d);
    return length_squared(n) > T(0) ? n : fallback;
}

/// x clamped to [0, 1], with NaN sent to 0 (every comparison with NaN is false).
template <typename T>
WEFT_HD constexpr T clamp01(T x) {
    return x > T(0) ? (x < T(1) ? x : T(1)) : T(0);
}

/// Parameter s ∈ [0, 1] of the point of [a, b] closest to p: the clamped projection
/// s = (p − a)·(b − a)/|b − a|², and 0 for a zero-length segment.
template <typename T>
WEFT_HD inline T segment_parameter(Vec3<T> p, Vec3<T> a, Vec3<T> b) {
    const Vec3<T> e = b - a;
    const T ee = dot(e, e);
    if (!(ee > T(0))) return T(0);
    return clamp01(dot(p - a, e) / ee);
}

}  // namespace detail

/// Closest point on the segment [a, b] to p (m). Handles a zero-length segment (s = 0).
template <typename T>
WEFT_HD inline PointSegmentProximity<T> point_segment_proximity(Vec3<T> p, Vec3<T> a, Vec3<T> b) {
    PointSegmentProximity<T> r{};
    r.s = detail::segment_parameter(p, a, b);
    r.closest = a + r.s * (b - a);
    const Vec3<T> d = p - r.closest;
    r.distance = length(d);
    r.normal = detail::direction_or(d, detail::any_perpendicular(b - a));
    return r;
}

/// Closest point on the triangle (a, b, c) to p (m), for the vertex–face pair. Robust for
/// zero-area triangles (collinear or coincident vertices): the closest point is then on an edge.
template <typename T>
WEFT_HD inline PointTriangleProximity<T> point_triangle_proximity(Vec3<T> p, Vec3<T> a, Vec3<T> b, Vec3<T> c) {
    const Vec3<T> ab = b - a;
    const Vec3<T> ac = c - a;
    const Vec3<T> ap = p - a;
    const Vec3<T> n = cross(ab, ac);
    const T nn = dot(n, n);

    // Boundary candidates: the three edges, each with its own well-conditioned projection.
    T best_u = detail::segment_parameter(p, a, b);  // edge ab: (u, v) = (s, 0)
    T best_v = T(0);
    Vec3<T> best_q = a + best_u * ab;
    T best_d2 = length_squared(p - best_q);
    {
        const T s = detail::segment_parameter(p, a, c);  // edge ac: (0, s)
        const Vec3<T> q = a + s * ac;
        const T d2 = length_squared(p - q);
        if (d2 < best_d2) {
            best_d2 = d2;
            best_u = T(0);
            best_v = s;
            best_q = q;
        }
    }
    {
        const T s = detail::segment_parameter(p, b, c);  // edge bc: (1 − s, s)
        const Vec3<T> q = b + s * (c - b);
        const T d2 = length_squared(p - q);
        if (d2 < best_d2) {
            best_d2 = d2;
            best_u = T(1) - s;
            best_v = s;
            best_q = q;
        }
    }
    // Interior candidate: the projection onto the plane, by Cramer's rule written with cross
    // products (ap = u·ab + v·ac + h·n ⇒ u = ((ap × ac)·n)/|n|², v = ((ab × ap)·n)/|n|²), which keeps
    // its accuracy for slivers better than the Gram determinant (ab·ab)(ac·ac) − (ab·ac)². A rejected
    // or NaN/inf candidate (|n|² underflowed) fails the range test and is skipped.
    if (nn > T(0)) {
        const T u = dot(cross(ap, ac), n) / nn;
        const T v = dot(cross(ab, ap), n) / nn;
        if (u >= T(0) && v >= T(0) && u + v <= T(1)) {
            const Vec3<T> q = a + u * ab + v * ac;
            const T d2 = length_squared(p - q);
            if (d2 <= best_d2) {
                best_d2 = d2;
                best_u = u;
                best_v = v;
                best_q = q;
            }
        }
    }

    PointTriangleProximity<T> r{};
    r.u = best_u;
    r.v = best_v;
    r.closest = best_q;
    const Vec3<T> d = p - best_q;
    r.distance = length(d);
    // The longest edge of a zero-area triangle spans it, so ⟂ it is ⟂ the whole triangle.
    Vec3<T> longest = ab;
    if (length_squared(ac) > length_squared(longest)) longest = ac;
    if (length_squared(c - b) > length_squared(longest)) longest = c - b;
    r.normal = detail::direction_or(d, detail::direction_or(n, detail::any_perpendicular(longest)));
    return r;
}

/// Closest points of the segments [e0, e1] and [f0, f1] (m), for the edge–edge pair. Robust for
/// parallel, collinear, crossing and zero-length edges. For parallel edges the closest pair is not
/// unique; an endpoint of one edge is returned.
template <typename T>
WEFT_HD inline EdgeEdgeProximity<T> edge_edge_proximity(Vec3<T> e0, Vec3<T> e1, Vec3<T> f0, Vec3<T> f1) {
    const Vec3<T> de = e1 - e0;
    const Vec3<T> df = f1 - f0;
    const Vec3<T> r0 = e0 - f0;

    // Boundary candidates: each endpoint against the other segment. For parallel edges the distance
    // is constant along the overlap, so an endpoint always attains the minimum.
    T best_u = T(0);
    T best_v = detail::segment_parameter(e0, f0, f1);
    Vec3<T> best_pe = e0;
    Vec3<T> best_pf = f0 + best_v * df;
    T best_d2 = length_squared(best_pe - best_pf);
    {
        const T s = detail::segment_parameter(e1, f0, f1);
        const Vec3<T> pf = f0 + s * df;
        const T d2 = length_squared(e1 - pf);
        if (d2 < best_d2) {
            best_d2 = d2;
            best_u = T(1);
            best_v = s;
            best_pe = e1;
            best_pf = pf;
        }
    }
    {
        const T s = detail::segment_parameter(f0, e0, e1);
        const Vec3<T> pe = e0 + s * de;
        const T d2 = length_squared(pe - f0);
        if (d2 < best_d2) {
            best_d2 = d2;
            best_u = s;
            best_v = T(0);
            best_pe = pe;
            best_pf = f0;
        }
    }
    {
        const T s = detail::segment_parameter(f1, e0, e1);
        const Vec3<T> pe = e0 + s * de;
        const T d2 = length_squared(pe - f1);
        if (d2 < best_d2) {
            best_d2 = d2;
            best_u = s;
            best_v = T(1);
            best_pe = pe;
            best_pf = f1;
        }
    }
    // Interior candidate: the common perpendicular. With n = de × df, the gap r0 + u·de − v·df is ∥ n
    // at the optimum; dotting with df × n and de × n (each ⟂ one edge and n) isolates u and v:
    // u = −((df × n)·r0)/|n|², v = −((de × n)·r0)/|n|². |n|² = |de|²|df|² sin²θ is accurate, unlike
    // the Gram determinant (de·de)(df·df) − (de·df)² that cancels for nearly parallel edges.
    const Vec3<T> n = cross(de, df);
    const T nn = dot(n, n);
    if (nn > T(0)) {
        const T u = -dot(cross(df, n), r0) / nn;
        const T v = -dot(cross(de, n), r0) / nn;
        if (u >= T(0) && u <= T(1) && v >= T(0) && v <= T(1)) {
            const Vec3<T> pe = e0 + u * de;
            const Vec3<T> pf = f0 + v * df;
            const T d2 = length_squared(pe - pf);
            if (d2 <= best_d2) {
                best_d2 = d2;
                best_u = u;
                best_v = v;
                best_pe = pe;
                best_pf = pf;
            }
        }
    }

    EdgeEdgeProximity<T> res{};
    res.u = best_u;
    res.v = best_v;
    res.closest_e = best_pe;
    res.closest_f = best_pf;
    const Vec3<T> d = best_pe - best_pf;
    res.distance = length(d);
    const Vec3<T> longer = length_squared(de) >= length_squared(df) ? de : df;
    res.normal = detail::direction_or(d, detail::direction_or(n, detail::any_perpendicular(longer)));
    return res;
}

/// A contact pair's closest points as the gap function g = Σ_i weight[i]·x[i] over its four vertices
/// uses them: vertex–face (x[0] against the triangle x[1..3]): weights (1, −(1 − u − v), −u, −v);
/// edge–edge (x[0]x[1] against x[2]x[3]): (1 − a, a, −(1 − b), −b). The normal points from the second
/// primitive towards the first. The one definition of the pair weights the CPU's narrow phase and
/// contact terms share.
template <typename T>
struct PairClosestPoints {
    T weight[4];
    Vec3<T> normal;  ///< unit
    T distance;      ///< m
};

template <typename T>
WEFT_HD inline PairClosestPoints<T> pair_closest_points(bool edge_edge, const Vec3<T> (&x)[4]) {
    if (edge_edge) {
        const auto q = edge_edge_proximity(x[0], x[1], x[2], x[3]);
        return {{T(1) - q.u, q.u, -(T(1) - q.v), -q.v}, q.normal, q.distance};
    }
    const auto q = point_triangle_proximity(x[0], x[1], x[2], x[3]);
    return {{T(1), -(T(1) - q.u - q.v), -q.u, -q.v}, q.normal, q.distance};
}

}  // namespace weft::physics
