#pragma once
// The multi-GPU partition the solver uses, for tests: a flat model's vertices cut along the
// multilevel Schwarz preconditioner's order into `parts` runs of whole level-0 domains.

#include "weft/backend/flat_model.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/backend/vertex_partition.h"

namespace weft::test {

inline VertexPartition partition_along_preconditioner(const FlatModel& flat, std::uint32_t parts) {
    const SchwarzHierarchy h = build_schwarz_hierarchy(flat.initial_positions, flat.pattern);
    const std::vector<double> work = row_work(flat.pattern);
    return build_partition(flat.pattern, cut_order(h.order, work, parts, SchwarzHierarchy::kDomainSize), parts, work);
}

}  // namespace weft::test
