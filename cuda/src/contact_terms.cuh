#pragma once
// The proximity contacts' share of A and b on the device, in the factored form of the CPU
// (runtime/src/cpu/contact_terms.h): pair p couples its four vertices with the blocks w_i·w_j·C_p, so
// A_contact·x is a pass per pair, s_p = C_p·Σ_j w_j x_j, and a gather per vertex, Σ w_i·s_p over its
// incidence list in pair order: a fixed order, no atomics, the CPU's sums term for term. Shared by
// contact_kernels.cu (the pair passes) and pcg_kernels.cu (the gathers, fused into its row kernels).

#include "device_math.cuh"

namespace weft::cuda {

/// Pairs in use this substep (a list that overflowed its capacity is cut at the capacity).
__device__ inline std::uint32_t contact_count(const ContactView& c) {
    const std::uint32_t m = *c.count;
    return m < c.capacity ? m : c.capacity;
}

__device__ inline M3 load_contact_block(const ContactView& c, std::uint32_t p) {
    M3 m;
    for (int e = 0; e < 9; ++e) m.m[e / 3][e % 3] = c.block[e * c.capacity + p];
    return m;
}

/// A per-pair vector of the product (ContactView::product): one 16-byte load or store, so that the
/// gathers, which read the pairs in the rows' order (random), touch one memory sector an entry, not 3.
__device__ inline V3 load_pair_vector(const float4* v, std::uint32_t p) {
    const float4 t = v[p];
    return {t.x, t.y, t.z};
}
__device__ inline void store_pair_vector(float4* v, std::uint32_t p, V3 value) { v[p] = float4{value.x, value.y, value.z, 0.0f}; }

/// Pair p is in the solve this Newton iteration (ContactView::active_mask, one word for 32 pairs).
__device__ inline bool contact_active(const ContactView& c, std::uint32_t p) {
    return ((c.active_mask[p / 32] >> (p % 32)) & 1U) != 0;
}

/// First pass of A_contact·x for pair p: s_p = C_p·Σ_j w_j x_j over its cloth corners (kinematic
/// vertices are not unknowns of the solve: they add nothing).
__device__ inline void contact_pair_product(const ContactView& c, std::uint32_t p, const float* x, std::uint32_t n) {
    if (!contact_active(c, p)) return;  // not in the incidence: its product is never read
    const uint4 ids = reinterpret_cast<const uint4*>(c.list)[4 * p];
    const float4 w = reinterpret_cast<const float4*>(c.list)[4 * p + 1];
    V3 s{};
    if (ids.x < n) s += w.x * load3(x, ids.x, n);
    if (ids.y < n) s += w.y * load3(x, ids.y, n);
    if (ids.z < n) s += w.z * load3(x, ids.z, n);
    if (ids.w < n) s += w.w * load3(x, ids.w, n);
    store_pair_vector(c.product, p, load_contact_block(c, p) * s);
}

/// The weight of incidence entry 4·pair + corner, from the list (ContactView::entry_weight holds it
/// in the incidence's order once the incidence is built).
__device__ inline float contact_weight(const ContactView& c, std::uint32_t entry) {
    return c.list[entry >> 2].weight[entry & 3u];
}

/// acc + Σ w_i·product over vertex i's incidence, added one entry at a time in pair order
/// (as the CPU's add_rhs and multiply_add do). A vertex of a wound or stacked sheet is in hundreds of
/// pairs, and its thread's chain of loads is what a grid-wide step waits for: the loads of a batch
/// of entries are issued before its additions, which still run one at a time in order (the same
/// sums, bit for bit).
__device__ inline V3 contact_gather(const ContactView& c, std::uint32_t i, V3 acc) {
    constexpr std::uint32_t kBatch = 8;
    std::uint32_t e = c.start[i];
    const std::uint32_t last = c.start[i + 1];
    for (; e + kBatch <= last; e += kBatch) {
        float weight[kBatch];
        V3 value[kBatch];
#pragma unroll
        for (std::uint32_t k = 0; k < kBatch; ++k) {
            weight[k] = c.entry_weight[e + k];
            value[k] = load_pair_vector(c.product, c.entries[e + k] >> 2);
        }
#pragma unroll
        for (std::uint32_t k = 0; k < kBatch; ++k) acc += weight[k] * value[k];
    }
    for (; e < last; ++e) acc += c.entry_weight[e] * load_pair_vector(c.product, c.entries[e] >> 2);
    return acc;
}

/// contact_gather for the rows of a whole warp (every lane calls it, converged; `active`: the lane has
/// a row i to gather). A vertex of a wound or stacked sheet is in hundreds of pairs, and a thread's
/// serial chain over such a row is what a grid-wide step waits for: a row longer than kLongRow
/// entries is summed by the whole warp (lane k adds entries k, k + 32, … in order, then a fixed
/// shuffle tree), and its owner adds that sum to acc. The order depends on the row lengths only: the
/// same bits on every run, and the CPU's sums up to float rounding (the short rows term for term).
__device__ inline V3 contact_gather_warp(const ContactView& c, bool active, std::uint32_t i, V3 acc) {
    constexpr std::uint32_t kLongRow = 32;
    constexpr unsigned kWarp = 0xffffffffu;
    const std::uint32_t lane = threadIdx.x % 32;
    std::uint32_t first = 0, last = 0;
    if (active) {
        first = c.start[i];
        last = c.start[i + 1];
    }
    const bool long_row = last - first > kLongRow;
    if (active && !long_row) acc = contact_gather(c, i, acc);
    for (unsigned pending = __ballot_sync(kWarp, long_row); pending != 0; pending &= pending - 1) {
        const int owner = __ffs(pending) - 1;
        const std::uint32_t begin = __shfl_sync(kWarp, first, owner), end = __shfl_sync(kWarp, last, owner);
        V3 part{};
        constexpr std::uint32_t kBatch = 4;  // each lane's loads of a batch go out together
        std::uint32_t e = begin + lane;
        for (; e + 32 * (kBatch - 1) < end; e += 32 * kBatch) {
            float weight[kBatch];
            V3 value[kBatch];
#pragma unroll
            for (std::uint32_t k = 0; k < kBatch; ++k) {
                weight[k] = c.entry_weight[e + 32 * k];
                value[k] = load_pair_vector(c.product, c.entries[e + 32 * k] >> 2);
            }
#pragma unroll
            for (std::uint32_t k = 0; k < kBatch; ++k) part += weight[k] * value[k];
        }
        for (; e < end; e += 32) part += c.entry_weight[e] * load_pair_vector(c.product, c.entries[e] >> 2);
        for (int offset = 16; offset > 0; offset /= 2) {
            part.x += __shfl_down_sync(kWarp, part.x, offset);
            part.y += __shfl_down_sync(kWarp, part.y, offset);
            part.z += __shfl_down_sync(kWarp, part.z, offset);
        }
        const V3 total{__shfl_sync(kWarp, part.x, 0), __shfl_sync(kWarp, part.y, 0), __shfl_sync(kWarp, part.z, 0)};
        if (static_cast<int>(lane) == owner) acc += total;
    }
    return acc;
}

/// The gather half of A_contact·x as a pass of its own: row_sum[i] = Σ w·per_pair over row i's
/// incidence, for rows [0, rows), by warp `warp` of `warps` (every lane of a warp calls it). The
/// contacts of a wound or stacked sheet crowd into runs of neighbouring rows; walking the rows in
/// their own order would hand a whole run to one warp while the others idle at the next grid-wide
/// step. So the rows are dealt out spread: lane l takes the l-th stripe of ⌈rows/32⌉ rows, warp w
/// its rows w, w + warps, … of the stripe, and a run of neighbouring rows lands one row to a warp
/// (long rows summed by the whole warp: contact_gather_warp). The product adds row_sum after the
/// row's matrix blocks. Fixed by the row lengths alone: the same bits on every run.
__device__ inline void contact_row_sums(const ContactView& c, std::uint32_t rows, std::uint32_t warp, std::uint32_t warps) {
    const std::uint32_t lane = threadIdx.x % 32;
    const std::uint32_t stripe = (rows + 31) / 32;
    for (std::uint32_t k = warp; k < stripe; k += warps) {  // the same count for every lane of the warp
        const std::uint32_t i = lane * stripe + k;
        const bool active = i < rows;
        const V3 sum = contact_gather_warp(c, active, i, V3{});
        if (active) store3(c.row_sum, i, c.vertices, sum);
    }
}

}  // namespace weft::cuda
