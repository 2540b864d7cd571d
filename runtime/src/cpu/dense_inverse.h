#pragma once
// The inverse of one Schwarz domain's dense matrix (kDomainDim × kDomainDim, SPD), stored by
// columns for dense_columns_times: the factorisation of the CPU preconditioner
// (cpu/schwarz_preconditioner.h), out of line so that it is built for AVX2 as well
// (cpu/vector_clones.h), where its row updates run 8 floats (4 doubles) at a time.

#include "weft/backend/schwarz_hierarchy.h"

namespace weft::cpu {

/// Replaces the row-major SPD matrix D with its inverse, transposed (column-major), by Gauss–Jordan
/// elimination without pivoting (the same algorithm as the GPU's, schwarz_kernels.cu). Returns true
/// if a pivot was not positive (D is not SPD in this precision); that pivot is replaced by the
/// magnitude of the original diagonal entry, so the result stays usable.
bool dense_invert_to_columns(double* D);
bool dense_invert_to_columns(float* D);

}  // namespace weft::cpu
