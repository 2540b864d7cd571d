#pragma once
/// @file
/// Whole-mesh exact intersection check (issue 4, item 6): finds every pair of triangles that
/// intersect, leaving out pairs that share a vertex (neighbours in the mesh always touch). Meant to
/// verify a final state (the collision tests; `weft run --check` as planned in docs/collisions.md):
/// the answer is exact, not a tolerance, because the narrow phase is `physics::triangles_intersect`
/// on exact predicates.
///
/// Broad phase: a uniform grid over the triangles' bounding boxes (cell edge about the typical
/// triangle size). Each triangle is listed in every cell its box overlaps; the (cell, triangle)
/// entries are sorted, and the pairs of each cell are tested. A pair whose boxes overlap is tested in
/// exactly one cell: the one holding the low corner of the boxes' intersection. Triangles whose box
/// covers too many cells are tested against every triangle directly instead. The result does not
/// depend on the thread count or on the order the work ran in.

#include <compare>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "weft/types.h"

namespace weft::collision {

/// Two intersecting triangles, `a < b` (indices into the triangle list).
struct IntersectingPair {
    std::uint32_t a = 0;
    std::uint32_t b = 0;
    friend auto operator<=>(const IntersectingPair&, const IntersectingPair&) = default;
};

struct IntersectionCheckOptions {
    /// How many intersecting pairs the report lists (the smallest by (a, b)); the count is always
    /// complete.
    std::size_t max_examples = 16;
    /// Grid cell edge, m. 0 picks the median of the triangles' largest box extents.
    double cell_size = 0.0;
};

struct IntersectionReport {
    std::size_t intersecting_pairs = 0;      ///< triangle pairs sharing no vertex that intersect
    std::vector<IntersectingPair> examples;  ///< the smallest of them by (a, b), sorted; at most max_examples
    std::size_t triangles_checked = 0;       ///< triangles with finite vertices
    std::size_t nonfinite_triangles = 0;     ///< skipped: a vertex is NaN or infinite
    std::size_t oversized_triangles = 0;     ///< box over too many cells: tested against all others directly
    std::size_t candidate_pairs = 0;         ///< pairs with overlapping boxes and no shared vertex (tested exactly)
    double cell_size = 0.0;                  ///< grid cell edge used, m

    [[nodiscard]] bool clean() const { return intersecting_pairs == 0; }
};

/// Every pair of `triangles` (indices into `positions`; several meshes may be concatenated, e.g.
/// the flat model's global triangles) that intersect as closed triangles and share no vertex index.
/// Touching counts as intersecting. Triangles with a non-finite vertex are skipped and counted.
/// Throws `weft::Error` for a vertex index out of range or more than 2^32 − 1 triangles.
[[nodiscard]] IntersectionReport check_intersections(std::span<const Vec3d> positions,
                                                     std::span<const Triangle> triangles,
                                                     const IntersectionCheckOptions& options = {});

}  // namespace weft::collision
