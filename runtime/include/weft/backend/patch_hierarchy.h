#pragma once
/// @file
/// The patch hierarchy of normal-cone self-collision culling (docs/methods.md §5; Tang et al. PSCC
/// 2018): a binary tree over the triangles of each cloth whose every node is a *connected* set of
/// triangles, built once per mesh from its fixed topology, with each node's contour (its boundary
/// edges) precomputed. `NormalConeFront` refits cones over it every step and picks the patches.
///
/// Build (once, O(T log² T)): every connected component of every cloth is a root. A node is split at
/// the median of its triangles' rest centroids along its longest extent (straight cuts give short,
/// smooth contours, hence cheap contour tests), then repaired to keep both children connected:
/// the smaller components of the first half move to the second and the smaller components of the
/// second move back to the first, which stays connected because each component of a connected
/// node's half touches the other half. Leaves are single triangles. Nodes are numbered level by
/// level (breadth first; a node's two children are consecutive), so every level is a contiguous
/// range: the refit runs one level at a time from the deepest, one parallel loop (one CUDA kernel)
/// per level.
///
/// Contours are merged bottom-up (the contour of a node is the symmetric difference of its
/// children's, each list kept sorted by edge key), stored flat for the nodes that can ever be
/// tested. A node can be tested only when it is a topological disk with consistently oriented
/// triangles (`kDisk`), which the cone-and-contour theorem needs (normal_cone_front.h): every edge
/// has at most two triangles, traversed in opposite directions, every vertex of the mesh is
/// manifold (one fan), every contour vertex of the node has exactly two contour edges (a single fan
/// in the node), and V − E + F = 1 (a connected orientable surface with boundary has
/// χ = 2 − 2g − b, so χ = 1 means g = 0, b = 1: a disk). Single triangles are always disks but are
/// never tested (a triangle cannot collide with itself), so their contours are not stored.

#include <cstdint>
#include <span>
#include <vector>

#include "weft/backend/collision_primitives.h"
#include "weft/types.h"

namespace weft::collision {

/// Marks "none": no node, no triangle, no patch.
inline constexpr std::uint32_t kNone = 0xFFFFFFFFU;

/// A directed contour edge: the node's triangle on its side runs from `a` to `b` (global vertex ids).
struct ContourEdge {
    std::uint32_t a = 0;
    std::uint32_t b = 0;
};

/// The hierarchy, as flat arrays (structure of arrays, indexed by node unless said otherwise).
/// Immutable after `build_patch_hierarchy`; shared by any number of fronts.
struct PatchHierarchy {
    static constexpr std::uint8_t kDisk = 1;  ///< node_flags: topological disk, testable

    std::uint32_t vertex_count = 0, triangle_count = 0, edge_count = 0;

    // ---- Nodes ----
    /// Node n covers triangles triangle_order[node_first[n] .. node_first[n] + node_count[n]).
    std::vector<std::uint32_t> node_first, node_count;
    /// Left child (the right one is node_child[n] + 1, always larger than n); kNone for a leaf.
    std::vector<std::uint32_t> node_child;
    std::vector<std::uint32_t> node_parent;  ///< kNone for a root
    std::vector<std::uint8_t> node_flags;
    /// Nodes of level k are [level_first[k], level_first[k + 1]); level 0 holds the roots.
    std::vector<std::uint32_t> level_first;
    /// Contour of node n: contour_edges[contour_first[n] .. contour_first[n + 1]), stored only for
    /// disks with more than one triangle (empty otherwise); sorted by (min, max) vertex.
    std::vector<std::uint32_t> contour_first;
    std::vector<ContourEdge> contour_edges;

    // ---- Triangles, vertices, edges ----
    std::vector<Triangle> triangles;            ///< the mesh's triangles (a copy: the refit reads them)
    std::vector<std::uint32_t> triangle_order;  ///< triangles in node order: every node a contiguous run
    std::vector<std::uint32_t> triangle_leaf;   ///< leaf node of each triangle
    /// The one incident triangle whose patch a vertex (an edge) takes: the lowest-index triangle
    /// using it; kNone for a vertex no triangle uses.
    std::vector<std::uint32_t> vertex_triangle, edge_triangle;

    [[nodiscard]] std::size_t node_size() const { return node_first.size(); }
    [[nodiscard]] std::size_t levels() const { return level_first.empty() ? 0 : level_first.size() - 1; }
    [[nodiscard]] bool is_leaf(std::uint32_t n) const { return node_child[n] == kNone; }
    [[nodiscard]] std::span<const ContourEdge> contour(std::uint32_t n) const {
        return {contour_edges.data() + contour_first[n], contour_edges.data() + contour_first[n + 1]};
    }
};

/// Builds the hierarchy over `triangles` (global vertex ids into `rest`, whose positions guide the
/// splits only: any positions give a correct hierarchy, rest or initial ones a good one). `edges`
/// is the broad phase's edge list (`build_edges(triangles)`) for `edge_triangle`; empty leaves
/// `edge_triangle` empty. `triangle_cloth` (optional, as in `BroadPhaseInput`) keeps patches within
/// one cloth. Throws `weft::Error` for an index out of range, a triangle repeating a vertex or a
/// size mismatch. Deterministic; single-threaded (it runs once per mesh).
[[nodiscard]] PatchHierarchy build_patch_hierarchy(std::span<const Vec3d> rest, std::span<const Triangle> triangles,
                                                   std::span<const Edge> edges = {},
                                                   std::span<const std::uint32_t> triangle_cloth = {});

}  // namespace weft::collision
