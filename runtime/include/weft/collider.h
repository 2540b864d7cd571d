#pragma once
/// @file
/// Analytic colliders: plane, sphere, capsule and box, static or following a `Motion`.

#include <cstdint>
#include <memory>
#include <string>

#include "weft/fabric.h"
#include "weft/motion.h"

namespace weft {

/// Plane, sphere, capsule and box are analytic (penalty contacts in the solve); a mesh collider is a
/// triangle mesh (a body, a chair) that goes through the cloth collision pipeline (proximity
/// contacts, CCD and impact zones) as kinematic geometry.
enum class ColliderShape : std::uint8_t { Plane, Sphere, Capsule, Box, Mesh };

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
    /// Mesh colliders only: the triangles in the collider's local frame (m), placed at time t by
    /// `motion.at(t)`. Closed or open; the cloth keeps its contact thickness from either side.
    std::shared_ptr<const MeshData> mesh;
    [[nodiscard]] bool is_analytic() const { return shape != ColliderShape::Mesh; }
};

}  // namespace weft
