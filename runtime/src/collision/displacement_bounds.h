#pragma once
/// @file
/// Per-vertex conservative displacement bounds of offset geometric contact (docs/methods.md §7b;
/// Chen et al. 2025), the CPU reference: instead of continuous collision detection, each vertex may
/// move at most b_v = γ·min(r, d_v) in an update, where d_v is the distance from the primitives it
/// belongs to (itself, its edges, its triangles) to the nearest primitive pair partner that shares no
/// vertex with them, r the query radius and γ < ½ the relaxation.
///
/// Why no update within the bounds can make two triangles intersect: at the first instant two
/// triangles that share no vertex touch, some vertex–face or edge–edge pair of theirs touches. Every
/// point of a primitive moves at most as far as its farthest vertex (a convex combination), and each
/// vertex of a pair at distance d moves at most γ·min(r, d) ≤ γ·d when d < r (the pair is one its
/// bound was taken over) and at most γ·r ≤ γ·d otherwise. The distance can therefore shrink by at
/// most 2γ·d < d along any straight-line update: it stays ≥ (1 − 2γ)·d > 0 for a pair that starts
/// apart.
///
/// The sharper, planar variant keeps what is known about each pair: the closest points give a plane
/// separating the two primitives (convex sets), and it suffices that no vertex moves more than γ·d
/// *towards* each partner within r (and no more than γ·r in all): the two primitives then stay on
/// their own sides of a slab of width (1 − 2γ)·d. Motion along the surfaces is not limited at all.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "collision/broad_phase.h"
#include "weft/backend/collision_primitives.h"
#include "weft/types.h"

namespace weft::collision {

struct DisplacementBoundsInput {
    std::span<const Vec3d> x;             ///< positions at the start of the update, m
    std::span<const Triangle> triangles;  ///< global vertex ids
    std::span<const Edge> edges;          ///< unique edges, normally `build_edges(triangles)`
    double query_radius = 0.0;            ///< r, m (> 0): partners farther than this do not limit a vertex
    /// Per-vertex query radii r_v, m (optional: empty uses `query_radius` for every vertex; else one
    /// finite value > 0 per vertex). A pair is measured when its distance is below the largest r_v of
    /// its four vertices, and then limits all four: a pair not measured is at least r_v from each of
    /// its vertices, which move at most γ·r_v, so the proof above holds vertex by vertex.
    std::span<const double> radius;
    double relaxation = 0.45;             ///< γ in (0, ½): the share of the distance a vertex may cover
    /// As BroadPhaseInput: false measures only pairs across groups (`triangle_group`), which the
    /// bounds then certify alone (self-collision off: a cloth may cross itself).
    bool self_pairs = true;
    std::span<const std::uint32_t> triangle_group;
    /// Normal-cone patch ids (optional, as BroadPhaseInput): pairs inside one patch are not measured.
    /// Sound only when the caller then certifies every such patch over the actual update (a patch
    /// that passes the normal-cone test over a motion never collides with itself during it,
    /// normal_cone_front.h) and measures them after all where it does not (`patches_hold`).
    std::span<const std::uint32_t> vertex_patch, edge_patch, triangle_patch;
};

/// True when every primitive that shared a patch id other than kNoPatch in `before` (the ids the
/// bounds culled with) still shares one with the same primitives in `after` (the ids of a front
/// updated over the actual update): then every pair the culling skipped lies in one patch that is
/// free of self-collision over that update. Spans: vertex, edge and triangle ids, concatenated.
[[nodiscard]] bool patches_hold(std::span<const std::uint32_t> before, std::span<const std::uint32_t> after);

/// One partner of a vertex within the query radius: the vertex may move at most `limit` (m) along the
/// unit `towards` (from its primitive's closest point to the partner's).
struct PartnerLimit {
    Vec3d towards;
    double limit = 0.0;  ///< γ·d
};

struct DisplacementBounds {
    std::vector<double> bound;         ///< b_v = γ·min(r_v, d_v) per vertex, m
    std::vector<double> reach;         ///< γ·r_v per vertex: the most vertex v may move in any direction, m
    /// Per vertex, its partners within r (CSR: partner_start has vertices + 1 entries, in pair order),
    /// for the planar truncation.
    std::vector<std::uint32_t> partner_start;
    std::vector<PartnerLimit> partners;
    /// The pairs measured (broad-phase order) and their distances at `x`, m: what the offset contacts
    /// are chosen from.
    BroadPhaseResult pairs;
    std::vector<double> vf_distance, ee_distance;
    std::size_t vf_pairs = 0;          ///< vertex–face pairs measured (within the radius)
    std::size_t ee_pairs = 0;          ///< edge–edge pairs measured
    std::size_t limited_vertices = 0;  ///< vertices with a partner closer than their r_v
};

/// The bounds of every vertex (the broad phase's spatial hash finds the pairs within r; `hash` keeps
/// its scratch between calls). Throws `weft::Error` for r ≤ 0, γ outside (0, ½) or mismatched input.
void compute_displacement_bounds(const DisplacementBoundsInput& in, BroadPhase& hash, DisplacementBounds& out);

/// The share t ∈ [0, 1] of vertex v's move `move` (m) that keeps its bounds: sphere (|t·move| ≤ b_v)
/// or planar (t·move advances at most γ·d towards each partner and at most reach_v in all; never less
/// than the sphere's).
double kept_share(const DisplacementBounds& b, std::size_t v, Vec3d move, bool planar);

/// Shortens each vertex's move x1 − x0 to at most its bound (along the move). Returns the number of
/// vertices shortened.
std::size_t truncate_displacements(std::span<const Vec3d> x0, std::span<Vec3d> x1, std::span<const double> bound);

/// The planar variant: shortens each vertex's move (along the move) to the longest that advances at
/// most `limit` towards each of its partners and at most its reach in all. Never shorter than
/// `truncate_displacements` would make it. Returns the number of vertices shortened.
std::size_t truncate_displacements_planar(std::span<const Vec3d> x0, std::span<Vec3d> x1, const DisplacementBounds& b);

}  // namespace weft::collision
