#pragma once
/// @file
/// An analytic `ColliderDesc` as the physics functions see it at a time t, and the test that decides
/// whether a collider moves fast enough to be swept (backend kit).

#include "weft/collider.h"
#include "weft/physics/collider_contact.h"
#include "weft/physics/swept_collider.h"

namespace weft {

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
