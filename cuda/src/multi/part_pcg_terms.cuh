#pragma once
// The per-row, per-pair and per-sum pieces of the CG across parts (multi/part_pcg.h), shared by its
// two loop forms: the batches of kernels (part_pcg.cu) and the one launch per GPU (part_pcg_loop.cu).
// Both call these with a block of kBlockSize threads on rows [kBlockSize·b, kBlockSize·(b+1)), so
// every partial sum is taken over the same rows in the same tree: the two forms give the same bits.

#include <cub/block/block_reduce.cuh>

#include "contact_terms.cuh"
#include "device_math.cuh"
#include "kernels.h"
#include "multi/part_pcg.h"
#include "multi/part_system.h"

namespace weft::cuda::multi {

/// What a reduction's scalar step does with the two sums.
enum ReductionMode : int {
    kStart = 0,       ///< (rᵀu, bᵀM⁻¹b) of the start: γ, γ_b and the first convergence test
    kFirstAlpha = 1,  ///< (−, wᵀu) of the first product: α = γ/δ
    kIteration = 2,   ///< (γ', δ) of an iteration: the test, then β and α
};

using PartReduce = cub::BlockReduce<double, kBlockSize>;

/// The block's sum of `value` (CUB's fixed tree order: deterministic), into partials[2·row_block + k]
/// by thread 0. Every thread of the block calls it; `storage` is free again when it returns.
__device__ inline void part_block_partial(double value, double* partials, unsigned row_block, int k,
                                          PartReduce::TempStorage& storage) {
    const double sum = PartReduce(storage).Sum(value);
    if (threadIdx.x == 0) partials[2 * row_block + k] = sum;
    __syncthreads();
}

/// The part's two sums of its `blocks` row-block partials, in a fixed order (thread t adds blocks
/// t, t + kBlockSize, …; then CUB's tree), valid in thread 0. Every thread of the block calls it.
__device__ inline void part_sum_partials(const double* partials, unsigned blocks, double sums[2],
                                         PartReduce::TempStorage& storage) {
    for (int k = 0; k < 2; ++k) {
        double acc = 0.0;
        for (unsigned b = threadIdx.x; b < blocks; b += blockDim.x) acc += __ldcg(&partials[2 * b + k]);
        sums[k] = PartReduce(storage).Sum(acc);
        __syncthreads();  // storage is reused
    }
}

/// Every part the same: the G pairs of sums added in part order, then the loop's decision.
__device__ inline void part_advance_scalars(const double* gathered, unsigned parts, PartPcgScalars& s, int mode) {
    double first = 0.0, second = 0.0;
    for (unsigned p = 0; p < parts; ++p) {
        first += __ldcg(&gathered[2 * p]);
        second += __ldcg(&gathered[2 * p + 1]);
    }
    if (mode == kStart) {
        // As the single-GPU start (pcg_control.cuh, start_solve): measured against the larger of
        // bᵀM⁻¹b and the start's own residual.
        s.gamma = first;
        s.energy.reset();
        s.reference = fmax(second, first);
        s.relative = s.reference > 0.0 ? sqrt(fmax(first, 0.0) / s.reference) : 0.0;
        s.converged = !(s.reference > 0.0) || first <= s.tolerance2 * s.reference ? 1 : 0;
        s.running = s.converged || s.max_iterations <= 0 ? 0 : 1;
        return;
    }
    if (mode == kFirstAlpha) {
        if (s.running == 0) return;
        if (!(second > 0.0)) {
            s.running = 0;
            return;
        }
        s.alpha = s.gamma / second;
        s.beta = 0.0;
        return;
    }
    s.energy.record(s.alpha, s.gamma);  // Φ fell by ½·α·γ in the iteration that gave γ' = `first`
    ++s.iterations;
    s.relative = sqrt(fmax(first, 0.0) / s.reference);
    s.converged = first <= s.tolerance2 * s.reference ? 1 : 0;
    if (s.converged != 0 && !s.energy.still_falling(s.energy_floor)) {
        s.running = 0;
        return;
    }
    const double beta = first / s.gamma;
    const double denominator = second - beta * first / s.alpha;
    if (s.iterations >= s.max_iterations || !(denominator > 0.0)) {  // the cap, or not SPD in float
        s.running = 0;
        return;
    }
    s.beta = beta;
    s.alpha = first / denominator;
    s.gamma = first;
}

/// Entry e of row i's preconditioner block at [e·local + i] (the single-GPU solver's layout).
__device__ inline M3 part_load_precond(const float* precond, std::uint32_t i, std::uint32_t local) {
    M3 m;
    for (int e = 0; e < 9; ++e) m.m[e / 3][e % 3] = precond[e * local + i];
    return m;
}

__device__ inline bool part_is_fixed(const PartSystem& a, std::uint32_t i) { return a.fixed != nullptr && a.fixed[i] != 0; }

/// Owned row i of the update p ← u + βp, s ← w + βs, x ← x + αp, r ← r − αs and (`jacobi`)
/// u ← M⁻¹r; returns rᵀu (0 without `jacobi`: the Schwarz apply computes u and the sum).
/// The first half of part_update_row: p, s, x and r of owned row i; returns the new r_i.
__device__ inline V3 part_update_directions_row(std::uint32_t local, std::uint32_t i, float alpha, float beta, float* x,
                                                float* r, const float* u, const float* w, float* p, float* s) {
    const V3 pi = load3(u, i, local) + beta * load3(p, i, local);
    const V3 si = load3(w, i, local) + beta * load3(s, i, local);
    store3(p, i, local, pi);
    store3(s, i, local, si);
    store3(x, i, local, load3(x, i, local) + alpha * pi);
    const V3 ri = load3(r, i, local) - alpha * si;
    store3(r, i, local, ri);
    return ri;
}

__device__ inline double part_update_row(const PartSystem& a, std::uint32_t i, const float* precond, bool jacobi, float alpha,
                                         float beta, float* x, float* r, float* u, const float* w, float* p, float* s) {
    const std::uint32_t local = a.local;
    const V3 ri = part_update_directions_row(local, i, alpha, beta, x, r, u, w, p, s);
    if (!jacobi) return 0.0;
    const V3 ui = part_load_precond(precond, i, local) * ri;
    store3(u, i, local, ui);
    return static_cast<double>(physics::dot(ri, ui));
}

/// Owned row i of filter(A·x): its blocks in the order of the single-GPU SpMV (pcg_kernels.cu), then
/// the row's contact sum as the single-GPU SpMV adds it (the pair pass and contact_row_sums before).
__device__ inline V3 part_product_row(const PartSystem& a, std::uint32_t i, const float* x) {
    V3 acc{};
    if (part_is_fixed(a, i)) return acc;
    const std::uint32_t slice = i / kSliceRowsDevice;
    const std::uint32_t first = a.slice_start[slice], width = (a.slice_start[slice + 1] - first) / kSliceRowsDevice;
    for (std::uint32_t k = 0; k < width; ++k) {
        const std::uint32_t pos = first + k * kSliceRowsDevice + i % kSliceRowsDevice;
        acc += load_block(a.blocks, pos) * load3(x, a.column[pos], a.local);
    }
    if (a.contacts.capacity > 0 && contact_count(a.contacts) > 0) acc += load3(a.contacts.row_sum, i, a.contacts.vertices);
    return acc;
}

/// Pair p of the contact product's pair pass over a part's contacts: a vertex the part owns is read
/// from its own vector `x` (stride `local`), another part's from the whole-size copy its owner pushed
/// (multi/contact_mirror.h), as ContactView::corner_source says. The same values as one GPU's pass
/// reads, in the same order: contact_pair_product's sum.
__device__ inline void part_pair_product(const ContactView& c, std::uint32_t p, const float* x, std::uint32_t local,
                                         const float* copy) {
    if (!contact_active(c, p)) return;  // not in the incidence
    const std::uint32_t whole = c.cloth_vertices;
    const uint4 from = c.corner_source[p];
    const float4 w = reinterpret_cast<const float4*>(c.list)[4 * p + 1];
    const std::uint32_t source[4] = {from.x, from.y, from.z, from.w};
    const float weight[4] = {w.x, w.y, w.z, w.w};
    V3 sum{};
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t k = source[j];
        if (k == kCornerNone) continue;  // a kinematic vertex: no unknown
        sum += weight[j] * ((k & kCornerFromCopy) == 0 ? load3(x, k, local) : load3(copy, k & ~kCornerFromCopy, whole));
    }
    store_pair_vector(c.product, p, load_contact_block(c, p) * sum);
}

}  // namespace weft::cuda::multi
