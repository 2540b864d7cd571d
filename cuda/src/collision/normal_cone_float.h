#pragma once
/// @file
/// The arithmetic of the normal-cone test in float, with rigorous rounding allowances: the device
/// twin of runtime/src/collision/normal_cone.cpp (continuous normal cones, Tang, Curtis, Yoon &
/// Manocha 2009) and runtime/src/collision/contour_test.cpp (the continuous 2D contour test of
/// Volino & Magnenat-Thalmann 1994), as used by PSCC (Tang, Liu, Tong & Manocha 2018). Single
/// source: the kernels of normal_cone_gpu.cu call these functions, and host tests call the same
/// ones to check the bounds without a device.
///
/// Soundness, not agreement, is the contract: every cone computed here contains the normal of each
/// of its triangles at every instant of the step, and a contour said to stay simple does, in exact
/// arithmetic on the given float positions. A node the float test passes is therefore free of
/// self-collision by the same theorem as on the CPU (normal_cone_front.h), whatever the CPU's double
/// version decides for it. Where the CPU version allows a few ε of double, this one allows a few ε of
/// float (ε = 2⁻²³), derived the same way, with the same factor of about four to spare:
///   - triangle cones: the rounding of the Bernstein control vectors is bounded by 2·16ε·m₁m₂ per
///     cross product (m the largest edge components; the error analysis of normal_cone.cpp, which
///     holds with or without fused multiply-adds), turned into an angle by 1.6·err/|N| ≥ asin;
///   - every angle from atan2 (device atan2f: 3 ulp) and every merge is widened by kSlack = 64ε rad
///     (each errs by about 10ε: the dot and cross products of nearly unit vectors, atan2, the tangent
///     cone's axis);
///   - a merge whose axes are less than about 1e-3 rad apart takes the cone about the first axis
///     instead of the tangent cone (φ below the rounding of φ would turn the tangent cone's axis
///     arbitrarily; the price is at most φ of width);
///   - a cone is narrow below π/2 − 1e-5 (kNarrowLimit): far above the merges' slack and the tilt of
///     the projection basis (a few ε), so that the projection along the basis' kernel keeps every
///     triangle positively oriented;
///   - contour coordinates are taken relative to a reference point of the contour before projecting:
///     float keeps 24 bits of the *local* extent m of the contour, not of the distance from the
///     origin. Every projected, interpolated or subtracted coordinate is then within
///     τ = 128·ε·m of exact (fewer than 35εm are made), bounds are grown by 2τ and an exclusion
///     direction d must clear 4τ|d|₁ (d scaled to |d|∞ = 1 first, so that the margin cannot underflow).
///     τ is per edge pair (the larger scale of the two), which is all the pair's test needs.

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "weft/math/host_device.h"
#include "weft/physics/vec.h"

namespace weft::cuda::collision {

using Vec3f = physics::Vec3<float>;

/// Float machine epsilon, 2⁻²³.
inline constexpr float kFloatEps = std::numeric_limits<float>::epsilon();
/// The half-angle of a cone that bounds nothing (a namespace-scope constant: usable in device code).
inline constexpr float kInfiniteAngle = std::numeric_limits<float>::infinity();
/// Widening of every computed cone angle, rad (the file comment says why 64ε).
inline constexpr float kConeSlack = 64.0F * kFloatEps;
/// Cones at or above this half-angle (rad) bound nothing and fail: π/2 − 1e-5, rounded to float.
inline constexpr float kNarrowLimit = static_cast<float>(std::numbers::pi / 2 - 1e-5);
/// Absolute rounding allowance for underflow, m² or m (each subnormal float operation errs by at
/// most 2⁻¹⁵⁰; a few dozen stay far below this).
inline constexpr float kTinyF = 1e-30F;
/// Below this sine of the angle between two axes, the merge keeps the first axis (see file comment).
inline constexpr float kMinTangentSine = 1e-3F;
/// Largest local scale (m) a contour may have: every product and sum of the test stays finite.
inline constexpr float kMaxContourScale = 1e30F;
/// Deepest time bisection of one contour edge pair (2⁻¹² of the step), as contour_test.h.
inline constexpr int kFloatContourMaxDepth = 12;

/// All directions within `half_angle` (rad) of `axis` (nearly unit). +∞ (the default): bounds
/// nothing (degenerate, flipping or non-finite normals, or not narrower than kNarrowLimit).
struct FloatCone {
    Vec3f axis{};
    float half_angle = kInfiniteAngle;
};

/// True when the cone is narrower than a hemisphere with margin (the node's cone passes).
WEFT_HD inline bool float_cone_is_narrow(const FloatCone& c) { return c.half_angle < kNarrowLimit; }

namespace detail {

WEFT_HD inline float max_abs(Vec3f v) {
    using std::fabs;
    using std::fmax;
    return fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z)));
}

/// A cone, or the infinite one once it reaches kNarrowLimit (also for NaN).
WEFT_HD inline FloatCone bounded_cone(Vec3f axis, float half) {
    FloatCone c;
    if (half < kNarrowLimit) {
        c.axis = axis;
        c.half_angle = half;
    }
    return c;
}

/// Angle between two non-zero vectors, rad, in [0, π] (atan2: well conditioned at every angle).
WEFT_HD inline float angle_between(Vec3f u, Vec3f v) {
    using std::atan2;
    return atan2(physics::length(physics::cross(u, v)), physics::dot(u, v));
}

}  // namespace detail

/// The continuous normal cone of triangle (a, b, c) moving linearly from (a0, b0, c0) to (a1, b1, c1)
/// (float twin of weft::collision::triangle_normal_cone; see normal_cone.h for the Bernstein
/// control vectors N0, N1, N2 of n(t)). Infinite when a control vector has no reliable direction,
/// when they do not fit in a cone narrower than kNarrowLimit, or for non-finite positions.
WEFT_HD inline FloatCone float_triangle_cone(Vec3f a0, Vec3f b0, Vec3f c0, Vec3f a1, Vec3f b1, Vec3f c1) {
    using physics::cross;
    using physics::dot;
    using physics::length;
    using std::atan2;
    using std::isfinite;
    const Vec3f e1_0 = b0 - a0, e2_0 = c0 - a0, e1_1 = b1 - a1, e2_1 = c1 - a1;
    const Vec3f n[3] = {cross(e1_0, e2_0), 0.5F * (cross(e1_0, e2_1) + cross(e1_1, e2_0)), cross(e1_1, e2_1)};
    // Rounding of each control vector (normal_cone.cpp's analysis with float's ε): at most
    // 8u·m1·m2 per cross product with u = ε/2, bounded by 16ε·m1·m2, doubled for √3 < 2.
    const float m1_0 = detail::max_abs(e1_0), m2_0 = detail::max_abs(e2_0);
    const float m1_1 = detail::max_abs(e1_1), m2_1 = detail::max_abs(e2_1);
    const float err[3] = {2.0F * (16.0F * kFloatEps * m1_0 * m2_0 + kTinyF),
                          2.0F * (16.0F * kFloatEps * (m1_0 * m2_1 + m1_1 * m2_0) + kTinyF),
                          2.0F * (16.0F * kFloatEps * m1_1 * m2_1 + kTinyF)};
    // Direction of the true control vector within asin(err/|n|) ≤ 1.6·err/|n| of n's; a ratio above
    // ½ means no usable direction. |n| must be finite: an overflowed length would read as ratio 0.
    float ratio[3];
    Vec3f axis{};
    for (int i = 0; i < 3; ++i) {
        const float len = length(n[i]);
        if (!isfinite(len)) return {};
        ratio[i] = err[i] / len;
        if (!(ratio[i] <= 0.5F)) return {};  // also NaN and zero lengths
        axis += n[i] / len;
    }
    const float axis_len = length(axis);
    if (!(axis_len > 0.5F)) return {};  // unit directions cancelling: at least two nearly opposite
    axis = axis / axis_len;
    // The widest control vector (largest tangent while a·n > 0), one atan2 for the three.
    float widest_tan = -1.0F, sin_w = 0.0F, cos_w = 1.0F;
    for (int i = 0; i < 3; ++i) {
        const float s = length(cross(axis, n[i])), c = dot(axis, n[i]);
        if (!(c > 0.0F)) return {};
        if (s / c > widest_tan) {
            widest_tan = s / c;
            sin_w = s;
            cos_w = c;
        }
    }
    using std::fmax;
    const float half = atan2(sin_w, cos_w) + 1.6F * fmax(ratio[0], fmax(ratio[1], ratio[2])) + kConeSlack;
    return detail::bounded_cone(axis, half);
}

/// A cone containing both (float twin of weft::collision::merge_cones): either one when it contains
/// the other, else the tangent cone of half-angle (φ + θ1 + θ2)/2, or, for axes within about 1e-3
/// rad, the cone about c1's axis of half-angle max(θ1, φ + θ2). Infinite as soon as an input or the
/// result is not narrow, so failure propagates upward and a parent is never narrower than a child.
WEFT_HD inline FloatCone float_merge_cones(const FloatCone& c1, const FloatCone& c2) {
    using physics::dot;
    using physics::length;
    using std::cos;
    using std::fmax;
    using std::sin;
    if (!(c1.half_angle < kNarrowLimit) || !(c2.half_angle < kNarrowLimit)) return {};
    const float phi = detail::angle_between(c1.axis, c2.axis);
    if (!(phi >= 0.0F)) return {};  // NaN axis
    if (phi + c2.half_angle <= c1.half_angle) return detail::bounded_cone(c1.axis, c1.half_angle + kConeSlack);
    if (phi + c1.half_angle <= c2.half_angle) return detail::bounded_cone(c2.axis, c2.half_angle + kConeSlack);
    const float half = 0.5F * (phi + c1.half_angle + c2.half_angle);
    if (!(half < kNarrowLimit)) return {};
    // w: the unit direction of a2 orthogonal to a1. Its absolute error is a few ε; divided by
    // |w| = sin φ and multiplied by sin β ≤ sin φ below, it moves the axis by a few ε, provided φ is
    // far above its own rounding, which kMinTangentSine ensures.
    Vec3f w = c2.axis - dot(c1.axis, c2.axis) * c1.axis;
    const float w_len = length(w);
    if (!(w_len >= kMinTangentSine))
        return detail::bounded_cone(c1.axis, fmax(c1.half_angle, phi + c2.half_angle) + kConeSlack);
    w = w / w_len;
    const float beta = half - c1.half_angle;
    const Vec3f axis = physics::normalized(cos(beta) * c1.axis + sin(beta) * w);
    return detail::bounded_cone(axis, half + kConeSlack);
}

// ---- The contour test ----------------------------------------------------------------------------

/// The projection plane of a cone axis (as contour_test.cpp): u ⟂ axis through the coordinate axis
/// least aligned with it, v = axis × u. The kernel of (u, v) is u × v, within a few ε of the axis,
/// far inside kNarrowLimit's margin.
struct ProjectionBasis {
    Vec3f u, v;
};

WEFT_HD inline ProjectionBasis projection_basis(Vec3f axis) {
    using std::fabs;
    const float ax = fabs(axis.x), ay = fabs(axis.y), az = fabs(axis.z);
    const Vec3f pick = ax <= ay && ax <= az ? Vec3f{1.0F, 0.0F, 0.0F}
                       : ay <= az           ? Vec3f{0.0F, 1.0F, 0.0F}
                                            : Vec3f{0.0F, 0.0F, 1.0F};
    const Vec3f u = physics::normalized(physics::cross(axis, pick));
    return {u, physics::cross(axis, u)};
}

/// One contour edge (a, b), projected at both ends of the step, relative to the contour's
/// reference point r.
struct SweptEdge {
    float p[4][2];  ///< a(0), a(1), b(0), b(1): projected coordinates of x − r, m
    float scale;    ///< largest |x − r| coordinate of the four positions, m (τ's scale)
    bool finite;    ///< every x − r finite and the scale below kMaxContourScale
};

/// The rounding allowance τ (m) of coordinates derived from positions of local scale `scale`.
WEFT_HD inline float contour_tau(float scale) { return 128.0F * kFloatEps * scale + kTinyF; }

WEFT_HD inline SweptEdge project_edge(const ProjectionBasis& basis, Vec3f r, Vec3f a0, Vec3f a1, Vec3f b0, Vec3f b1) {
    using std::fmax;
    using std::isfinite;
    SweptEdge s{};
    const Vec3f ends[4] = {a0 - r, a1 - r, b0 - r, b1 - r};
    float scale = 0.0F;
    bool finite = true;
    for (int k = 0; k < 4; ++k) {
        const Vec3f& d = ends[k];
        finite = finite && isfinite(d.x) && isfinite(d.y) && isfinite(d.z);
        scale = fmax(scale, detail::max_abs(d));
        s.p[k][0] = physics::dot(basis.u, d);
        s.p[k][1] = physics::dot(basis.v, d);
    }
    s.scale = scale;
    s.finite = finite && scale < kMaxContourScale;
    return s;
}

/// Do the swept 2D boxes of two edges (each grown by 2τ of its own scale) overlap? Pairs whose
/// boxes miss cannot touch during the step.
WEFT_HD inline bool swept_boxes_overlap(const SweptEdge& e, const SweptEdge& f) {
    using std::fmax;
    using std::fmin;
    const float te = 2.0F * contour_tau(e.scale), tf = 2.0F * contour_tau(f.scale);
    for (int c = 0; c < 2; ++c) {
        const float elo = fmin(fmin(e.p[0][c], e.p[1][c]), fmin(e.p[2][c], e.p[3][c])) - te;
        const float ehi = fmax(fmax(e.p[0][c], e.p[1][c]), fmax(e.p[2][c], e.p[3][c])) + te;
        const float flo = fmin(fmin(f.p[0][c], f.p[1][c]), fmin(f.p[2][c], f.p[3][c])) - tf;
        const float fhi = fmax(fmax(f.p[0][c], f.p[1][c]), fmax(f.p[2][c], f.p[3][c])) + tf;
        if (flo > ehi || elo > fhi) return false;
    }
    return true;
}

namespace detail {

struct P2f {
    float x, y;
};

WEFT_HD inline P2f lerp2(const float p0[2], const float p1[2], float t) {
    return {p0[0] + t * (p1[0] - p0[0]), p0[1] + t * (p1[1] - p0[1])};
}

WEFT_HD inline float cross2(const P2f& o, const P2f& a, const P2f& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

/// Does direction (dx, dy) put every point beyond 4τ|d|₁? d is scaled to |d|∞ = 1 first so that the
/// margin cannot underflow; NaN compares false.
WEFT_HD inline bool separates(const P2f (&p)[8], float dx, float dy, float tau) {
    using std::fabs;
    using std::fmax;
    const float s = fmax(fabs(dx), fabs(dy));
    if (!(s > 0.0F)) return false;
    dx = dx / s;
    dy = dy / s;
    const float need = 4.0F * tau * (fabs(dx) + fabs(dy));
    for (const P2f& q : p)
        if (!(dx * q.x + dy * q.y > need)) return false;
    return true;
}

/// True when the 8 points provably stay away from the origin (contour_test.cpp's origin_excluded):
/// the direction of their mean, then the inward normals of their convex hull (Andrew's monotone
/// chain). How a direction was found does not matter to soundness: each is checked on all 8 points.
WEFT_HD inline bool origin_excluded(P2f (&p)[8], float tau) {
    P2f mean{0.0F, 0.0F};
    for (const P2f& q : p) mean = {mean.x + q.x, mean.y + q.y};
    if (separates(p, mean.x, mean.y, tau)) return true;
    for (int i = 1; i < 8; ++i) {  // insertion sort by (x, y)
        const P2f key = p[i];
        int j = i - 1;
        while (j >= 0 && (p[j].x > key.x || (p[j].x == key.x && p[j].y > key.y))) {
            p[j + 1] = p[j];
            --j;
        }
        p[j + 1] = key;
    }
    P2f hull[16];
    int k = 0;
    for (int i = 0; i < 8; ++i) {  // lower chain
        while (k >= 2 && cross2(hull[k - 2], hull[k - 1], p[i]) <= 0.0F) --k;
        hull[k++] = p[i];
    }
    for (int i = 6, lower = k + 1; i >= 0; --i) {  // upper chain
        while (k >= lower && cross2(hull[k - 2], hull[k - 1], p[i]) <= 0.0F) --k;
        hull[k++] = p[i];
    }
    // hull[0..k) runs counter-clockwise and repeats its first point; (−dy, dx) points inwards.
    for (int i = 0; i + 1 < k; ++i) {
        const float dx = hull[i + 1].x - hull[i].x, dy = hull[i + 1].y - hull[i].y;
        if (separates(p, -dy, dx, tau)) return true;
    }
    return false;
}

}  // namespace detail

/// Continuous test of two non-adjacent contour edges (contour_test.cpp's pair_separated): true when
/// they provably never touch during the step. The gap F(t, λ, μ) = e(t, λ) − f(t, μ) is multilinear
/// in (t, λ, μ), so over a time interval it lies in the hull of its 8 corner values; an interval
/// whose hull is not provably clear of the origin is bisected, down to 2^−kFloatContourMaxDepth,
/// where the pair counts as touching. A fixed stack of kFloatContourMaxDepth + 2 intervals.
WEFT_HD inline bool swept_edges_separated(const SweptEdge& e, const SweptEdge& f) {
    using std::fmax;
    if (!e.finite || !f.finite) return false;
    const float tau = contour_tau(fmax(e.scale, f.scale));
    struct Interval {
        float t0, t1;
        int depth;
    };
    Interval stack[kFloatContourMaxDepth + 2];
    int top = 0;
    stack[top++] = {0.0F, 1.0F, 0};
    while (top > 0) {
        const Interval iv = stack[--top];
        detail::P2f corners[8];
        int c = 0;
        for (int k = 0; k < 2; ++k) {
            const float t = k == 0 ? iv.t0 : iv.t1;
            const detail::P2f a = detail::lerp2(e.p[0], e.p[1], t), b = detail::lerp2(e.p[2], e.p[3], t);
            const detail::P2f g = detail::lerp2(f.p[0], f.p[1], t), h = detail::lerp2(f.p[2], f.p[3], t);
            corners[c++] = {a.x - g.x, a.y - g.y};
            corners[c++] = {a.x - h.x, a.y - h.y};
            corners[c++] = {b.x - g.x, b.y - g.y};
            corners[c++] = {b.x - h.x, b.y - h.y};
        }
        if (detail::origin_excluded(corners, tau)) continue;
        if (iv.depth == kFloatContourMaxDepth) return false;
        // Dyadic midpoints are exact in float at these depths; the earlier half first.
        const float mid = 0.5F * (iv.t0 + iv.t1);
        stack[top++] = {mid, iv.t1, iv.depth + 1};
        stack[top++] = {iv.t0, mid, iv.depth + 1};
    }
    return true;
}

}  // namespace weft::cuda::collision
