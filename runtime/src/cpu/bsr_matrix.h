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
    std::vector<physics::Mat3<T>> blocks;

    void resize(const BlockPattern& p) {
        pattern = &p;
        blocks.assign(p.block_count(), physics::Mat3<T>{});
    }
    [[nodiscard]] std::size_t rows() const { return pattern->diagonal.size(); }
    /// The 3×3 diagonal block of row i (what block-Jacobi inverts).
    [[nodiscard]] physics::Mat3<T> diagonal_block(std::size_t i) const { return blocks[pattern->diagonal[i]]; }

    /// y = A x, one block row per task.
    void multiply(const std::vector<physics::Vec3<T>>& x, std::vector<physics::Vec3<T>>& y) const {
        const auto& rs = pattern->row_start;
        const auto& col = pattern->column;
        parallel_chunks(rows(), [&](std::size_t b, std::size_t e) {
            bsr_rows_times(blocks.data(), rs.data(), col.data(), x.data(), y.data(), b, e);
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
            return bsr_rows_times_dot(blocks.data(), rs.data(), col.data(), x.data(), y.data(), fixed.data(), b, e);
        });
    }
};

}  // namespace weft::cpu
