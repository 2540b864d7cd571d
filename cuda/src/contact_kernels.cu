// Proximity contacts in the implicit solve on the device: the per-substep incidence build, the
// per-Newton-iteration evaluation of every pair spring, and the per-pair pass of the contact SpMV.
// The CPU reference is runtime/src/cpu/contact_terms.h; the gathers that complete each step live in
// the PCG kernels (contact_terms.cuh), fused into the row passes that already read the row.
//
// The pair count is read from device memory by every kernel (launches are sized by the capacity), so
// the narrow phase can change it from one substep to the next under one CUDA graph.
#include <cub/device/device_scan.cuh>

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

// ---- incidence: a counting sort of (vertex, 4·pair + corner) by vertex, stable ------------------------

/// The solver row of a pair's vertex v: v itself on one GPU, the part's row (or ~0) in part mode.
__device__ inline std::uint32_t contact_row(const ContactView& c, std::uint32_t v) {
    if (c.row_of == nullptr) return v;
    return v < c.cloth_vertices ? c.row_of[v] : 0xFFFFFFFFu;
}

/// Histogram of the cloth corners (integer atomics: the counts do not depend on the order). Also
/// reports the substep's pair count in the stats.
__global__ void contact_count_kernel(DeviceView d) {
    const ContactView& c = d.contacts;
    const std::uint32_t m = contact_count(c);
    if (first_thread() == 0) d.stats->proximity_contacts = static_cast<int>(m);
    for (std::uint32_t e = first_thread(); e < 4 * m; e += thread_stride()) {
        const DeviceContact& pair = c.list[e >> 2];
        const std::uint32_t v = contact_row(c, pair.vertex[e & 3u]);
        if (v < d.n && (pair.pair & kInactiveContactBit) == 0) atomicAdd(&c.fill[v], 1u);
    }
}

/// Each corner takes a slot in its vertex's range, counting `fill` back down to zero (so the next
/// substep's histogram starts from zeros without a memset). The order within a range is the order
/// the atomics ran in; contact_order_kernel makes it the pair order.
__global__ void contact_scatter_kernel(DeviceView d) {
    const ContactView& c = d.contacts;
    const std::uint32_t corners = 4 * contact_count(c);
    for (std::uint32_t e = first_thread(); e < corners; e += thread_stride()) {
        const DeviceContact& pair = c.list[e >> 2];
        const std::uint32_t v = contact_row(c, pair.vertex[e & 3u]);
        if (v >= d.n || (pair.pair & kInactiveContactBit) != 0) continue;
        const std::uint32_t slot = c.start[v] + atomicSub(&c.fill[v], 1u) - 1u;
        c.entries[slot] = e;
    }
}

/// Sorts each vertex's entries (the pairs one vertex is in: a few, tens where sheets lie stacked) by
/// insertion: entries are 4·pair + corner, so ascending is pair order, the CPU's order, whatever
/// order the scatter ran in.
__global__ void contact_order_kernel(DeviceView d) {
    const ContactView& c = d.contacts;
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= d.n || contact_count(c) == 0) return;
    const std::uint32_t first = c.start[i], last = c.start[i + 1];
    for (std::uint32_t a = first + 1; a < last; ++a) {
        const std::uint32_t key = c.entries[a];
        std::uint32_t b = a;
        for (; b > first && c.entries[b - 1] > key; --b) c.entries[b] = c.entries[b - 1];
        c.entries[b] = key;
    }
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
    for (std::uint32_t p = first_thread(); p < m; p += thread_stride()) {
        if ((d.contacts.list[p].pair & kOffsetContactBit) != 0)
            evaluate_offset_pair(d, p);
        else
            evaluate_pair(d, p);
    }
}

/// s_p = C_p·Σ_j w_j x_j for every pair (the gather is fused into the PCG row kernels).
__global__ void contact_product_kernel(DeviceView d, const float* x, int in_cg_loop) {
    if (in_cg_loop && !d.control->running) return;
    const std::uint32_t m = contact_count(d.contacts);
    for (std::uint32_t p = first_thread(); p < m; p += thread_stride()) contact_pair_product(d.contacts, p, x, d.n);
}

}  // namespace

std::size_t contact_scan_storage_bytes(std::uint32_t n) {
    std::size_t bytes = 0;
    WEFT_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(nullptr, bytes, static_cast<const std::uint32_t*>(nullptr),
                                                  static_cast<std::uint32_t*>(nullptr), static_cast<int>(n) + 1));
    return bytes;
}

void launch_contact_incidence(const DeviceView& d, void* scan_storage, std::size_t scan_bytes, cudaStream_t stream) {
    const ContactView& c = d.contacts;
    const unsigned corner_blocks = pair_grid(4ull * c.capacity);
    contact_count_kernel<<<corner_blocks, kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("contact_count_kernel");
    // fill[n] is never counted: the scan's last element is the total, start[n].
    std::size_t bytes = scan_bytes;
    WEFT_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(scan_storage, bytes, static_cast<const std::uint32_t*>(c.fill),
                                                  c.start, static_cast<int>(d.n) + 1, stream));
    contact_scatter_kernel<<<corner_blocks, kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("contact_scatter_kernel");
    contact_order_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("contact_order_kernel");
}

void launch_contact_evaluate(const DeviceView& d, cudaStream_t stream) {
    contact_evaluate_kernel<<<pair_grid(d.contacts.capacity), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("contact_evaluate_kernel");
}

void launch_contact_product(const DeviceView& d, const float* x, bool in_cg_loop, cudaStream_t stream) {
    contact_product_kernel<<<pair_grid(d.contacts.capacity), kBlockSize, 0, stream>>>(d, x, in_cg_loop ? 1 : 0);
    WEFT_CUDA_CHECK_LAUNCH("contact_product_kernel");
}

}  // namespace weft::cuda
