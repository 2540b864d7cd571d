#pragma once
/// @file
/// Analytic colliders: plane, sphere, capsule and box, static or following a `Motion`.

#include <cstdint>
#include <memory>
#include <string>

#include "weft/fabric.h"

#include "weft/motion.h"
#include "weft/physics/collider_contact.h"
#include "weft/physics/swept_collider.h"

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

/// The collider at time `t` (s) as the physics functions see it, in scalar T: its pose, sizes and the
/// velocity of its frame. Backends call this once per analytic collider per substep (never for a
/// mesh collider: see `is_analytic`).
template <typename T>
[[nodiscard]] physics::Shape<T> shape_at(const ColliderDesc& c, double t) {
    const Transform frame = c.motion.at(t);
    physics::Shape<T> s{};
    switch (c.shape) {
        case ColliderShape::Sphere: s.kind = physics::ShapeKind::Sphere; break;
        case ColliderShape::Capsule: s.kind = physics::ShapeKind::Capsule; break;
        case ColliderShape::Box: s.kind = physics::ShapeKind::Box; break;
        case ColliderShape::Plane:
        default: s.kind = physics::ShapeKind::Plane; break;
    }
    s.rotation = frame.rotation.template cast<T>();
    s.origin = frame.translation.template cast<T>();
    s.radius = static_cast<T>(c.radius);
    s.half_height = static_cast<T>(c.half_height);
    s.half_extents = c.half_extents.template cast<T>();
    s.linear_velocity = c.motion.point_velocity(t, frame.translation).template cast<T>();
    s.angular_velocity = c.motion.angular_velocity.template cast<T>();
    return s;
}

/// True when analytic collider `c` moves more than a quarter of its smallest width during the
/// substep [t, t + h] (s): fast enough by its own motion to pass through cloth between two penalty
/// evaluations, so the vertex paths must be swept against it (weft/physics/swept_collider.h). Planes
/// never are. The backends sweep on the relative motion, so a collider for which this is false is
/// still swept against cloth that itself moves that far in the substep.
[[nodiscard]] inline bool is_fast_collider(const ColliderDesc& c, double t, double h) {
    if (!c.is_analytic()) return false;
    const physics::Shape<double> s0 = shape_at<double>(c, t);
    const physics::Shape<double> s1 = shape_at<double>(c, t + h);
    const double width = physics::shape_min_width(s0);
    if (!(width > 0.0)) return false;
    const double travel = physics::length(s1.origin - s0.origin) +
                          physics::length(s0.angular_velocity) * h * physics::shape_bounding_radius(s0);
    return travel > 0.25 * width;
}

}  // namespace weft
