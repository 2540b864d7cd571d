#pragma once
/// @file
/// Kinematic motion of a rigid frame: what animated colliders and animated pins follow.

#include "weft/types.h"

namespace weft {

/// A rigid transform: x_world = rotation · x_local + translation.
struct Transform {
    Mat3d rotation = Mat3d::identity();  ///< orthonormal, local → world
    Vec3d translation{};                 ///< m
    [[nodiscard]] Vec3d apply(Vec3d p) const { return rotation * p + translation; }
};

/// A parametric rigid motion, evaluated at time t (s):
///   translation(t) = origin + linear_velocity·t + amplitude·sin(2π·frequency·t + phase)
///   rotation(t)    = exp([angular_velocity]× t) · initial_rotation
/// The rotation turns about the frame's own origin (translation(t)). This covers a rotating sphere,
/// a swinging shoulder and a collider thrown at constant speed; keyframed tracks are not supported yet.
struct Motion {
    Vec3d origin{};            ///< m
    Mat3d initial_rotation = Mat3d::identity();
    Vec3d linear_velocity{};   ///< m/s
    Vec3d angular_velocity{};  ///< rad/s, axis × rate, world frame
    Vec3d amplitude{};         ///< m, oscillation amplitude per axis
    double frequency = 0.0;    ///< Hz
    double phase = 0.0;        ///< rad

    /// The frame at time t (s).
    [[nodiscard]] Transform at(double t) const;
    /// Velocity (m/s) at time t of the material point that sits at world position p.
    [[nodiscard]] Vec3d point_velocity(double t, Vec3d p) const;
    /// True when the frame never moves.
    [[nodiscard]] bool is_static() const;
};

/// Rotation matrix of the rotation vector w (axis × angle, rad): Rodrigues' formula.
[[nodiscard]] Mat3d rotation_from_vector(Vec3d w);

/// Rotation from the scene format's Euler angles in degrees [x, y, z]: about the world X axis
/// first, then Y, then Z (R = Rz·Ry·Rx).
[[nodiscard]] Mat3d rotation_from_euler_degrees(Vec3d degrees);
/// The Euler angles (degrees, the convention above) of rotation `r`: y in [−90, 90], x and z in
/// (−180, 180]; at y = ±90 (gimbal lock) x is 0 and z carries the rest.
[[nodiscard]] Vec3d euler_degrees_from_rotation(const Mat3d& r);

}  // namespace weft
