#pragma once
// The proximity contacts of one substep inside the CPU solve: P-Cloth's dynamic part of the matrix
// (A = A_fabric + A_contact) kept in factored form. A pair couples four vertices with the blocks
// w_i·w_j·C (pair_contact.h), so it stores one 3×3 C and four weights instead of 16 blocks, and
// A_contact·x is two passes: per pair s = C·Σ_j w_j x_j, then per vertex a gather Σ w_i s over the
// pairs touching it (a fixed incidence list in pair order: deterministic, no atomics; the GPU port
// uses the same two passes).

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "collision/buffer_trim.h"
#include "collision/proximity_contacts.h"
#include "cpu/bsr_matrix.h"
#include "deterministic_parallel.h"
#include "weft/physics/implicit_terms.h"
#include "weft/physics/offset_contact.h"
#include "weft/physics/pair_contact.h"
#include "weft/physics/proximity.h"

namespace weft::cpu {

template <typename T>
class ContactTerms {
public:
    using V3 = physics::Vec3<T>;
    using M3 = physics::Mat3<T>;

    /// Takes the substep's contacts. Vertex ids ≥ `cloth_vertices` are kinematic (collider meshes):
    /// they move as prescribed and are not unknowns of the solve. `offset`: each pair is an offset
    /// contact (weft/physics/offset_contact.h) whose closest points, weights and normal follow the
    /// primitives at every evaluation, with the contact's thickness as its radius; otherwise a pair
    /// spring along the contact's fixed normal.
    void set(std::span<const collision::ProximityContact> contacts, std::size_t cloth_vertices, bool offset = false) {
        n_ = cloth_vertices;
        offset_ = offset;
        const std::size_t m = contacts.size();
        ids_.resize(m);
        weight_.resize(m);
        normal_.resize(m);
        params_.resize(m);
        edge_edge_.resize(m);
        block_.resize(m);
        rhs_.resize(m);
        scratch_.resize(m);
        for (std::size_t p = 0; p < m; ++p) {
            const collision::ProximityContact& c = contacts[p];
            for (int i = 0; i < 4; ++i) {
                ids_[p][i] = c.vertex[i];
                weight_[p][i] = static_cast<T>(c.weight[i]);
            }
            normal_[p] = c.normal.template cast<T>();
            edge_edge_[p] = c.edge_edge ? 1 : 0;
            params_[p] = {static_cast<T>(c.stiffness), static_cast<T>(c.thickness), static_cast<T>(c.friction),
                          T(1e-3)};
        }
        active_.assign(m, 1);
        build_incidence();
        diagonal_.assign(n_, M3{});
        trim_after_flood(m);
    }

    [[nodiscard]] std::size_t size() const { return ids_.size(); }

    /// The cloth vertices (ids below the cloth vertex count) of every pair still in the solve, each
    /// once, ascending, into `out` (Backend::contact_vertices).
    void contact_vertices(std::vector<std::uint32_t>& out) const {
        out.clear();
        for (std::size_t p = 0; p < ids_.size(); ++p) {
            if (active_[p] == 0) continue;
            for (int i = 0; i < 4; ++i)
                if (ids_[p][i] < n_) out.push_back(static_cast<std::uint32_t>(ids_[p][i]));
        }
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    }

    /// Evaluates every spring at the Newton linearisation point: cloth vertex i at x0 + h·w_k
    /// moving with v_k (d = v_k − w_k is how far the iterate is from the linearisation), kinematic
    /// vertex j at its pose at t + h moving with its velocity. Fills the per-pair right-hand side
    /// h·F + h²·K·Σ w_j d_j and system block C = −h·D − h²·K (Baraff–Witkin's linearisation, as
    /// cpu_solver.cpp does for the analytic colliders), and the per-vertex diagonal Σ w_i²·C.
    void evaluate(T h, const std::vector<V3>& x0, const std::vector<V3>& wk, const std::vector<V3>& vk,
                  std::span<const V3> kinematic_x1, std::span<const V3> kinematic_v) {
        const physics::ImplicitStep<T> step{h, h * h};
        parallel_chunks(ids_.size(), [&](std::size_t lo, std::size_t hi) {
            for (std::size_t p = lo; p < hi; ++p) {
                if (offset_) {
                    evaluate_offset(step, p, x0, wk, vk, kinematic_x1, kinematic_v);
                    continue;
                }
                V3 g{}, u{}, d{};
                for (int i = 0; i < 4; ++i) {
                    const std::uint32_t v = ids_[p][i];
                    const T w = weight_[p][i];
                    if (v < n_) {
                        g += w * (x0[v] + h * wk[v]);
                        u += w * vk[v];
                        d += w * (vk[v] - wk[v]);
                    } else {
                        g += w * kinematic_x1[v - n_];
                        u += w * kinematic_v[v - n_];
                    }
                }
                const physics::PairContactForce<T> f = physics::pair_contact(normal_[p], g, u, params_[p]);
                physics::pair_contact_terms(step, f.force, f.dfdx, f.dfdv, d, rhs_[p], block_[p]);
            }
        });
        if (offset_) {
            // Offset contacts beyond their radius at this iterate add exactly zero (most of the pairs
            // the bounds select): leave them out of the incidence, as the GPU does, so the CG pays
            // only for the pairs in contact. The sums do not change.
            for (std::size_t p = 0; p < ids_.size(); ++p) {
                bool zero = rhs_[p] == V3{};
                for (int r = 0; r < 3 && zero; ++r)
                    for (int c = 0; c < 3 && zero; ++c) zero = block_[p].m[r][c] == T(0);
                active_[p] = zero ? 0 : 1;
            }
            build_incidence();
        }
        parallel_chunks(n_, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t i = lo; i < hi; ++i) {
                M3 acc{};
                for (std::uint32_t e = start_[i]; e < start_[i + 1]; ++e) {
                    const T w = entry_weight_[e];
                    acc += (w * w) * block_[entry_[e]];
                }
                diagonal_[i] = acc;
            }
        });
    }

    /// Offset contacts: their penalty energy with cloth vertex i at x[i] and kinematic vertex k at
    /// kinematic_x[k], J (the closest points taken there; 0 for pair springs).
    [[nodiscard]] double energy_at(const std::vector<V3>& x, std::span<const V3> kinematic_x) const {
        if (!offset_) return 0.0;
        double e = 0.0;
        for (std::size_t p = 0; p < ids_.size(); ++p) {
            V3 y[4];
            for (int i = 0; i < 4; ++i) y[i] = ids_[p][i] < n_ ? x[ids_[p][i]] : kinematic_x[ids_[p][i] - n_];
            const T d = physics::pair_closest_points(edge_edge_[p] != 0, y).distance;
            e += static_cast<double>(physics::offset_penalty(d, params_[p].stiffness, params_[p].thickness).energy);
        }
        return e;
    }

    /// b_i += Σ_pairs w_i·(pair right-hand side).
    void add_rhs(std::vector<V3>& b) const {
        parallel_chunks(n_, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t i = lo; i < hi; ++i)
                for (std::uint32_t e = start_[i]; e < start_[i + 1]; ++e)
                    b[i] += entry_weight_[e] * rhs_[entry_[e]];
        });
    }

    /// Σ_pairs w_i²·C: what the contacts add to the diagonal block of row i.
    [[nodiscard]] const M3& diagonal(std::size_t i) const { return diagonal_[i]; }

    /// y += A_contact·x over the cloth vertices (kinematic vertices are not unknowns: they add nothing).
    void multiply_add(const std::vector<V3>& x, std::vector<V3>& y) const {
        parallel_chunks(ids_.size(), [&](std::size_t lo, std::size_t hi) {
            for (std::size_t p = lo; p < hi; ++p) {
                if (active_[p] == 0) continue;  // not in the incidence: its product is never read
                V3 s{};
                for (int i = 0; i < 4; ++i)
                    if (ids_[p][i] < n_) s += weight_[p][i] * x[ids_[p][i]];
                scratch_[p] = block_[p] * s;
            }
        });
        parallel_chunks(n_, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t i = lo; i < hi; ++i)
                for (std::uint32_t e = start_[i]; e < start_[i + 1]; ++e)
                    y[i] += entry_weight_[e] * scratch_[entry_[e]];
        });
    }

    [[nodiscard]] std::size_t memory_bytes() const {
        return ids_.capacity() * sizeof(ids_[0]) + weight_.capacity() * sizeof(weight_[0]) +
               (normal_.capacity() + rhs_.capacity() + scratch_.capacity()) * sizeof(V3) +
               params_.capacity() * sizeof(params_[0]) + (block_.capacity() + diagonal_.capacity()) * sizeof(M3) +
               (start_.capacity() + entry_.capacity() + fill_.capacity()) * sizeof(std::uint32_t) +
               entry_weight_.capacity() * sizeof(T) + edge_edge_.capacity() +
               active_.capacity();
    }

private:
    // The trim window (collision/buffer_trim.h): lists that one frame's flood of contacts grew are
    // cut back once a whole window of calls needed far less.
    std::size_t sets_since_trim_ = 0, peak_pairs_ = 0, peak_entries_ = 0;
    void trim_after_flood(std::size_t pairs) {
        peak_pairs_ = std::max(peak_pairs_, pairs);
        peak_entries_ = std::max(peak_entries_, entry_.size());
        if (++sets_since_trim_ < collision::kTrimPeriod) return;
        (void)collision::trim_to_peak(ids_, peak_pairs_);
        (void)collision::trim_to_peak(weight_, peak_pairs_);
        (void)collision::trim_to_peak(normal_, peak_pairs_);
        (void)collision::trim_to_peak(params_, peak_pairs_);
        (void)collision::trim_to_peak(edge_edge_, peak_pairs_);
        (void)collision::trim_to_peak(active_, peak_pairs_);
        (void)collision::trim_to_peak(block_, peak_pairs_);
        (void)collision::trim_to_peak(rhs_, peak_pairs_);
        (void)collision::trim_to_peak(scratch_, peak_pairs_);
        (void)collision::trim_to_peak(entry_, peak_entries_);
        (void)collision::trim_to_peak(entry_weight_, peak_entries_);
        sets_since_trim_ = peak_pairs_ = peak_entries_ = 0;
    }

    /// Incidence of cloth vertices over the active pairs, counting sort in pair order.
    void build_incidence() {
        start_.assign(n_ + 1, 0);
        for (std::size_t p = 0; p < ids_.size(); ++p)
            if (active_[p] != 0)
                for (std::uint32_t v : ids_[p])
                    if (v < n_) ++start_[v + 1];
        for (std::size_t i = 0; i < n_; ++i) start_[i + 1] += start_[i];
        entry_.resize(start_[n_]);
        entry_weight_.resize(start_[n_]);
        fill_.assign(start_.begin(), start_.end() - 1);
        for (std::size_t p = 0; p < ids_.size(); ++p)
            if (active_[p] != 0)
                for (std::uint32_t i = 0; i < 4; ++i)
                    if (ids_[p][i] < n_) {
                        const std::uint32_t e = fill_[ids_[p][i]]++;
                        entry_[e] = static_cast<std::uint32_t>(p);
                        entry_weight_[e] = weight_[p][i];
                    }
    }

    /// One offset contact at the linearisation point: closest points of its two primitives there
    /// (vertex–face or edge–edge), hence this evaluation's weights, then the penalty of the distance.
    void evaluate_offset(const physics::ImplicitStep<T>& step, std::size_t p, const std::vector<V3>& x0,
                         const std::vector<V3>& wk, const std::vector<V3>& vk, std::span<const V3> kinematic_x1,
                         std::span<const V3> kinematic_v) {
        V3 x[4];
        for (int i = 0; i < 4; ++i) {
            const std::uint32_t v = ids_[p][i];
            x[i] = v < n_ ? x0[v] + step.h * wk[v] : kinematic_x1[v - n_];
        }
        const physics::PairClosestPoints<T> closest = physics::pair_closest_points(edge_edge_[p] != 0, x);
        std::array<T, 4>& w = weight_[p];
        for (int i = 0; i < 4; ++i) w[i] = closest.weight[i];
        const V3 fallback = closest.normal;
        V3 g{}, u{}, d{};
        for (int i = 0; i < 4; ++i) {
            const std::uint32_t v = ids_[p][i];
            g += w[i] * x[i];
            if (v < n_) {
                u += w[i] * vk[v];
                d += w[i] * (vk[v] - wk[v]);
            } else {
                u += w[i] * kinematic_v[v - n_];
            }
        }
        const physics::PairContactParams<T>& c = params_[p];
        const physics::OffsetContactForce<T> f = physics::offset_contact(
            g, u, fallback, physics::OffsetContactParams<T>{c.stiffness, c.thickness, c.friction, c.slip_velocity});
        physics::pair_contact_terms(step, f.force, f.dfdx, f.dfdv, d, rhs_[p], block_[p]);
    }

    std::size_t n_ = 0;
    bool offset_ = false;
    std::vector<std::uint8_t> edge_edge_;
    std::vector<std::uint8_t> active_;  // per pair: 0 when its terms are exactly zero at this iterate (offset)

    std::vector<std::array<std::uint32_t, 4>> ids_;
    std::vector<std::array<T, 4>> weight_;
    std::vector<V3> normal_;
    std::vector<physics::PairContactParams<T>> params_;
    std::vector<M3> block_;
    std::vector<V3> rhs_;
    mutable std::vector<V3> scratch_;  // per-pair C·Σ w_j x_j of the current product
    // The incidence: row i's entries [start_[i], start_[i+1]) name a pair and carry the row's weight
    // in it, in the order the rows read them (one random load a product term, not two).
    std::vector<std::uint32_t> start_, entry_, fill_;
    std::vector<T> entry_weight_;
    std::vector<M3> diagonal_;
};

/// The operator the CPU solve hands to PCG: the fabric's BSR matrix plus the contact springs.
template <typename T>
struct SystemOperator {
    const BsrMatrix<T>& fabric;
    const ContactTerms<T>* contacts;  // null or empty: the fabric alone
    void multiply(const std::vector<physics::Vec3<T>>& x, std::vector<physics::Vec3<T>>& y) const {
        fabric.multiply(x, y);
        if (contacts != nullptr && contacts->size() > 0) contacts->multiply_add(x, y);
    }
    /// y = filter(A x), returning xᵀy: one pass over the fabric's rows when there are no contacts.
    double multiply_dot(const std::vector<physics::Vec3<T>>& x, std::vector<physics::Vec3<T>>& y,
                        const std::vector<std::uint8_t>& fixed, std::vector<double>& partials) const {
        if (contacts == nullptr || contacts->size() == 0) return fabric.multiply_dot(x, y, fixed, partials);
        multiply(x, y);
        return deterministic_sum(y.size(), partials, [&](std::size_t b, std::size_t e) {
            double acc = 0.0;
            for (std::size_t i = b; i < e; ++i) {
                if (fixed[i]) y[i] = physics::Vec3<T>{};
                acc += static_cast<double>(physics::dot(x[i], y[i]));
            }
            return acc;
        });
    }
    [[nodiscard]] physics::Mat3<T> diagonal_block(std::size_t i) const {
        physics::Mat3<T> d = fabric.diagonal_block(i);
        if (contacts != nullptr && contacts->size() > 0) d += contacts->diagonal(i);
        return d;
    }
};

}  // namespace weft::cpu
