#pragma once
// The product of one Schwarz domain's dense inverse, stored by columns, with a vector: the inner
// loop of the CPU preconditioner's apply (cpu/schwarz_preconditioner.h), out of line so that it is
// built for AVX2 as well (cpu/vector_clones.h). Every out[i] sums its products in j order from zero.

#include <cstdint>

#include "weft/backend/schwarz_hierarchy.h"

namespace weft::cpu {

/// out[i] = Σ_j columns[j·kDomainDim + i]·in[j] (j ascending) for i < kDomainDim.
void dense_columns_times(const double* columns, const double* in, double* out);
void dense_columns_times(const float* columns, const float* in, float* out);

}  // namespace weft::cpu
