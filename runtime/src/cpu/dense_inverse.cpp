// See dense_inverse.h.
#include "cpu/dense_inverse.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "cpu/vector_clones.h"

namespace weft::cpu {
namespace {

constexpr std::uint32_t kDim = SchwarzHierarchy::kDomainDim;

/// Every step is a rank-one update of whole rows, which the compiler vectorises. Always inlined:
/// a call out of the AVX2 clone would run the baseline build of the loops.
///
/// Rows whose entry in the pivot's column is zero are skipped: a domain couples each node to its
/// few mesh neighbours, so at a step many rows have nothing to eliminate (on the demo flag's
/// domains 30 of 47 rows are updated a step). The rows to update are listed first, then updated
/// without a branch a row: which rows are zero changes from step to step, and a mispredicted
/// branch cost about as much as a row's update.
///
/// Skipping gives the same bits as updating, for a matrix with finite entries: row[j] − (±0·row_k[j])
/// equals row[j] except when row[j] = −0, and no entry is ever −0 here. The domain matrices are
/// sums that start from +0 (an exact cancellation rounds to +0), the pivot row is scaled by a
/// positive 1/pivot, and a difference x − y is −0 only for x = −0; so by induction none appears
/// during the elimination either.
template <typename T>
[[gnu::always_inline]] inline bool invert(T* D) {
    bool failed = false;
    T magnitude[kDim], column[kDim];
    std::uint32_t active[kDim];  // the rows this step updates
    for (std::uint32_t k = 0; k < kDim; ++k) magnitude[k] = std::max(std::abs(D[k * kDim + k]), T(1e-12));
    for (std::uint32_t k = 0; k < kDim; ++k) {
        for (std::uint32_t i = 0; i < kDim; ++i) column[i] = D[i * kDim + k];
        T pivot = column[k];
        if (!(pivot > T(0))) {
            failed = true;
            pivot = magnitude[k];
        }
        const T inverse = T(1) / pivot;
        T* row_k = D + k * kDim;
        for (std::uint32_t j = 0; j < kDim; ++j) row_k[j] *= inverse;
        row_k[k] = inverse;
        // Every other row loses its entry in the pivot's column; those where it was zero have
        // nothing else to update (see above).
        std::uint32_t count = 0;
        for (std::uint32_t i = 0; i < kDim; ++i) {
            active[count] = i;
            count += i != k && column[i] != T(0) ? 1u : 0u;
            if (i != k) D[i * kDim + k] = T(0);
        }
        for (std::uint32_t a = 0; a < count; ++a) {
            T* row = D + active[a] * kDim;
            const T f = column[active[a]];
            for (std::uint32_t j = 0; j < kDim; ++j) row[j] -= f * row_k[j];
        }
    }
    return failed;
}

template <typename T>
[[gnu::always_inline]] inline void transpose(T* D) {
    for (std::uint32_t i = 0; i < kDim; ++i)
        for (std::uint32_t j = i + 1; j < kDim; ++j) std::swap(D[i * kDim + j], D[j * kDim + i]);
}

}  // namespace

WEFT_VECTOR_CLONES bool dense_invert_to_columns(double* D) {
    const bool failed = invert(D);
    transpose(D);
    return failed;
}

WEFT_VECTOR_CLONES bool dense_invert_to_columns(float* D) {
    const bool failed = invert(D);
    transpose(D);
    return failed;
}

}  // namespace weft::cpu
