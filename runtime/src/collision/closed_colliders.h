#pragma once
// Cloth inside a closed mesh collider, found and put back outside (docs/collisions.md, "Closed mesh
// colliders").
//
// A mesh collider holds cloth off its surface from either side, so that open meshes (a sheet of
// ground, a shell) work; and the CCD stops a vertex crossing the surface in either direction. So a
// cloth vertex that once gets inside a collider (squeezed between two moving parts of a body, or
// through a fallback of the impact zones) stays there, at its contact thickness from the walls,
// with every substep reported resolved. Where a piece of the collider is closed, its inside is
// defined: the winding number of the piece's surface around the point (Jacobson et al. 2013, the
// sum of the triangles' signed solid angles over 4π: ±1 inside a closed surface, 0 outside, for
// either orientation of the faces). Such a vertex is moved, at the start of a substep, to just
// outside the nearest point of the surface it is inside, and takes the surface's velocity there
// plus its own motion along the surface.

#include <cstdint>
#include <span>
#include <vector>

#include "weft/backend/collision_geometry.h"

namespace weft::collision {

/// A closed piece of a mesh collider: a connected set of its triangles (sharing vertices) in which
/// every edge belongs to exactly two triangles, so that it bounds a volume.
struct ClosedPiece {
    std::vector<std::uint32_t> triangles;  ///< indices into CollisionGeometry::triangles
};

/// The closed pieces of `g`'s mesh colliders (open pieces have no inside and are left out), in
/// triangle order. Built once with the geometry.
[[nodiscard]] std::vector<ClosedPiece> find_closed_pieces(const CollisionGeometry& g);

/// The winding number of the closed surface `triangles` (collision vertex ids into `x`) around `p`:
/// about ±1 inside, 0 outside (exact up to rounding away from the surface).
[[nodiscard]] double winding_number(Vec3d p, std::span<const Triangle> triangles, std::span<const std::uint32_t> piece,
                                    std::span<const Vec3d> x);

/// A cloth vertex found inside a closed piece, and where it goes.
struct Ejection {
    std::uint32_t vertex = 0;  ///< cloth vertex
    Vec3d position;            ///< `gap` outside the nearest point of the surface it was inside, m
    Vec3d normal;              ///< the unit direction it was moved out along (outward there)
    Vec3d surface_velocity;    ///< the surface's velocity at that point, m/s
};

/// The cloth vertices of `x` (collision positions: cloth first, then the kinematic vertices) inside
/// a closed piece, each with the point `gap` outside the nearest point of the pieces' surfaces that
/// is inside none of them (the nearest point where every choice lands inside another piece, as where
/// two pieces overlap deeply). `kinematic_velocity` holds the kinematic vertices' velocities (m/s).
/// Deterministic (vertex order); parallel over the vertices.
[[nodiscard]] std::vector<Ejection> find_ejections(const CollisionGeometry& g, std::span<const ClosedPiece> pieces,
                                                   std::span<const Vec3d> x, std::span<const Vec3d> kinematic_velocity,
                                                   double gap);

}  // namespace weft::collision
