#pragma once
/// @file
/// Continuous normal cones (docs/methods.md §5): a cone of directions that contains the normal of a
/// triangle, or of every triangle of a patch, at *every* instant of a step over which each vertex
/// moves linearly from x0 (t = 0) to x1 (t = 1).
///
/// A triangle's unnormalised normal over the step, n(t) = (b(t) − a(t)) × (c(t) − a(t)), is a
/// quadratic in t because both edge vectors are linear in t. Written in the Bernstein basis,
///   n(t) = (1 − t)²·N0 + 2t(1 − t)·N1 + t²·N2,
///   N0 = e1(0) × e2(0),   N1 = ½ (e1(0) × e2(1) + e1(1) × e2(0)),   N2 = e1(1) × e2(1),
/// with e1 = b − a, e2 = c − a. The weights are ≥ 0 and sum to 1 on [0, 1], so n(t) lies in the
/// convex hull of N0, N1, N2 (Tang, Curtis, Yoon & Manocha 2009, "Interactive continuous collision
/// detection between deformable models using connectivity-based culling", §4: the continuous normal
/// cone). A cone that contains the three control vectors therefore contains n(t) for all t, and if
/// its half-angle is below π/2 then axis·n(t) > 0 on the whole step: the triangle never degenerates
/// or flips, and neither does any triangle of a patch whose cone passes.
///
/// Rigour: positions are the exact inputs; the control vectors are computed in double with a bound
/// on their rounding, turned into an angle that widens each leaf cone; merges widen by a fixed
/// slack far above their O(ε) rounding (all angles come from atan2, which is well conditioned, never
/// from acos). `cone_is_narrow` keeps a further margin of 1e-9 rad below π/2, which also covers the
/// projection basis that the contour test builds from the axis.
///
/// CUDA: the three functions are branch-light arithmetic on a handful of vectors and port as
/// `__host__ __device__` code; the refit that calls them is one kernel per hierarchy level.

#include <cmath>
#include <limits>
#include <numbers>

#include "weft/physics/vec.h"
#include "weft/types.h"

namespace weft::collision {

/// All directions within `half_angle` (rad) of the unit vector `axis`. A half-angle of +∞ (the
/// default) marks a cone that bounds nothing: degenerate or non-finite normals, or wider than a
/// hemisphere, which is all the culling needs to know.
struct NormalCone {
    Vec3d axis{};
    double half_angle = std::numeric_limits<double>::infinity();
};

/// Kept below π/2 by `cone_is_narrow`, rad: covers the merges' rounding (≤ 64 levels × 64ε) and the
/// tilt of the contour test's projection basis (a few ε) with orders of magnitude to spare.
inline constexpr double kConeMargin = 1e-9;

/// The continuous normal cone of triangle (a, b, c) moving linearly from (a0, b0, c0) to (a1, b1, c1):
/// contains the direction of n(t) for every t in [0, 1] (see the file comment). Infinite half-angle
/// when the control vectors do not fit in a cone narrower than a hemisphere (only a convex cone
/// holds their convex hull), when one is too small to have a reliable direction (the triangle
/// degenerates at some point of the step, or nearly) or a position is not finite.
[[nodiscard]] NormalCone triangle_normal_cone(const Vec3d& a0, const Vec3d& b0, const Vec3d& c0, const Vec3d& a1,
                                              const Vec3d& b1, const Vec3d& c1);

/// A cone containing both cones (Tang et al. 2009; the usual merge: the smallest cone around the two
/// when neither contains the other). Only cones narrower than a hemisphere are merged: when either
/// input or the result reaches π/2 the result is the infinite cone, so failure propagates upward
/// and a parent's half-angle is never below a child's (the monotonicity the front relies on).
[[nodiscard]] NormalCone merge_cones(const NormalCone& c1, const NormalCone& c2);

/// True when every direction in the cone makes an angle below π/2 − kConeMargin with its axis: then
/// axis·n > 0 for every normal n the cone bounds, with margin. False for NaN.
[[nodiscard]] inline bool cone_is_narrow(const NormalCone& c) {
    return c.half_angle < std::numbers::pi / 2 - kConeMargin;
}

/// Angle between two non-zero vectors, rad, in [0, π]: atan2(|u × v|, u·v), accurate to a few ulps
/// of π for any angle (acos loses half the digits near 0 and π).
[[nodiscard]] inline double angle_between(const Vec3d& u, const Vec3d& v) {
    return std::atan2(physics::length(physics::cross(u, v)), physics::dot(u, v));
}

}  // namespace weft::collision
