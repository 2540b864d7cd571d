#pragma once
/// @file
/// The exact intersection check of a whole world state (issue 4, item 6): what `weft run --check`
/// and `CollisionSettings::check` run after every step.

#include <span>
#include <vector>

#include "collision/intersection_check.h"
#include "weft/backend/model.h"

namespace weft::collision {

/// Every intersecting pair of triangles among the cloths (positions given per cloth, in model order)
/// and the mesh colliders placed at time `t` (s), leaving out pairs that share a vertex and pairs of
/// two collider triangles (a collider is not ours to fix). Exact (intersection_check.h).
[[nodiscard]] IntersectionReport check_world_intersections(const Model& model,
                                                           std::span<const std::vector<Vec3d>> cloth_positions,
                                                           double t);

}  // namespace weft::collision
