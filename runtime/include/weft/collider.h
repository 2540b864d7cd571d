#pragma once
/// @file
/// Analytic colliders: plane, sphere, capsule and box, static or following a `Motion`.

#include <cstdint>
#include <string>

#include "weft/motion.h"

namespace weft {

enum class ColliderShape : std::uint8_t { Plane, Sphere, Capsule, Box };

/// An analytic collider. Its local frame follows `motion` (origin, rotation, animation).
/// Plane: passes through the frame origin with normal = local +Y.
/// Sphere: radius about the origin. Capsule: segment from −half_height to +half_height along local Y,
/// swept by radius. Box: half_extents along local X, Y, Z.
struct ColliderDesc {
    std::string name;
    ColliderShape shape = ColliderShape::Plane;
    Motion motion{};
    double radius = 0.5;        ///< m (sphere, capsule)
    double half_height = 0.5;   ///< m (capsule)
    Vec3d half_extents{0.5, 0.5, 0.5};  ///< m (box)
    double friction = -1.0;     ///< Coulomb coefficient; negative: use the cloth material's
};

}  // namespace weft
