#pragma once
// Deformations of flat test sheets shared by the normal-cone tests (CPU tests/solver/
// test_normal_cone.cpp and GPU tests/gpu/test_normal_cone_gpu.cpp): a fold about a line, a roll into
// a spiral, and the twist benchmark's kinematic field.
#include <cmath>
#include <numbers>

#include "weft/types.h"

namespace weft::test {

/// Folds the part of a flat sheet beyond the line u = u_fold (u = x cos α + y sin α) by θ about it.
inline Vec3d fold(const Vec3d& p, double alpha, double u_fold, double theta) {
    const double c = std::cos(alpha), s = std::sin(alpha);
    const double u = c * p.x + s * p.y, w = -s * p.x + c * p.y;
    if (u <= u_fold) return p;
    const double d = u - u_fold, u2 = u_fold + d * std::cos(theta), z = p.z + d * std::sin(theta);
    return {c * u2 - s * w, s * u2 + c * w, z};
}

/// Rolls a strip (x from its start x_min) into an inward spiral: radius r0, gap g between turns.
inline Vec3d roll(const Vec3d& p, double x_min, double r0, double gap) {
    const double phi = (p.x - x_min) / r0;
    const double r = r0 - gap * phi / (2.0 * std::numbers::pi);
    return {x_min + r * std::sin(phi), p.y, r0 - r * std::cos(phi) + p.z};
}

/// The twist benchmark's kinematic field: the sheet (x along the axis through the midpoints of its
/// two opposite edges x = ±L/2) turned about that axis by (π/3 rad/s)·t·(2x/L): the two edges turn
/// at π/3 rad/s in opposite directions.
inline Vec3d twist(const Vec3d& p, double L, double t) {
    const double phi = std::numbers::pi / 3.0 * t * (2.0 * p.x / L);
    return {p.x, p.y * std::cos(phi) - p.z * std::sin(phi), p.y * std::sin(phi) + p.z * std::cos(phi)};
}

}  // namespace weft::test
