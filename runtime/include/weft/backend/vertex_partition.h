#pragma once
/// @file
/// The world's vertices cut into parts, one per GPU (docs/multi-gpu.md): which rows each part owns,
/// which vertices it reads but does not own (its ghosts, or halo), and which of its own vertices it
/// sends to each other part. Backend kit: built once per topology, on the host.
///
/// A part's rows are the matrix rows of its owned vertices. Every element that touches an owned
/// vertex couples it to the element's other vertices, and the block pattern holds a block for every
/// such pair, so the ghosts of a part are exactly the pattern neighbours of its rows that other
/// parts own: one ring of the pattern is as deep as both the product A·x of the owned rows and the
/// assembly of their forces and blocks need.
///
/// Owned vertices are listed interior first (no pattern neighbour outside the part), then boundary:
/// a pipelined product computes the interior rows while the ghosts' values travel, then the
/// boundary rows (P-Cloth's overlap of the halo exchange with the SpMV).
///
/// The bending models per triangle (SolverSettings::bending = Shell) read deeper: a row's hinge
/// takes terms from its two faces, and each face's terms read all three of its hinges, whose far
/// corners lie two rings out. A partition built with that reach (per_triangle_bending_reach) lists
/// those vertices among the ghosts too; the product still reads the pattern's ring only, so the
/// interior rows stay those without a pattern neighbour outside the part.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "weft/fabric.h"

namespace weft {

struct FlatModel;

/// One part of a VertexPartition. Vertex ids are global (the FlatModel's) unless said otherwise.
struct PartitionPart {
    /// The vertices this part owns, interior first, each group in increasing global id.
    std::vector<std::uint32_t> owned;
    std::uint32_t interior = 0;  ///< owned[0, interior) are interior, the rest boundary
    /// The vertices its rows read that other parts own, grouped by owner part (in increasing part,
    /// then global id): those of part q are ghosts[ghost_start[q], ghost_start[q + 1]).
    std::vector<std::uint32_t> ghosts;
    std::vector<std::uint32_t> ghost_start;  ///< size parts + 1
    /// The owned vertices other parts read, grouped by receiving part in the order that part lists
    /// them among its ghosts: part q receives send[send_start[q], send_start[q + 1]), which are
    /// indices into `owned` (local), so that part q's ghosts from this part are
    /// owned[send[send_start[q] + k]] for k in order.
    std::vector<std::uint32_t> send;
    std::vector<std::uint32_t> send_start;  ///< size parts + 1
    double work = 0.0;                      ///< the sum of its owned vertices' work

    [[nodiscard]] std::uint32_t boundary() const { return static_cast<std::uint32_t>(owned.size()) - interior; }
};

/// How well a partition cuts: what the multi-GPU solve pays per product and per step.
struct PartitionQuality {
    std::uint64_t cut_blocks = 0;      ///< off-diagonal pattern blocks whose row and column lie in different parts
    std::uint64_t halo_vertices = 0;   ///< ghosts summed over the parts (values received per product)
    std::uint64_t boundary_vertices = 0;  ///< owned boundary vertices summed over the parts
    double imbalance = 1.0;            ///< the largest part's work over the mean part's (1 is perfect)
};

struct VertexPartition {
    std::uint32_t parts = 0;
    std::vector<std::uint32_t> part_of;      ///< the owning part of each global vertex
    std::vector<std::uint32_t> local_index;  ///< each global vertex's index in its owner's `owned`
    std::vector<PartitionPart> part;
    PartitionQuality quality;
};

/// The work of each row for balancing: the pattern's blocks in it (the product's and the
/// assembly's cost both follow them).
[[nodiscard]] std::vector<double> row_work(const BlockPattern& pattern);

/// The cost of one contact's vertex in a row, in the units of row_work (pattern blocks). A contact
/// costs every CG iteration a pair pass (its four vertices gathered, weighted, multiplied) and a row
/// gather at each of its cloth vertices. From the one-launch loop's clock on the 1.2M-triangle flag
/// with self-contact on two H200s (WEFT_CUDA_PCG_CLOCK=1): the parts' row phases cost about 51 µs an
/// iteration per million pattern blocks and their contact phases about 19.5 µs per million incidence
/// entries (a contact's vertex), so about 0.38; the re-cut was then run at 0.125–1 in one call
/// (WEFT_GPU_CONTACT_WORK, docs/multi-gpu.md) and 0.3 left the parts the closest (waits of 34 µs
/// against 53 at 0.38 and 0.5; below 0.3 the imbalance stays under solver.gpu_rebalance and no
/// re-cut happens). The row sums' cost follows how the contacts crowd into rows, which no count
/// captures, so the weight is a compromise.
inline constexpr double kContactWorkPerVertex = 0.3;

/// How uneven the parts' CG work is: the busiest part's over the mean part's (1 is even), a part's
/// work being its rows' row_work (`part_rows`) plus 4·kContactWorkPerVertex for every contact it
/// holds (`part_contacts`, a contact across a cut on each part it touches: each part runs its pair
/// pass). `contact_work`: a contact's vertex in pattern blocks (the constant, unless profiling
/// overrides it). Throws weft::Error when the spans' sizes differ. 1 where there is no work.
[[nodiscard]] double part_work_imbalance(std::span<const double> part_rows, std::span<const std::size_t> part_contacts,
                                         double contact_work = kContactWorkPerVertex);

/// row_work plus kContactWorkPerVertex for every contact at the row's vertex (`contacts_at`, one
/// count a vertex: a re-cut by contact load balances both).
[[nodiscard]] std::vector<double> row_and_contact_work(const BlockPattern& pattern, std::span<const std::uint32_t> contacts_at,
                                                       double contact_work = kContactWorkPerVertex);

/// Cuts `order` (every vertex once, e.g. the multilevel Schwarz preconditioner's level-0 order:
/// spatially local runs) into `parts` contiguous runs of nearly equal `work`, each run a whole
/// number of `granule` consecutive entries (the preconditioner's domain size keeps every level-0
/// domain on one part), and returns each vertex's part. Throws weft::Error naming the value when
/// `parts` is 0, or greater than the granules there are, or the sizes disagree.
[[nodiscard]] std::vector<std::uint32_t> cut_order(std::span<const std::uint32_t> order, std::span<const double> work,
                                                   std::uint32_t parts, std::uint32_t granule);

/// Vertices each row's assembly reads beyond its pattern neighbours, as lists per global vertex:
/// vertex i reads vertex[start[i], start[i + 1]).
struct VertexReach {
    std::vector<std::uint32_t> start;  ///< size vertices + 1
    std::vector<std::uint32_t> vertex;
};

/// The reach of the bending models per triangle on `flat`: for each vertex, the vertices of every
/// hinge of every face of every hinge through it (weft/physics/shell_bending_slots.h: a hinge's
/// terms come from its faces, each face's from its three hinges). Sorted, without repeats.
[[nodiscard]] VertexReach per_triangle_bending_reach(const FlatModel& flat);

/// The owned, interior, ghost and send lists of each part for the assignment `part_of` (each
/// vertex's part, < parts; a part may own nothing) on `pattern`, and the quality of the cut.
/// `reach` (optional): vertices the rows read beyond the pattern, which become ghosts as well.
/// Deterministic. Throws weft::Error when the sizes disagree or a part id is out of range.
[[nodiscard]] VertexPartition build_partition(const BlockPattern& pattern, std::span<const std::uint32_t> part_of,
                                              std::uint32_t parts, std::span<const double> work,
                                              const VertexReach* reach = nullptr);

/// The multi-GPU solver's partition of `flat` (docs/multi-gpu.md, "Partition"): its vertices cut
/// along the multilevel Schwarz preconditioner's level-0 order into `parts` runs of whole level-0
/// domains of nearly equal row work. Throws weft::Error as cut_order does.
[[nodiscard]] VertexPartition partition_along_preconditioner(const FlatModel& flat, std::uint32_t parts);

/// One line: parts, cut blocks, halo and boundary vertices, imbalance (for logs and benchmarks).
[[nodiscard]] std::string describe(const PartitionQuality& quality, std::uint32_t parts);

}  // namespace weft
