#pragma once
/// @file
/// The exact intersection check of a whole world state (issue 4, item 6): what `weft run --check`
/// and `CollisionSettings::check` run after every step.

#include <span>
#include <vector>

#include "collision/intersection_check.h"
#include "weft/backend/model.h"
#include "weft/world.h"

namespace weft::collision {

/// What the check found, by kind: a fix differs for cloth through cloth (the contacts) and cloth
/// through a body (the colliders' contacts, or a body whose parts overlap and pinch the cloth).
struct WorldIntersections {
    std::size_t cloth_with_cloth = 0;     ///< pairs of cloth triangles (of one cloth or of two)
    std::size_t cloth_with_collider = 0;  ///< a cloth triangle through a mesh collider's triangle
    [[nodiscard]] std::size_t total() const { return cloth_with_cloth + cloth_with_collider; }
};

/// Every intersecting pair of triangles among the cloths (positions given per cloth, in model order)
/// and the mesh colliders placed at time `t` (s), leaving out pairs that share a vertex and pairs of
/// two collider triangles (a collider is not ours to fix). Exact (intersection_check.h).
[[nodiscard]] WorldIntersections check_world_intersections(const Model& model,
                                                           std::span<const std::vector<Vec3d>> cloth_positions,
                                                           double t);

/// The same pairs, named (World::intersections): at most `max_pairs`, ordered by the cloth triangle
/// (cloths in model order), then the other.
[[nodiscard]] std::vector<IntersectingTriangles> list_world_intersections(const Model& model,
                                                                          std::span<const std::vector<Vec3d>> cloth_positions,
                                                                          double t, std::size_t max_pairs);

}  // namespace weft::collision
