#pragma once
/// @file
/// The collision index space of a world (docs/collisions.md), shared by both backends: the cloth's
/// vertices first, then the vertices of every mesh collider (kinematic: placed by their motion,
/// never moved). Built once per topology from the flat model; the per-vertex attributes are what
/// the proximity contacts and the impact zones read.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "weft/backend/collision_primitives.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/model.h"

namespace weft::collision {

struct CollisionGeometry {
    struct MeshCollider {
        std::size_t collider = 0;        ///< index in Model::colliders
        std::uint32_t first_vertex = 0;  ///< first vertex in the kinematic range (0-based within it)
    };
    bool self = false;                 ///< self-collision was on when built
    std::size_t cloth_vertices = 0;
    std::vector<MeshCollider> meshes;
    std::vector<Vec3d> kinematic_local;  ///< mesh collider vertices in their collider's frame, m
    std::vector<Triangle> triangles;     ///< cloth then kinematic, collision vertex ids
    /// Broad-phase group of each triangle: with self-collision each cloth its own group, without it
    /// all cloth one group (so only cloth–collider pairs form); each mesh collider its own group.
    std::vector<std::uint32_t> triangle_group;
    /// The first mesh collider's group: groups from here on are kinematic (no pair among them matters).
    std::uint32_t first_kinematic_group = 0;
    std::vector<Edge> edges;             ///< build_edges(triangles)
    std::vector<double> inverse_mass;    ///< 1/kg; 0 for pinned and kinematic vertices
    std::vector<double> thickness;       ///< m: the cloth's contact thickness, 0 for kinematic vertices
    std::vector<double> friction;        ///< the cloth's or the collider's Coulomb coefficient
    /// Cloth vertices only (size cloth_vertices): the rest shape as placed at the start, m, and the
    /// owning cloth, for the proximity stage's rest exclusion (CollisionSettings::rest_exclusion).
    std::vector<Vec3d> rest;
    std::vector<std::uint32_t> vertex_cloth;
    double max_thickness = 0.0;          ///< largest cloth contact thickness, m

    [[nodiscard]] std::size_t kinematic_vertices() const { return kinematic_local.size(); }
    [[nodiscard]] std::size_t vertex_count() const { return cloth_vertices + kinematic_local.size(); }
    /// The gap kept between surfaces (broad-phase inflation, impact-zone target), m.
    [[nodiscard]] double gap(const CollisionSettings& s) const { return s.thickness > 0.0 ? s.thickness : max_thickness; }
    /// Kinematic vertex positions at time t (s), into `out` (size kinematic_vertices()).
    void place_kinematic(const Model& model, double t, std::span<Vec3d> out) const;
};

/// The geometry of `flat` and the mesh colliders of `model`. Throws `weft::Error` for a mesh
/// collider without a mesh.
[[nodiscard]] CollisionGeometry build_collision_geometry(const FlatModel& flat, const Model& model);

}  // namespace weft::collision
