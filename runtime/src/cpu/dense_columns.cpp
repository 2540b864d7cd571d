// See dense_columns.h.
#include "cpu/dense_columns.h"

#include "cpu/vector_clones.h"

namespace weft::cpu {
namespace {

constexpr std::uint32_t kDim = SchwarzHierarchy::kDomainDim;

template <typename T>
inline void columns_times(const T* columns, const T* in, T* out) {
    for (std::uint32_t i = 0; i < kDim; ++i) out[i] = T(0);
    for (std::uint32_t j = 0; j < kDim; ++j) {
        const T* column = columns + j * kDim;
        const T x = in[j];
        for (std::uint32_t i = 0; i < kDim; ++i) out[i] += column[i] * x;
    }
}

}  // namespace

WEFT_VECTOR_CLONES void dense_columns_times(const double* columns, const double* in, double* out) {
    columns_times(columns, in, out);
}

WEFT_VECTOR_CLONES void dense_columns_times(const float* columns, const float* in, float* out) {
    columns_times(columns, in, out);
}

}  // namespace weft::cpu
