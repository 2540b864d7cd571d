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

/// First pass of A_contact·x for pair p: s_p = C_p·Σ_j w_j x_j over its cloth corners (kinematic
/// vertices are not unknowns of the solve: they add nothing).
__device__ inline void contact_pair_product(const ContactView& c, std::uint32_t p, const float* x, std::uint32_t n) {
    if ((c.list[p].pair & kInactiveContactBit) != 0) return;  // not in the incidence: its product is never read
    const uint4 ids = reinterpret_cast<const uint4*>(c.list)[4 * p];
    const float4 w = reinterpret_cast<const float4*>(c.list)[4 * p + 1];
    V3 s{};
    if (ids.x < n) s += w.x * load3(x, ids.x, n);
    if (ids.y < n) s += w.y * load3(x, ids.y, n);
    if (ids.z < n) s += w.z * load3(x, ids.z, n);
    if (ids.w < n) s += w.w * load3(x, ids.w, n);
    store3(c.product, p, c.capacity, load_contact_block(c, p) * s);
}

/// The weight of incidence entry 4·pair + corner.
__device__ inline float contact_weight(const ContactView& c, std::uint32_t entry) {
    return c.list[entry >> 2].weight[entry & 3u];
}

/// acc + Σ w_i·(per-pair vector) over vertex i's incidence, added one entry at a time in pair order
/// (as the CPU's add_rhs and multiply_add do).
__device__ inline V3 contact_gather(const ContactView& c, std::uint32_t i, const float* per_pair, V3 acc) {
    const std::uint32_t last = c.start[i + 1];
    for (std::uint32_t e = c.start[i]; e < last; ++e) {
        const std::uint32_t entry = c.entries[e];
        acc += contact_weight(c, entry) * load3(per_pair, entry >> 2, c.capacity);
    }
    return acc;
}

}  // namespace weft::cuda
