// Parametric rigid motions followed by animated colliders and pins.
#include "weft/motion.h"

#include <algorithm>
#include <cmath>
#include <numbers>

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

Mat3d rotation_from_euler_degrees(Vec3d degrees) {
    // Degrees because people type them; the angular *velocity* of a motion stays in rad/s.
    const double k = std::numbers::pi / 180.0;
    const double cx = std::cos(degrees.x * k), sx = std::sin(degrees.x * k);
    const double cy = std::cos(degrees.y * k), sy = std::sin(degrees.y * k);
    const double cz = std::cos(degrees.z * k), sz = std::sin(degrees.z * k);
    Mat3d rx = Mat3d::identity(), ry = Mat3d::identity(), rz = Mat3d::identity();
    rx.m[1][1] = cx; rx.m[1][2] = -sx; rx.m[2][1] = sx; rx.m[2][2] = cx;
    ry.m[0][0] = cy; ry.m[0][2] = sy; ry.m[2][0] = -sy; ry.m[2][2] = cy;
    rz.m[0][0] = cz; rz.m[0][1] = -sz; rz.m[1][0] = sz; rz.m[1][1] = cz;
    return rz * (ry * rx);
}

Vec3d euler_degrees_from_rotation(const Mat3d& r) {
    // R = Rz·Ry·Rx: R20 = −sin y, R21 = cos y·sin x, R22 = cos y·cos x, R10 = sin z·cos y, R00 = cos z·cos y.
    const double k = 180.0 / std::numbers::pi;
    const double sy = std::clamp(-r.m[2][0], -1.0, 1.0);
    const double y = std::asin(sy);
    if (std::abs(sy) > 1.0 - 1e-12) {  // gimbal lock: x and z turn about one axis; put it all in z
        const double z = std::atan2(-r.m[0][1], r.m[1][1]);
        return {0.0, y * k, z * k};
    }
    return {std::atan2(r.m[2][1], r.m[2][2]) * k, y * k, std::atan2(r.m[1][0], r.m[0][0]) * k};
}

bool Motion::is_static() const {
    const auto zero = [](Vec3d a) { return a.x == 0.0 && a.y == 0.0 && a.z == 0.0; };
    return zero(linear_velocity) && zero(angular_velocity) && (zero(amplitude) || frequency == 0.0);
}

}  // namespace weft
