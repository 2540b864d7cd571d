#pragma once
// The rows of a BSR product, y_i = Σ_s A_s·x_col(s) over rows [begin, end): the inner loop of the
// CPU solver's CG (cpu/bsr_matrix.h), out of line so that it is built for AVX2 as well
// (cpu/vector_clones.h). The blocks come by columns (BsrMatrix::columns, one padding block after
// the last); the sums run in slot order, each row of a block as Mat3 × Vec3 of weft/math/vec.h
// forms it, so the bits are those of the row-major product.

#include <cstddef>
#include <cstdint>

#include "weft/physics/vec.h"

namespace weft::cpu {

void bsr_rows_times(const physics::Mat3<double>* columns, const std::uint32_t* row_start, const std::uint32_t* column,
                    const physics::Vec3<double>* x, physics::Vec3<double>* y, std::size_t begin, std::size_t end);
void bsr_rows_times(const physics::Mat3<float>* columns, const std::uint32_t* row_start, const std::uint32_t* column,
                    const physics::Vec3<float>* x, physics::Vec3<float>* y, std::size_t begin, std::size_t end);

/// The same with rows where fixed[i] != 0 set to zero, returning Σ_i x_i·y_i over the rows (in
/// double, row order).
double bsr_rows_times_dot(const physics::Mat3<double>* columns, const std::uint32_t* row_start, const std::uint32_t* column,
                          const physics::Vec3<double>* x, physics::Vec3<double>* y, const std::uint8_t* fixed,
                          std::size_t begin, std::size_t end);
double bsr_rows_times_dot(const physics::Mat3<float>* columns, const std::uint32_t* row_start, const std::uint32_t* column,
                          const physics::Vec3<float>* x, physics::Vec3<float>* y, const std::uint8_t* fixed,
                          std::size_t begin, std::size_t end);

}  // namespace weft::cpu
