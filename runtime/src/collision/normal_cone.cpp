// Continuous normal cones: the Bernstein control vectors of a moving triangle's normal, and the merge
// of two cones (see normal_cone.h for the method and its references).
#include "collision/normal_cone.h"
#include "weft/physics/vec.h"

#include <algorithm>

namespace weft::collision {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kHalfPi = std::numbers::pi / 2;
// Widening of every computed cone, rad. The angles of a cone come from atan2 on vectors of unit
// length up to a few ε, so each carries an error of a few ε; 64ε covers it with room (and the slack
// adds up over at most a few dozen levels to ~1e-12 rad, far inside kConeMargin).
constexpr double kSlack = 64.0 * kEps;
// Absolute rounding allowance for underflow in the cross products (each subnormal operation errs
// by at most 2^−1075; a few dozen of them stay far below this).
constexpr double kTiny = 1e-300;

double max_abs(const Vec3d& v) { return std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z))); }

}  // namespace

NormalCone triangle_normal_cone(const Vec3d& a0, const Vec3d& b0, const Vec3d& c0, const Vec3d& a1, const Vec3d& b1,
                                const Vec3d& c1) {
    using physics::cross;
    const Vec3d e1_0 = b0 - a0, e2_0 = c0 - a0, e1_1 = b1 - a1, e2_1 = c1 - a1;
    // Bernstein control vectors of n(t) (normal_cone.h).
    const Vec3d n[3] = {cross(e1_0, e2_0), 0.5 * (cross(e1_0, e2_1) + cross(e1_1, e2_0)), cross(e1_1, e2_1)};
    // Rounding of each control vector, per component. Each edge component carries a relative error
    // ≤ u = ε/2 from its subtraction; a product of two of them then ≤ 3u, the difference in the
    // cross product adds u of the result: |error| ≤ 4u·(|p q| + |r s|) ≤ 4ε·m1·m2 with m the largest
    // edge component. N1 sums two such products (one more rounding; the ½ is exact). 16ε per
    // product bound is four times that; √3 < 2 turns it into a Euclidean bound.
    const double m1_0 = max_abs(e1_0), m2_0 = max_abs(e2_0), m1_1 = max_abs(e1_1), m2_1 = max_abs(e2_1);
    const double err[3] = {2.0 * (16.0 * kEps * m1_0 * m2_0 + kTiny),
                           2.0 * (16.0 * kEps * (m1_0 * m2_1 + m1_1 * m2_0) + kTiny),
                           2.0 * (16.0 * kEps * m1_1 * m2_1 + kTiny)};
    // The true control vector N lies within err of the computed n, so its direction lies within
    // asin(err/|n|) ≤ (π/2)·err/|n| of n's (asin(x)/x ≤ π/2 on (0, 1]); 1.6 > π/2 absorbs the
    // rounding of the ratio. A ratio above ½ means no usable direction.
    double ratio[3];
    Vec3d axis{};
    for (int i = 0; i < 3; ++i) {
        const double len = physics::length(n[i]);
        ratio[i] = err[i] / len;
        if (!(ratio[i] <= 0.5)) return {};  // also NaN, infinite and zero lengths
        axis += n[i] / len;
    }
    const double axis_len = physics::length(axis);
    if (!(axis_len > 0.5)) return {};  // unit directions cancelling: at least two nearly opposite
    axis = axis / axis_len;
    // The widest control vector: angle = atan2(|a × n|, a·n) grows with the tangent |a × n|/(a·n)
    // while a·n > 0 (wider than π/2 fails anyway), so one atan2 serves the three (a choice upset by
    // rounding picks an angle within a few ε of the widest, inside the slack).
    double widest_tan = -1.0, sin_w = 0.0, cos_w = 1.0;
    for (int i = 0; i < 3; ++i) {
        const double s = physics::length(physics::cross(axis, n[i])), c = physics::dot(axis, n[i]);
        if (!(c > 0.0)) return {};
        if (s / c > widest_tan) {
            widest_tan = s / c;
            sin_w = s;
            cos_w = c;
        }
    }
    const double half = std::atan2(sin_w, cos_w) + 1.6 * std::max(ratio[0], std::max(ratio[1], ratio[2])) + kSlack;
    // A circular cone holds the convex hull of directions it holds only while it is convex, i.e.
    // no wider than a hemisphere; wider ones bound nothing here.
    if (!(half < kHalfPi)) return {};
    return {axis, half};
}

NormalCone merge_cones(const NormalCone& c1, const NormalCone& c2) {
    // Only cones inside an open hemisphere matter to the culling; refusing the others keeps the
    // angle between the axes below π, where the merge below is well conditioned.
    if (!(c1.half_angle < kHalfPi) || !(c2.half_angle < kHalfPi)) return {};
    const double phi = angle_between(c1.axis, c2.axis);
    if (!(phi >= 0.0)) return {};  // NaN axis
    if (phi + c2.half_angle <= c1.half_angle) return {c1.axis, c1.half_angle + kSlack};
    if (phi + c1.half_angle <= c2.half_angle) return {c2.axis, c2.half_angle + kSlack};
    // Neither contains the other: the cone tangent to both, half-angle (φ + θ1 + θ2)/2, its axis
    // rotated from a1 towards a2 by β = θ − θ1 ∈ (0, φ) in their common plane.
    const double half = 0.5 * (phi + c1.half_angle + c2.half_angle);
    if (!(half < kHalfPi)) return {};
    const double beta = half - c1.half_angle;
    // w: the unit direction of a2 orthogonal to a1. |w| = sin φ > 0 here (φ > |θ2 − θ1| ≥ 0); its
    // direction errs by O(ε / sin φ), multiplied by sin β ≤ sin φ below: O(ε) overall.
    Vec3d w = c2.axis - physics::dot(c1.axis, c2.axis) * c1.axis;
    const double w_len = physics::length(w);
    if (!(w_len > 0.0)) return {c1.axis, c1.half_angle + phi + c2.half_angle + kSlack};  // φ below rounding
    w = w / w_len;
    const Vec3d axis = physics::normalized(std::cos(beta) * c1.axis + std::sin(beta) * w);
    return {axis, half + kSlack};
}

}  // namespace weft::collision
