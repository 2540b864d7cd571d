// Parametric rigid motions followed by animated colliders and pins.
#include <cmath>
#include <numbers>

#include "weft/motion.h"

namespace weft {

Mat3d rotation_from_vector(Vec3d w) {
    const double angle = math::length(w);
    if (angle < 1e-15) return Mat3d::identity();
    const Vec3d k = w / angle;
    // Rodrigues: R = I + sinθ [k]× + (1 − cosθ) [k]×²
    Mat3d kx{};
    kx.m[0][1] = -k.z; kx.m[0][2] = k.y;
    kx.m[1][0] = k.z;  kx.m[1][2] = -k.x;
    kx.m[2][0] = -k.y; kx.m[2][1] = k.x;
    return Mat3d::identity() + std::sin(angle) * kx + (1.0 - std::cos(angle)) * (kx * kx);
}

Transform Motion::at(double t) const {
    const double s = std::sin(2.0 * std::numbers::pi * frequency * t + phase);
    const double s0 = std::sin(phase);
    Transform tr;
    // The oscillation is measured from its value at t = 0 so that the frame starts at `origin`.
    tr.translation = origin + t * linear_velocity + (s - s0) * amplitude;
    tr.rotation = rotation_from_vector(t * angular_velocity) * initial_rotation;
    return tr;
}

Vec3d Motion::point_velocity(double t, Vec3d p) const {
    const double c = std::cos(2.0 * std::numbers::pi * frequency * t + phase);
    const Vec3d v = linear_velocity + (2.0 * std::numbers::pi * frequency * c) * amplitude;
    const Vec3d centre = at(t).translation;
    return v + math::cross(angular_velocity, p - centre);
}

bool Motion::is_static() const {
    const auto zero = [](Vec3d a) { return a.x == 0.0 && a.y == 0.0 && a.z == 0.0; };
    return zero(linear_velocity) && zero(angular_velocity) && (zero(amplitude) || frequency == 0.0);
}

}  // namespace weft
