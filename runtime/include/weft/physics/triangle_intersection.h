#pragma once
/// @file
/// Exact triangle–triangle intersection test on double coordinates, built only on the exact signs of
/// `orient3d` and `orient2d` (`weft/physics/predicates.h`) and on exact comparisons of coordinates:
/// no constructed points, no tolerances, so the answer is right for every finite input. **Host only**
/// (as the predicates).
///
/// Triangles are *closed* sets: touching counts as intersecting, whether at a single point (a vertex
/// on a face or an edge, two edges crossing) or along an edge. Two triangles of one mesh that share a
/// vertex or an edge therefore always intersect by this test; the whole-mesh check
/// (`runtime/src/collision/intersection_check.h`) leaves such pairs out before calling it.
///
/// Degenerate triangles are handled exactly as the sets they are: three collinear vertices are the
/// segment between the two extreme ones, three equal vertices a point.
///
/// The case analysis, and why it is complete:
/// - **Separating planes** (as in Möller 1997 and Devillers & Guigue 2002): if all three vertices of
///   one triangle lie strictly on one side of the other's plane, they are disjoint. This ends most
///   calls after three to six orient3d.
/// - **Both proper, coplanar.** Both are projected onto the coordinate plane that drops an axis along
///   which the common normal has a nonzero component (chosen by an exact orient2d, so the projection
///   is one-to-one on the plane and intersection is preserved exactly). Two closed convex polygons in
///   the plane are disjoint iff the supporting line of some edge of one has the other polygon strictly
///   on its outer side (separating-axis theorem: the origin lies outside the Minkowski difference
///   A − B, hence strictly outside one of its edge half-planes, and each edge of A − B is an edge of
///   A or of B).
/// - **Both proper, not coplanar.** The intersection of two closed convex sets, if not empty, contains
///   a point on the relative boundary of one of them (an end of the segment A ∩ B on the line where
///   the planes meet). So they intersect iff an edge of A meets B or an edge of B meets A, each a
///   segment–triangle test: a segment crossing the plane strictly meets the triangle iff the three
///   orient3d(p, q, t_i, t_j) are not of mixed sign (each is the 2D orientation of the crossing point
///   against an edge, times one common factor); an endpoint on the plane, or a whole segment in it,
///   goes to the exact 2D tests on the projection.
/// - **A degenerate triangle** is a segment (or a point): segment–triangle as above, or
///   segment–segment: four coplanar points lie in a plane (or line, or point) onto which at least one
///   coordinate projection is one-to-one, so coplanar segments intersect iff all three projections
///   do, each an exact 2D segment test.

#include <algorithm>
#include <initializer_list>

#include "weft/physics/predicates.h"
#include "weft/physics/vec.h"

namespace weft::physics {

namespace tri_detail {

using P3 = Vec3<double>;
using P2 = Vec2<double>;

/// Projection dropping axis k (0: x, 1: y, 2: z); the remaining two keep their cyclic order, so the
/// projected orientation is the sign of the normal's k-th component.
inline P2 project(const P3& p, int k) {
    if (k == 0) return {p.y, p.z};
    if (k == 1) return {p.z, p.x};
    return {p.x, p.y};
}

/// True if the signs include both +1 and −1.
inline bool mixed(int s0, int s1, int s2) { return (s0 > 0 || s1 > 0 || s2 > 0) && (s0 < 0 || s1 < 0 || s2 < 0); }

/// An axis whose projection keeps the triangle proper (its normal has a nonzero component along it),
/// or −1 if the three vertices are collinear (then every projection is degenerate).
inline int projection_axis(const P3& a, const P3& b, const P3& c) {
    for (const int k : {2, 0, 1})
        if (orient2d(project(a, k), project(b, k), project(c, k)) != 0) return k;
    return -1;
}

/// For three collinear points: the indices of the two extreme ones (equal if all three coincide).
/// Along an axis on which the points are not all equal, the coordinate is strictly monotone along
/// the line, so the extremes there are the extremes on the line.
inline void extreme_pair(const P3 t[3], int& lo, int& hi) {
    lo = hi = 0;
    for (int k = 0; k < 3; ++k) {
        if (t[0][k] == t[1][k] && t[1][k] == t[2][k]) continue;
        for (int i = 1; i < 3; ++i) {
            if (t[i][k] < t[lo][k]) lo = i;
            if (t[i][k] > t[hi][k]) hi = i;
        }
        return;
    }
}

// ---- 2D ------------------------------------------------------------------------------------------

/// r on the closed segment pq, given that r is collinear with p and q (or p == q): r within the
/// segment's bounding box.
inline bool within_box(const P2& p, const P2& q, const P2& r) {
    return std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y &&
           r.y <= std::max(p.y, q.y);
}

/// Closed segments pq and rs intersect (either may be a single point).
inline bool segments_intersect_2d(const P2& p, const P2& q, const P2& r, const P2& s) {
    const int o1 = orient2d(p, q, r), o2 = orient2d(p, q, s);
    const int o3 = orient2d(r, s, p), o4 = orient2d(r, s, q);
    if (o1 * o2 < 0 && o3 * o4 < 0) return true;  // proper crossing
    // Touching or collinear: some endpoint lies on the other segment. (If pq is a point, o1 = o2 = 0
    // and the tests below reduce to "r or s equals p" or "p on rs", as they should.)
    return (o1 == 0 && within_box(p, q, r)) || (o2 == 0 && within_box(p, q, s)) || (o3 == 0 && within_box(r, s, p)) ||
           (o4 == 0 && within_box(r, s, q));
}

/// p in the closed triangle t, t proper: the three edge orientations are not of mixed sign (for a
/// proper triangle they cannot all be ≤ 0 outside when it is counter-clockwise, nor ≥ 0 when
/// clockwise, since they add up to twice its signed area).
inline bool point_in_triangle_2d(const P2& p, const P2 t[3]) {
    return !mixed(orient2d(t[0], t[1], p), orient2d(t[1], t[2], p), orient2d(t[2], t[0], p));
}

/// Closed segment pq (possibly a point) meets the closed proper triangle t: an endpoint inside, or
/// else the segment must cross the boundary.
inline bool segment_triangle_2d(const P2& p, const P2& q, const P2 t[3]) {
    return point_in_triangle_2d(p, t) || point_in_triangle_2d(q, t) || segments_intersect_2d(p, q, t[0], t[1]) ||
           segments_intersect_2d(p, q, t[1], t[2]) || segments_intersect_2d(p, q, t[2], t[0]);
}

/// Some edge line of the proper triangle a has all of b strictly on its outer side.
inline bool separated_by_edge_2d(const P2 a[3], const P2 b[3]) {
    const int orientation = orient2d(a[0], a[1], a[2]);  // nonzero: a is proper
    for (int i = 0; i < 3; ++i) {
        const P2& p = a[i];
        const P2& q = a[(i + 1) % 3];
        if (orient2d(p, q, b[0]) * orientation < 0 && orient2d(p, q, b[1]) * orientation < 0 &&
            orient2d(p, q, b[2]) * orientation < 0)
            return true;
    }
    return false;
}

/// Closed proper triangles a and b in the plane intersect (separating-axis theorem over the edges).
inline bool triangles_intersect_2d(const P2 a[3], const P2 b[3]) {
    return !separated_by_edge_2d(a, b) && !separated_by_edge_2d(b, a);
}

// ---- 3D ------------------------------------------------------------------------------------------

/// The closed segment pq (p == q allowed) meets the closed proper triangle t, whose projection axis
/// is k. sp and sq are orient3d(t0, t1, t2, p) and orient3d(t0, t1, t2, q).
inline bool segment_triangle_3d(const P3& p, const P3& q, int sp, int sq, const P3 t[3], int k) {
    if (sp * sq > 0) return false;  // both strictly on one side of the plane
    if (sp != 0 && sq != 0) {
        // The segment crosses the plane at one interior point x; orient3d(p, q, t_i, t_j) is the
        // orientation of (t_i, t_j, x) within the plane times a factor common to all three edges.
        return !mixed(orient3d(p, q, t[0], t[1]), orient3d(p, q, t[1], t[2]), orient3d(p, q, t[2], t[0]));
    }
    const P2 tk[3] = {project(t[0], k), project(t[1], k), project(t[2], k)};
    if (sp != 0) return point_in_triangle_2d(project(q, k), tk);   // only q is on the plane
    if (sq != 0) return point_in_triangle_2d(project(p, k), tk);   // only p is on the plane
    return segment_triangle_2d(project(p, k), project(q, k), tk);  // the whole segment is in the plane
}

/// Closed segments pq and rs (either may be a point) intersect in 3D.
inline bool segments_intersect_3d(const P3& p, const P3& q, const P3& r, const P3& s) {
    if (orient3d(p, q, r, s) != 0) return false;  // not coplanar: disjoint
    for (int k = 0; k < 3; ++k)
        if (!segments_intersect_2d(project(p, k), project(q, k), project(r, k), project(s, k))) return false;
    return true;
}

}  // namespace tri_detail

/// True if the closed triangles (a0, a1, a2) and (b0, b1, b2) have a point in common. Exact for all
/// finite coordinates; touching counts (see the file comment), degenerate triangles are the segments
/// or points they are. Symmetric in the two triangles and independent of the vertex order. Host only.
inline bool triangles_intersect(const Vec3<double> a[3], const Vec3<double> b[3]) {
    using namespace tri_detail;
    // Signs of a's vertices against b's plane, and of b's vertices against a's plane (all zero when
    // that triangle is degenerate, as its "plane" then has a zero normal).
    const int sa[3] = {orient3d(b[0], b[1], b[2], a[0]), orient3d(b[0], b[1], b[2], a[1]),
                       orient3d(b[0], b[1], b[2], a[2])};
    if ((sa[0] > 0 && sa[1] > 0 && sa[2] > 0) || (sa[0] < 0 && sa[1] < 0 && sa[2] < 0)) return false;
    const int sb[3] = {orient3d(a[0], a[1], a[2], b[0]), orient3d(a[0], a[1], a[2], b[1]),
                       orient3d(a[0], a[1], a[2], b[2])};
    if ((sb[0] > 0 && sb[1] > 0 && sb[2] > 0) || (sb[0] < 0 && sb[1] < 0 && sb[2] < 0)) return false;

    const int ka = projection_axis(a[0], a[1], a[2]);
    const int kb = projection_axis(b[0], b[1], b[2]);
    if (ka >= 0 && kb >= 0) {
        if (sa[0] == 0 && sa[1] == 0 && sa[2] == 0) {
            // Coplanar (then sb is all zero too). Projecting along ka is one-to-one on the common plane.
            const P2 a2[3] = {project(a[0], ka), project(a[1], ka), project(a[2], ka)};
            const P2 b2[3] = {project(b[0], ka), project(b[1], ka), project(b[2], ka)};
            return triangles_intersect_2d(a2, b2);
        }
        for (int i = 0; i < 3; ++i) {
            const int j = (i + 1) % 3;
            if (segment_triangle_3d(a[i], a[j], sa[i], sa[j], b, kb)) return true;
        }
        for (int i = 0; i < 3; ++i) {
            const int j = (i + 1) % 3;
            if (segment_triangle_3d(b[i], b[j], sb[i], sb[j], a, ka)) return true;
        }
        return false;
    }
    if (ka >= 0) {  // b is a segment or a point
        int lo = 0, hi = 0;
        extreme_pair(b, lo, hi);
        return segment_triangle_3d(b[lo], b[hi], sb[lo], sb[hi], a, ka);
    }
    if (kb >= 0) {  // a is a segment or a point
        int lo = 0, hi = 0;
        extreme_pair(a, lo, hi);
        return segment_triangle_3d(a[lo], a[hi], sa[lo], sa[hi], b, kb);
    }
    int alo = 0, ahi = 0, blo = 0, bhi = 0;
    extreme_pair(a, alo, ahi);
    extreme_pair(b, blo, bhi);
    return segments_intersect_3d(a[alo], a[ahi], b[blo], b[bhi]);
}

}  // namespace weft::physics
