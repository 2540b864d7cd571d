#pragma once
// Block sparse row matrix with 3×3 blocks over a fixed pattern (weft::BlockPattern).

#include <vector>

#include "cpu/bsr_rows.h"
#include "deterministic_parallel.h"
#include "weft/fabric.h"
#include "weft/physics/vec.h"

namespace weft::cpu {

template <typename T>
struct BsrMatrix {
    const BlockPattern* pattern = nullptr;
    /// Each slot's 3×3 block stored by columns (its transpose: columns[s].m[c] is column c of block
    /// s), then one zero block of padding. The product reads a column as one 4-lane vector, the 4th
    /// lane running into the next column (or the padding), so that every row of the block is a lane
    /// (cpu/bsr_rows.cpp). Write and read through set_block and block.
    std::vector<physics::Mat3<T>> columns;

    void resize(const BlockPattern& p) {
        pattern = &p;
        columns.assign(p.block_count() + 1, physics::Mat3<T>{});
    }
    [[nodiscard]] std::size_t rows() const { return pattern->diagonal.size(); }
    /// Slot s's block, row-major (a transpose: exact).
    [[nodiscard]] physics::Mat3<T> block(std::size_t s) const { return physics::transpose(columns[s]); }
    void set_block(std::size_t s, const physics::Mat3<T>& m) { columns[s] = physics::transpose(m); }
    /// The 3×3 diagonal block of row i (what block-Jacobi inverts).
    [[nodiscard]] physics::Mat3<T> diagonal_block(std::size_t i) const { return block(pattern->diagonal[i]); }

    /// y = A x, one block row per task.
    void multiply(const std::vector<physics::Vec3<T>>& x, std::vector<physics::Vec3<T>>& y) const {
        const auto& rs = pattern->row_start;
        const auto& col = pattern->column;
        parallel_chunks(rows(), [&](std::size_t b, std::size_t e) {
            bsr_rows_times(columns.data(), rs.data(), col.data(), x.data(), y.data(), b, e);
        });
    }

    /// y = filter(A x) and returns xᵀy in one pass (the CG's step denominator without a second
    /// sweep over the vectors): the same chunks and order as deterministic_sum, so the same bits as
    /// multiplying and summing apart. `fixed[i]` != 0 zeroes row i. `partials` is scratch.
    double multiply_dot(const std::vector<physics::Vec3<T>>& x, std::vector<physics::Vec3<T>>& y,
                        const std::vector<std::uint8_t>& fixed, std::vector<double>& partials) const {
        const auto& rs = pattern->row_start;
        const auto& col = pattern->column;
        return deterministic_sum(rows(), partials, [&](std::size_t b, std::size_t e) {
            return bsr_rows_times_dot(columns.data(), rs.data(), col.data(), x.data(), y.data(), fixed.data(), b, e);
        });
    }
};

}  // namespace weft::cpu
