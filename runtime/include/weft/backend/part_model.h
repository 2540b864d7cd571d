#pragma once
/// @file
/// One part of a partitioned world as a model of its own (docs/multi-gpu.md, "Per-GPU state"): the
/// vertices a GPU owns, then its ghosts; the elements that touch an owned vertex; the pattern rows
/// those elements fill. Backend kit, built on the host once per topology.
///
/// The owned rows are the global rows exactly: the same columns in the same order, each slot summing
/// the same element blocks in the same order, each vertex gathering the same element forces in the
/// same order. A backend that assembles and multiplies the owned rows of every part therefore gets
/// the bits of the whole system, whatever the number of parts. Ghost rows hold only the blocks of
/// the part's own elements: they are never solved for (their values arrive from their owners).

#include <cstdint>
#include <vector>

#include "weft/backend/flat_model.h"
#include "weft/backend/vertex_partition.h"

namespace weft {

struct PartModel {
    /// The part as a FlatModel over local vertices: owned (interior, then boundary, as
    /// PartitionPart::owned), then ghosts (as PartitionPart::ghosts). Its elements are the global
    /// elements that touch an owned vertex (and with per-triangle bending those its rows' bending
    /// reads: extract_part), in global order, with local vertex ids; its pins are the
    /// owned vertices' pins. Cloth offsets are left empty (a part's vertices are not runs of cloths):
    /// `global_vertex` maps back.
    FlatModel model;
    std::uint32_t owned = 0;     ///< local vertices [0, owned) are owned, [owned, vertex_count) ghosts
    std::uint32_t interior = 0;  ///< local vertices [0, interior) have no neighbour in another part
    std::vector<std::uint32_t> global_vertex;    ///< per local vertex
    std::vector<std::uint32_t> global_triangle;  ///< per local triangle
    std::vector<std::uint32_t> global_hinge;     ///< per local hinge
    std::vector<std::uint32_t> global_slot;      ///< per local pattern slot: the global slot it copies
};

/// Part `p` of `partition` of `flat`. With `per_triangle_bending` (SolverSettings::bending = Shell)
/// it also holds the faces of every hinge through an owned vertex and those faces' hinges (whose
/// terms the owned rows' bending reads; they touch ghosts only), and its triangles' hinges (local
/// ids) and shell rest data; the partition must then have been built with
/// per_triangle_bending_reach. Throws weft::Error when `p` is out of range or the partition was not
/// built on this model's pattern and reach (an element with a vertex that is neither owned nor a
/// ghost).
[[nodiscard]] PartModel extract_part(const FlatModel& flat, const VertexPartition& partition, std::uint32_t p,
                                     bool per_triangle_bending = false);

}  // namespace weft
