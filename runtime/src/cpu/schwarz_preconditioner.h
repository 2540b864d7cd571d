#pragma once
// The multilevel additive Schwarz preconditioner on the CPU (Wu, Wang & Wang 2022; docs/methods.md
// §2b; the levels are weft/backend/schwarz_hierarchy.h): M⁻¹ = Σ_l R_lᵀ D_l⁻¹ R_l. Every substep
// it aggregates the assembled 3×3 blocks level by level into coupling blocks (the hierarchy's fixed
// sums), writes each level's domain matrices (dense, 48×48 for domains of 16 nodes), factors them
// (Gauss–Jordan, to the explicit inverse, as on the GPU; cpu/dense_inverse.h), and applies all
// levels to a residual. Work is split by domain, each domain written by one task in a fixed order:
// the result does not depend on the thread count.
//
// Filtered (pinned) vertices: the solve acts on the free vertices only (S·A·S), so their blocks are
// left out of every level and a vertex or node with nothing left gets the identity (it is decoupled,
// and its value is filtered out anyway). Contact springs add their diagonal blocks (Σ w_i²·C) to
// their vertex's node, on every level; their couplings between vertices are not aggregated yet.

#include <algorithm>
#include <cstdint>
#include <vector>

#include "cpu/aligned_allocator.h"
#include "cpu/bsr_matrix.h"
#include "cpu/dense_columns.h"
#include "cpu/dense_inverse.h"
#include "deterministic_parallel.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/physics/vec.h"

namespace weft::cpu {

template <typename T>
class SchwarzPreconditioner {
public:
    using V3 = physics::Vec3<T>;
    using M3 = physics::Mat3<T>;
    static constexpr std::uint32_t kNodes = SchwarzHierarchy::kDomainSize;
    static constexpr std::uint32_t kDim = SchwarzHierarchy::kDomainDim;  // rows of a dense domain matrix
    /// Domains per task: a domain is ~5K multiply-adds to solve and ~40K to factor, so a few make a
    /// task worth scheduling.
    static constexpr std::size_t kDomainGrain = 8;

    /// Sizes the work arrays for `h`, built on `pattern` (the matrix's).
    void build(const SchwarzHierarchy& h, const BlockPattern& pattern) {
        h_ = &h;
        const auto levels = static_cast<std::size_t>(h.levels());
        slot_row_.resize(pattern.column.size());
        for (std::uint32_t i = 0; i + 1 < pattern.row_start.size(); ++i)
            for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s) slot_row_[s] = i;
        couplings_.resize(levels);
        failed_.resize(levels);
        dense_.resize(levels);
        values_.resize(levels);
        solved_.resize(levels);
        for (std::size_t l = 0; l < levels; ++l) {
            const SchwarzLevel& level = h.level[l];
            couplings_[l].assign(l == 0 ? pattern.column.size() : level.entry_row.size(), M3{});
            dense_[l].assign(std::size_t(level.domains()) * kDim * kDim, T(0));
            failed_[l].assign(level.domains(), 0);
            values_[l].assign(std::size_t(level.domains()) * kNodes, V3{});
            solved_[l].assign(std::size_t(level.domains()) * kNodes, V3{});
        }
    }

    [[nodiscard]] bool built() const { return h_ != nullptr; }
    [[nodiscard]] int levels() const { return h_ ? h_->levels() : 0; }
    /// Domain inversions that met a non-positive pivot in the last `factor` (a matrix that is not SPD
    /// in this precision); their pivot was replaced by the diagonal's magnitude.
    [[nodiscard]] int pivot_failures() const { return pivot_failures_; }

    /// Aggregates `A` (plus `extra_diagonal(i)`, the contact springs' share of row i's diagonal block)
    /// into every level's coupling blocks and domain matrices, and factors the domains.
    template <typename ExtraDiagonal>
    void factor(const BsrMatrix<T>& A, const std::vector<std::uint8_t>& fixed, ExtraDiagonal&& extra_diagonal) {
        const SchwarzHierarchy& h = *h_;
        const auto& column = A.pattern->column;
        // Level 0: A's blocks without the filtered (pinned) rows and columns: the solve acts on S·A·S.
        std::vector<M3>& fine = couplings_[0];
        parallel_chunks(fine.size(), [&](std::size_t lo, std::size_t hi) {
            for (std::size_t s = lo; s < hi; ++s) {
                const std::uint32_t i = slot_row_[s], j = column[s];
                fine[s] = fixed[i] || fixed[j] ? M3{} : (i == j ? A.block(s) + extra_diagonal(i) : A.block(s));
            }
        });
        // Coarser levels: each coupling block sums its listed blocks of the level below, in order.
        for (int l = 1; l < h.levels(); ++l) {
            const SchwarzLevel& level = h.level[static_cast<std::size_t>(l)];
            const std::vector<M3>& below = couplings_[static_cast<std::size_t>(l - 1)];
            std::vector<M3>& out = couplings_[static_cast<std::size_t>(l)];
            parallel_chunks(out.size(), [&](std::size_t lo, std::size_t hi) {
                for (std::size_t e = lo; e < hi; ++e) {
                    M3 acc{};
                    for (std::uint32_t k = level.source_start[e]; k < level.source_start[e + 1]; ++k) acc += below[level.source[k]];
                    out[e] = acc;
                }
            });
        }
        int failures = 0;
        for (int l = 0; l < h.levels(); ++l) {
            const SchwarzLevel& level = h.level[static_cast<std::size_t>(l)];
            const std::vector<M3>& blocks = couplings_[static_cast<std::size_t>(l)];
            auto& dense = dense_[static_cast<std::size_t>(l)];
            std::fill(dense.begin(), dense.end(), T(0));
            // Each dense block comes from one coupling: the writes never collide.
            parallel_chunks(level.dense_entry.size(), [&](std::size_t lo, std::size_t hi) {
                for (std::size_t k = lo; k < hi; ++k) put_block(dense.data(), level.dense_block[k], blocks[level.dense_entry[k]]);
            });
            std::vector<std::uint8_t>& failed = failed_[static_cast<std::size_t>(l)];
            parallel_grains(level.domains(), kDomainGrain, [&](std::size_t lo, std::size_t hi) {
                for (std::size_t d = lo; d < hi; ++d) {
                    T* D = &dense[d * kDim * kDim];
                    // Nodes with nothing (all pinned, or past the end of the last domain) are decoupled.
                    for (std::uint32_t k = 0; k < kDim; ++k)
                        if (D[k * kDim + k] == T(0)) D[k * kDim + k] = T(1);
                    failed[d] = dense_invert_to_columns(D) ? 1 : 0;  // column-major for solve_domain
                }
            });
            for (const std::uint8_t f : failed) failures += f;
        }
        pivot_failures_ = failures;
    }

    /// z = M⁻¹ r over all vertices (the caller filters r before and z after). Two passes over the
    /// vertices and one per coarse level: level 0's domains gather their residuals, solve and restrict
    /// in one task each; each coarser level solves and restricts; then every vertex sums its nodes'
    /// corrections on every level.
    void apply(const std::vector<V3>& r, std::vector<V3>& z) {
        const SchwarzHierarchy& h = *h_;
        const int levels = h.levels();
        for (int l = 0; l < levels; ++l) {
            const SchwarzLevel& level = h.level[static_cast<std::size_t>(l)];
            std::vector<V3>& v = values_[static_cast<std::size_t>(l)];
            const auto& dense = dense_[static_cast<std::size_t>(l)];
            std::vector<V3>& y = solved_[static_cast<std::size_t>(l)];
            parallel_grains(level.domains(), kDomainGrain, [&](std::size_t lo, std::size_t hi) {
                for (std::size_t d = lo; d < hi; ++d) {
                    if (l == 0) {
                        for (std::size_t p = d * kNodes; p < (d + 1) * kNodes; ++p) v[p] = p < h.vertex_count ? r[h.order[p]] : V3{};
                    }
                    solve_domain(&dense[d * kDim * kDim], &v[d * kNodes], &y[d * kNodes]);
                    if (l + 1 < levels) restrict_domain(level, d, &v[d * kNodes], values_[static_cast<std::size_t>(l + 1)]);
                }
            });
        }
        parallel_chunks(h.vertex_count, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t p = lo; p < hi; ++p) {
                V3 sum = solved_[0][p];
                std::uint32_t node = static_cast<std::uint32_t>(p);
                for (int l = 1; l < levels; ++l) {
                    node = h.level[static_cast<std::size_t>(l - 1)].parent[node];
                    sum += solved_[static_cast<std::size_t>(l)][node];
                }
                z[h.order[p]] = sum;
            }
        });
    }

    [[nodiscard]] std::size_t memory_bytes() const {
        std::size_t bytes = slot_row_.capacity() * sizeof(std::uint32_t);
        for (std::size_t l = 0; l < dense_.size(); ++l)
            bytes += dense_[l].capacity() * sizeof(T) + couplings_[l].capacity() * sizeof(M3) + failed_[l].capacity() +
                     (values_[l].capacity() + solved_[l].capacity()) * sizeof(V3);
        return bytes;
    }

private:
    /// Each coarse node of domain d's pieces gets the sum of its members' values `v` (the domain's
    /// kNodes), in node order; the domain's pieces are its own, so domains write disjoint nodes.
    /// The sum of the node being summed is kept in registers while its members come in a run (a
    /// domain is mostly one piece): the same additions in the same order as adding into `coarse`
    /// member by member, without a store and a reload between two of them.
    static void restrict_domain(const SchwarzLevel& level, std::size_t d, const V3* v, std::vector<V3>& coarse) {
        const std::uint32_t first = level.parent_start[d], last = level.parent_start[d + 1];
        for (std::uint32_t c = first; c < last; ++c) coarse[c] = V3{};
        const std::size_t begin = d * kNodes, end = std::min<std::size_t>(level.nodes, (d + 1) * kNodes);
        if (begin >= end) return;
        std::uint32_t node = level.parent[begin];
        V3 sum{};
        for (std::size_t k = begin; k < end; ++k) {
            if (level.parent[k] != node) {
                coarse[node] = sum;
                node = level.parent[k];
                sum = coarse[node];
            }
            sum += v[k - begin];
        }
        coarse[node] = sum;
    }

    /// Writes `m` as block `block` = (domain·kNodes + a)·kNodes + b of the dense matrices.
    static void put_block(T* dense, std::uint32_t block, const M3& m) {
        const std::size_t domain = block / (kNodes * kNodes);
        const std::uint32_t a = (block / kNodes) % kNodes, b = block % kNodes;
        T* D = dense + domain * kDim * kDim;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) D[(3 * a + r) * kDim + 3 * b + c] = m.m[r][c];
    }

    /// y = D⁻¹ v for one domain (kNodes vectors of 3), D⁻¹ column-major (transposed after the
    /// inverse). Column by column (cpu/dense_columns.h): every out[i] still sums its products in j
    /// order from zero, the bits of a row-by-row dot product, but the kDim sums run side by side
    /// (vectorised, no chain of dependent additions).
    static void solve_domain(const T* inverse, const V3* v, V3* y) {
        T in[kDim], out[kDim];
        for (std::uint32_t a = 0; a < kNodes; ++a)
            for (int c = 0; c < 3; ++c) in[3 * a + c] = v[a][c];
        dense_columns_times(inverse, in, out);
        for (std::uint32_t a = 0; a < kNodes; ++a) y[a] = V3{out[3 * a], out[3 * a + 1], out[3 * a + 2]};
    }

    const SchwarzHierarchy* h_ = nullptr;
    std::vector<std::uint32_t> slot_row_;        // pattern slot → its row
    std::vector<std::vector<M3>> couplings_;      // per level: the coupling blocks (level 0: per slot)
    std::vector<std::vector<std::uint8_t>> failed_;  // per level and domain: a pivot was replaced
    // Per level: domains × kDim², row-major: the matrix, then its inverse transposed. On cache lines:
    // a domain (kDim² scalars) is a whole number of them, so every row's 32-byte accesses stay in one.
    std::vector<std::vector<T, AlignedAllocator<T>>> dense_;
    std::vector<std::vector<V3>> values_;  // per level: the restricted residual per node
    std::vector<std::vector<V3>> solved_;  // per level: the domain solutions per node
    int pivot_failures_ = 0;
};

}  // namespace weft::cpu
