// Proximity contacts in the implicit solve on the device: the per-substep incidence build, the
// per-Newton-iteration evaluation of every pair spring, and the per-pair pass of the contact SpMV.
// The CPU reference is runtime/src/cpu/contact_terms.h; the gathers that complete each step live in
// the PCG kernels (contact_terms.cuh), fused into the row passes that already read the row.
//
// The pair count is read from device memory by every kernel (launches are sized by the capacity), so
// the narrow phase can change it from one substep to the next under one CUDA graph.
#include <cub/device/device_radix_sort.cuh>

#include <algorithm>
#include <cstddef>

#include "contact_terms.cuh"
#include "cuda_check.h"
#include "weft/physics/implicit_terms.h"
#include "weft/physics/offset_contact.h"
#include "weft/physics/pair_contact.h"
#include "weft/physics/proximity.h"

namespace weft::cuda {
namespace {

/// Pair kernels stride over the pairs with at most this many blocks: enough threads to keep the
/// memory system busy on any count, and an empty list costs one short launch however large the
/// capacity has grown (the per-CG-iteration pass runs whether or not the substep has contacts).
constexpr unsigned kMaxPairBlocks = 1024;

unsigned pair_grid(std::uint64_t items) {
    const auto blocks = static_cast<unsigned>((items + kBlockSize - 1) / kBlockSize);
    return blocks < kMaxPairBlocks ? blocks : kMaxPairBlocks;
}

__device__ inline std::uint32_t first_thread() { return blockIdx.x * blockDim.x + threadIdx.x; }
__device__ inline std::uint32_t thread_stride() { return gridDim.x * blockDim.x; }

// ---- incidence: a stable radix sort of the corners (4·pair + corner) by their vertex's row ------------

/// The solver row of a pair's vertex v: v itself on one GPU, the part's row (or ~0) in part mode.
__device__ inline std::uint32_t contact_row(const ContactView& c, std::uint32_t v) {
    if (c.row_of == nullptr) return v;
    return v < c.cloth_vertices ? c.row_of[v] : 0xFFFFFFFFu;
}

/// Key and id of every corner slot of the arrays: the row of a corner in use (active, at a row of
/// this solver), else n, which sorts after every row. Also reports the substep's pair count.
__global__ void contact_keys_kernel(DeviceView d, std::uint32_t* keys, std::uint32_t* ids, std::uint32_t corner_slots) {
    const ContactView& c = d.contacts;
    const std::uint32_t m = contact_count(c);
    if (first_thread() == 0) d.stats->proximity_contacts = static_cast<int>(m);
    for (std::uint32_t e = first_thread(); e < corner_slots; e += thread_stride()) {
        std::uint32_t key = d.n;
        if (e < 4 * m) {
            const DeviceContact& pair = c.list[e >> 2];
            const std::uint32_t v = contact_row(c, pair.vertex[e & 3u]);
            if (v < d.n && (pair.pair & kInactiveContactBit) == 0) key = v;
        }
        keys[e] = key;
        ids[e] = e;
    }
}

/// start[i] = the first sorted slot whose row is at least i (a binary search): row i's entries are
/// [start[i], start[i + 1]), and start[n] counts the corners in use.
__global__ void contact_starts_kernel(DeviceView d, const std::uint32_t* sorted_keys, std::uint32_t corner_slots) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i > d.n) return;
    std::uint32_t lo = 0, hi = corner_slots;
    while (lo < hi) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        if (sorted_keys[mid] < i)
            lo = mid + 1;
        else
            hi = mid;
    }
    d.contacts.start[i] = lo;
}

/// entry_weight[e] = the weight of sorted entry e (the rows' entries, [0, start[n])).
__global__ void contact_entry_weights_kernel(DeviceView d) {
    const ContactView& c = d.contacts;
    const std::uint32_t used = c.start[d.n];
    for (std::uint32_t e = first_thread(); e < used; e += thread_stride()) c.entry_weight[e] = contact_weight(c, c.entries[e]);
}

// ---- per Newton iteration -------------------------------------------------------------------------

/// Pair p at the linearisation point, as the CPU's ContactTerms::evaluate: cloth vertex j at
/// x0 + h·w_k moving with v_k (d = v_k − w_k: how far the iterate is from the linearisation),
/// kinematic vertex k at its pose at t + h moving with its velocity. Writes the right-hand side
/// h·F + h²·K·Σ w_j d_j and the block C = −h·D − h²·K (Baraff–Witkin's linearisation).
__device__ inline void evaluate_pair(const DeviceView& d, std::uint32_t p) {
    const ContactView& c = d.contacts;
    const float h = step_params(d).h;
    const physics::ImplicitStep<float> step{h, h * h};  // h² as the CPU forms it in float (not the staged square)
    const DeviceContact& pair = c.list[p];
    const uint4 ids = reinterpret_cast<const uint4*>(c.list)[4 * p];
    const float4 w4 = reinterpret_cast<const float4*>(c.list)[4 * p + 1];
    const std::uint32_t id[4] = {ids.x, ids.y, ids.z, ids.w};
    const float w[4] = {w4.x, w4.y, w4.z, w4.w};
    V3 g{}, u{}, dvw{};
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = id[j];
        if (v < d.n) {
            const V3 wk = load3(d.wk, v, d.n), vk = load3(d.vk, v, d.n);
            g += w[j] * (load3(d.x0, v, d.n) + h * wk);
            u += w[j] * vk;
            dvw += w[j] * (vk - wk);
        } else {
            const std::uint32_t k = v - d.n;
            g += w[j] * load3(c.kinematic_x1, k, c.kinematic_capacity);
            u += w[j] * load3(c.kinematic_v, k, c.kinematic_capacity);
        }
    }
    const V3 normal{pair.normal[0], pair.normal[1], pair.normal[2]};
    const physics::PairContactParams<float> params{pair.stiffness, pair.thickness, pair.friction, 1e-3f};
    const physics::PairContactForce<float> f = physics::pair_contact(normal, g, u, params);
    V3 rhs;
    M3 C;
    physics::pair_contact_terms(step, f.force, f.dfdx, f.dfdv, dvw, rhs, C);
    store3(c.rhs, p, c.capacity, rhs);
    for (int e = 0; e < 9; ++e) c.block[e * c.capacity + p] = C.m[e / 3][e % 3];
}

/// An offset contact at the linearisation point, as the CPU's ContactTerms::evaluate_offset: the
/// closest points of its two primitives there give this evaluation's weights (written back into the
/// list, which the SpMV and the gathers read), then the penalty of the distance.
__device__ inline void evaluate_offset_pair(const DeviceView& d, std::uint32_t p) {
    const ContactView& c = d.contacts;
    const float h = step_params(d).h;
    const physics::ImplicitStep<float> step{h, h * h};
    DeviceContact& pair = c.list[p];
    const uint4 ids = reinterpret_cast<const uint4*>(c.list)[4 * p];
    const std::uint32_t id[4] = {ids.x, ids.y, ids.z, ids.w};
    V3 x[4];
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = id[j];
        x[j] = v < d.n ? load3(d.x0, v, d.n) + h * load3(d.wk, v, d.n)
                       : load3(c.kinematic_x1, v - d.n, c.kinematic_capacity);
    }
    float w[4];
    V3 fallback;
    if ((pair.pair & kEdgeEdgeContactBit) != 0) {
        const auto q = physics::edge_edge_proximity(x[0], x[1], x[2], x[3]);
        w[0] = 1.0f - q.u;
        w[1] = q.u;
        w[2] = -(1.0f - q.v);
        w[3] = -q.v;
        fallback = q.normal;
    } else {
        const auto q = physics::point_triangle_proximity(x[0], x[1], x[2], x[3]);
        w[0] = 1.0f;
        w[1] = -(1.0f - q.u - q.v);
        w[2] = -q.u;
        w[3] = -q.v;
        fallback = q.normal;
    }
    reinterpret_cast<float4*>(c.list)[4 * p + 1] = float4{w[0], w[1], w[2], w[3]};
    V3 g{}, u{}, dvw{};
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = id[j];
        g += w[j] * x[j];
        if (v < d.n) {
            const V3 wk = load3(d.wk, v, d.n), vk = load3(d.vk, v, d.n);
            u += w[j] * vk;
            dvw += w[j] * (vk - wk);
        } else {
            u += w[j] * load3(c.kinematic_v, v - d.n, c.kinematic_capacity);
        }
    }
    const physics::OffsetContactForce<float> f = physics::offset_contact(
        g, u, fallback, physics::OffsetContactParams<float>{pair.stiffness, pair.thickness, pair.friction, 1e-3f});
    V3 rhs;
    M3 C;
    physics::pair_contact_terms(step, f.force, f.dfdx, f.dfdv, dvw, rhs, C);
    store3(c.rhs, p, c.capacity, rhs);
    bool zero = rhs.x == 0.0f && rhs.y == 0.0f && rhs.z == 0.0f;
    for (int e = 0; e < 9; ++e) {
        c.block[e * c.capacity + p] = C.m[e / 3][e % 3];
        zero = zero && C.m[e / 3][e % 3] == 0.0f;
    }
    // Exactly zero terms add exactly nothing to any sum: leaving the pair out changes no result.
    pair.pair = zero ? (pair.pair | kInactiveContactBit) : (pair.pair & ~kInactiveContactBit);
}

__global__ void contact_evaluate_kernel(DeviceView d) {
    const std::uint32_t m = contact_count(d.contacts);
    const std::uint32_t lane = threadIdx.x % 32;
    // A warp takes 32 consecutive pairs at a time (the block size is a multiple of 32), every lane
    // the same number of times, so that it can write their word of the active mask with one ballot.
    for (std::uint32_t base = first_thread() - lane; base < m; base += thread_stride()) {
        const std::uint32_t p = base + lane;
        bool active = false;
        if (p < m) {
            if ((d.contacts.list[p].pair & kOffsetContactBit) != 0)
                evaluate_offset_pair(d, p);
            else
                evaluate_pair(d, p);
            active = (d.contacts.list[p].pair & kInactiveContactBit) == 0;
        }
        const unsigned bits = __ballot_sync(0xffffffffu, active);
        if (lane == 0) d.contacts.active_mask[base / 32] = bits;
    }
}

/// s_p = C_p·Σ_j w_j x_j for every pair (the gather is fused into the PCG row kernels).
__global__ void contact_product_kernel(DeviceView d, const float* x, int in_cg_loop) {
    if (in_cg_loop && !d.control->running) return;
    const std::uint32_t m = contact_count(d.contacts);
    for (std::uint32_t p = first_thread(); p < m; p += thread_stride()) contact_pair_product(d.contacts, p, x, d.n);
}

/// contact_row_sums over the grid's warps; `running`: nothing once the CG loop has stopped.
__global__ void contact_row_sum_kernel(ContactView c, std::uint32_t rows, const int* running) {
    if (running != nullptr && *running == 0) return;
    if (contact_count(c) == 0) return;
    contact_row_sums(c, rows, first_thread() / 32, thread_stride() / 32);
}

}  // namespace

void launch_contact_row_sums(const ContactView& c, std::uint32_t rows, const int* running, cudaStream_t stream) {
    const unsigned warps = (rows + 31) / 32;
    contact_row_sum_kernel<<<std::max(1u, std::min(kMaxPairBlocks, blocks_for(warps, kBlockSize / 32))), kBlockSize, 0, stream>>>(
        c, rows, running);
    WEFT_CUDA_CHECK_LAUNCH("contact_row_sum_kernel");
}

std::size_t contact_sort_storage_bytes(std::uint32_t corner_slots, int key_bits) {
    std::size_t bytes = 0;
    cub::DoubleBuffer<std::uint32_t> keys(nullptr, nullptr), ids(nullptr, nullptr);
    WEFT_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, bytes, keys, ids, corner_slots, 0, key_bits));
    return bytes;
}

void launch_contact_incidence(const DeviceView& d, const ContactSortScratch& scratch, cudaStream_t stream) {
    // Why a radix sort: a vertex of a wound or stacked sheet is in hundreds of pairs, and sorting each
    // vertex's entries on its own thread (an insertion sort after an atomic scatter) cost 12 ms a
    // substep on the wound 200K twist. The sort is stable, so each row's entries come out in
    // ascending 4·pair + corner: the pair order of the CPU's ContactTerms, whatever order the narrow
    // phase wrote the pairs in.
    const ContactView& c = d.contacts;
    const std::uint32_t slots = scratch.corner_slots;
    contact_keys_kernel<<<pair_grid(slots), kBlockSize, 0, stream>>>(d, scratch.keys[0], scratch.ids, slots);
    WEFT_CUDA_CHECK_LAUNCH("contact_keys_kernel");
    cub::DoubleBuffer<std::uint32_t> keys(scratch.keys[0], scratch.keys[1]), ids(scratch.ids, c.entries);
    std::size_t bytes = scratch.storage_bytes;
    WEFT_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(scratch.storage, bytes, keys, ids, slots, 0, scratch.key_bits, stream));
    // The passes alternate between the buffers: an even count leaves the ids in the scratch.
    if (ids.Current() != c.entries)
        WEFT_CUDA_CHECK(cudaMemcpyAsync(c.entries, ids.Current(), std::size_t{slots} * sizeof(std::uint32_t),
                                        cudaMemcpyDeviceToDevice, stream));
    contact_starts_kernel<<<grid_for(d.n + 1), kBlockSize, 0, stream>>>(d, keys.Current(), slots);
    WEFT_CUDA_CHECK_LAUNCH("contact_starts_kernel");
    contact_entry_weights_kernel<<<pair_grid(slots), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("contact_entry_weights_kernel");
}

void launch_contact_evaluate(const DeviceView& d, cudaStream_t stream) {
    contact_evaluate_kernel<<<pair_grid(d.contacts.capacity), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("contact_evaluate_kernel");
}

void launch_contact_product(const DeviceView& d, const float* x, bool in_cg_loop, cudaStream_t stream) {
    contact_product_kernel<<<pair_grid(d.contacts.capacity), kBlockSize, 0, stream>>>(d, x, in_cg_loop ? 1 : 0);
    WEFT_CUDA_CHECK_LAUNCH("contact_product_kernel");
    // The CG's products read each row's contact sum from the spread pass (contact_row_sums).
    if (in_cg_loop)
        launch_contact_row_sums(d.contacts, d.n, reinterpret_cast<const int*>(reinterpret_cast<const char*>(d.control) +
                                                                               offsetof(PcgControl, running)),
                                stream);
}

}  // namespace weft::cuda
