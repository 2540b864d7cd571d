#pragma once
/// @file
/// One part's share of the multilevel Schwarz preconditioner across GPUs (docs/multi-gpu.md, "The
/// CG iteration"). Backend kit, built on the host once per topology.
///
/// The parts cut the whole hierarchy's level-0 order at domain boundaries
/// (partition_along_preconditioner), so each part owns whole level-0 domains and the level-1 nodes
/// they make, and each level-1 coupling block of a row node it owns sums pattern slots of rows it
/// owns. A part therefore computes level 0 alone, and its own rows of level 1 (the restricted
/// residual each CG iteration, the coupling blocks each Newton iteration); gathering those from
/// every part gives each GPU the whole of level 1, from which it computes levels ≥ 1 exactly as one
/// GPU would. The preconditioner is the single-GPU one on any number of parts.

#include <cstdint>

#include "weft/backend/part_model.h"
#include "weft/backend/schwarz_hierarchy.h"

namespace weft {

struct PartSchwarz {
    /// The tables a device uploads. Level 0 is the part's: its nodes are the part's owned vertices
    /// in the whole order (order and rank in local vertex ids, rank sized to the local vertex
    /// count), its couplings the part's pattern slots, its parents the whole hierarchy's level-1
    /// node ids. Levels ≥ 1 are the whole hierarchy's, except level 1's coupling sources: only the
    /// part's own entries [entry_begin, entry_end), `source_start` indexed from entry_begin and
    /// `source` naming the part's local pattern slots. Level 1's entry_row and entry_column stay
    /// whole (their count sizes the coupling array every part holds).
    SchwarzHierarchy levels;
    std::uint32_t first_domain = 0;  ///< the part's level-0 domains are the whole's [first_domain, + levels.domains(0))
    std::uint32_t node_begin = 0, node_end = 0;    ///< level-1 nodes made by the part's domains
    std::uint32_t entry_begin = 0, entry_end = 0;  ///< level-1 coupling entries whose row node is the part's
};

/// Part `part`'s share of `whole` (built on the whole flat model the part was extracted from, with
/// the partition cut along its order). Throws weft::Error when the part's vertices are not whole
/// level-0 domains of `whole` or a coupling's source is not a slot of the part's owned rows (a
/// partition or hierarchy of another model).
[[nodiscard]] PartSchwarz extract_part_schwarz(const SchwarzHierarchy& whole, const PartModel& part);

}  // namespace weft
