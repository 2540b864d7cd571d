// Displacement bounds and the truncation on the GPU (see displacement_bounds_gpu.h).
#include "collision/displacement_bounds_gpu.h"

#include <cmath>
#include <string>

#include "collision/pair_geometry.cuh"
#include "cuda_check.h"
#include "grid_size.h"
#include "weft/error.h"

namespace weft::cuda::collision {
namespace {

constexpr unsigned kThreads = 256;
constexpr std::uint32_t kInfinityBits = 0x7F800000U;  // +∞: above every finite non-negative float
constexpr std::uint32_t kOneBits = 0x3F800000U;       // 1.0f
constexpr std::uint32_t kEdgeEdgeFlag = 1U << 31;      // in the last id of pair_ids_

__global__ void reset_kernel(GpuBoundsCounters* c, std::uint32_t* nearest, std::uint32_t n) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i == 0) *c = GpuBoundsCounters{};  // every field: read_back copies the whole block
    if (i < n) nearest[i] = kInfinityBits;
}

/// One thread per candidate: its distance and normal at x, and, when it is within the largest radius
/// of its four vertices, the nearest distance of each of them lowered to it.
__global__ void pair_kernel(GpuBoundsInput in, std::uint32_t stride, GpuPairList pairs, float4* geometry, uint4* ids,
                            std::uint32_t* nearest, GpuBoundsCounters* counters) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= candidates_in_use(pairs)) return;
    const PairVertices pv = pair_vertices(pairs.encoding, pairs.keys[i], in.triangles, in.edges);
    ids[i] = uint4{pv.id[0], pv.id[1], pv.id[2], pv.id[3] | (pv.vf ? 0U : kEdgeEdgeFlag)};
    V3f x[4];
    for (int a = 0; a < 4; ++a) x[a] = load_position(in.x, pv.id[a], stride);
    float w[4];
    V3f normal;
    float d = 0.0F;
    pair_closest(pv.vf, x, w, normal, d);
    float largest = 0.0F;
    for (int a = 0; a < 4; ++a) largest = fmaxf(largest, in.radius[pv.id[a]]);
    const bool measured = d < largest;
    geometry[i] = float4{normal.x, normal.y, normal.z, measured ? d : __int_as_float(kInfinityBits)};
    if (!measured) return;
    const std::uint32_t bits = __float_as_uint(fmaxf(d, 0.0F));
    for (int a = 0; a < 4; ++a) atomicMin(&nearest[pv.id[a]], bits);
    atomicAdd(pv.vf ? &counters->measured_vf : &counters->measured_ee, 1U);
}

__global__ void vertex_kernel(GpuBoundsInput in, const std::uint32_t* nearest, float* bound, float* reach,
                              GpuBoundsCounters* counters) {
    const std::uint32_t v = blockIdx.x * blockDim.x + threadIdx.x;
    if (v >= in.vertex_count) return;
    const float r = in.radius[v];
    const float d = __uint_as_float(nearest[v]);
    if (d < r) atomicAdd(&counters->limited, 1U);
    bound[v] = in.relaxation * fminf(r, d);
    reach[v] = in.relaxation * r;
}

__device__ inline float step_h(const GpuTruncateInput& t) { return t.h_device != nullptr ? *t.h_device : t.h; }
__device__ inline V3f step_shift(const GpuTruncateInput& t) {
    return t.shift_device != nullptr ? V3f{t.shift_device[0], t.shift_device[1], t.shift_device[2]}
                                     : V3f{t.shift[0], t.shift[1], t.shift[2]};
}

/// The proposal of local vertex i: x0 + h·v, or x0 alone for a check.
__device__ inline V3f proposal(const GpuTruncateInput& t, std::uint32_t stride, std::uint32_t i) {
    const V3f x = load_position(t.x0, i, stride);
    return t.v != nullptr ? x + step_h(t) * load_position(t.v, i, stride) : x;
}

/// The move of local vertex i from the detection: proposal − shift − x_detect.
__device__ inline V3f move_of(const GpuTruncateInput& t, std::uint32_t stride, std::uint32_t detect_stride,
                              std::uint32_t i) {
    return proposal(t, stride, i) - step_shift(t) - load_position(t.x_detect, t.first + i, detect_stride);
}

/// Per vertex: the share its reach (planar) or its bound (sphere) allows.
__global__ void share_kernel(GpuTruncateInput t, std::uint32_t stride, std::uint32_t detect_stride, const float* bound,
                             const float* reach, std::uint32_t* share, GpuBoundsCounters* counters, int reset) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i == 0 && reset) counters->truncated = counters->broken = 0;
    if (i >= t.vertex_count) return;
    const float length = physics::length(move_of(t, stride, detect_stride, i));
    const float limit = t.planar ? reach[t.first + i] : bound[t.first + i];
    share[t.first + i] = length > limit ? __float_as_uint(limit / length) : kOneBits;
}

/// Planar: one thread per measured pair; each of its vertices may advance at most γ·d towards the
/// partner (the first primitive's vertices along −n, the second's along +n).
__global__ void pair_share_kernel(GpuTruncateInput t, std::uint32_t stride, std::uint32_t detect_stride,
                                  float relaxation, const std::uint32_t* count, std::uint32_t capacity,
                                  const uint4* ids, const float4* geometry, std::uint32_t* share) {
    const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= capacity || k >= *count) return;
    const float4 g = geometry[k];
    if (!(g.w < __int_as_float(kInfinityBits))) return;  // not measured
    const uint4 q = ids[k];
    const std::uint32_t id[4] = {q.x, q.y, q.z, q.w & ~kEdgeEdgeFlag};
    const int first_side = (q.w & kEdgeEdgeFlag) != 0 ? 2 : 1;
    const float limit = relaxation * g.w;
    for (int a = 0; a < 4; ++a) {
        const std::uint32_t v = id[a];
        if (v < t.first || v - t.first >= t.vertex_count) continue;
        const float sign = a < first_side ? -1.0F : 1.0F;
        const float advance = sign * physics::dot(move_of(t, stride, detect_stride, v - t.first), V3f{g.x, g.y, g.z});
        if (advance > limit) atomicMin(&share[v], __float_as_uint(limit / advance));
    }
}

__global__ void apply_kernel(GpuTruncateInput t, std::uint32_t stride, std::uint32_t detect_stride,
                             const std::uint32_t* share, GpuBoundsCounters* counters) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= t.vertex_count) return;
    const float s = __uint_as_float(share[t.first + i]);
    const bool cut = s < 1.0F;
    const V3f move = move_of(t, stride, detect_stride, i);
    if (t.remainder != nullptr) t.remainder[i] = cut ? (1.0F - s) * physics::length(move) : 0.0F;
    if (!cut) return;
    if (t.v == nullptr || (t.prescribed != nullptr && t.prescribed[i] != 0)) {
        atomicAdd(&counters->broken, 1U);
        return;
    }
    const V3f kept = load_position(t.x_detect, t.first + i, detect_stride) + s * move + step_shift(t);
    const V3f vel = (kept - load_position(t.x0, i, stride)) / step_h(t);
    for (float* out : {t.v, t.v_copy}) {
        if (out == nullptr) continue;
        out[i] = vel.x;
        out[i + static_cast<std::size_t>(stride)] = vel.y;
        out[i + 2 * static_cast<std::size_t>(stride)] = vel.z;
    }
    atomicAdd(&counters->truncated, 1U);
}

/// Up to kMaxReducedArrays device arrays, passed by value (peers' pointers included).
struct ArraySet {
    const std::uint32_t* array[GpuDisplacementBounds::kMaxReducedArrays];
    std::uint32_t count;
};

/// out[v] = min over the arrays of array[v]: the bits of non-negative floats order like the floats.
__global__ void min_across_kernel(ArraySet set, std::uint32_t n, std::uint32_t* out) {
    const std::uint32_t v = blockIdx.x * blockDim.x + threadIdx.x;
    if (v >= n) return;
    std::uint32_t m = set.array[0][v];
    for (std::uint32_t a = 1; a < set.count; ++a) m = min(m, set.array[a][v]);
    out[v] = m;
}

}  // namespace

void GpuDisplacementBounds::compute(const GpuBoundsInput& in, GpuBroadPhase& hash, cudaStream_t stream,
                                    const BoundsReduction& reduce) {
    if (in.vertex_count > 0 && (in.x == nullptr || in.radius == nullptr))
        throw Error("GPU displacement bounds: positions or radii missing");
    if (!(in.relaxation > 0.0F && in.relaxation < 0.5F))
        throw Error("GPU displacement bounds: relaxation " + std::to_string(in.relaxation) + " (must lie in (0, 0.5))");
    in_ = in;
    const std::uint32_t stride = in.stride != 0 ? in.stride : in.vertex_count;
    GpuBroadPhaseInput b;
    b.x0 = in.x;
    b.x1 = in.x;
    b.vertex_count = in.vertex_count;
    b.stride = stride;
    b.triangles = in.triangles;
    b.triangle_count = in.triangle_count;
    b.edges = in.edges;
    b.edge_count = in.edge_count;
    b.triangle_cloth = in.triangle_cloth;
    b.self_pairs = in.self_pairs;
    b.vertex_padding = in.radius;
    b.share_index = in.share_index;
    b.share_count = in.share_count;
    (void)hash.find(b, stream);
    pairs_ = hash.pairs();

    if (counters_host_.size() == 0) counters_host_.allocate(1);
    if (counters_.size() == 0) counters_.allocate(1, ledger_, "offset bounds: counters");
    if (nearest_bits_.size() < in.vertex_count) {
        ++generation_;
        nearest_bits_.allocate(in.vertex_count, ledger_, "offset bounds: nearest");
        share_bits_.allocate(in.vertex_count, ledger_, "offset bounds: shares");
        bound_.allocate(in.vertex_count, ledger_, "offset bounds: bounds");
        reach_.allocate(in.vertex_count, ledger_, "offset bounds: reach");
    }
    if (capacity_ < pairs_.capacity) {
        capacity_ = pairs_.capacity;
        pair_geometry_.allocate(capacity_, ledger_, "offset bounds: pairs");
        pair_ids_.allocate(capacity_, ledger_, "offset bounds: pairs");
        ++generation_;
    }

    reset_kernel<<<blocks_for(in.vertex_count, kThreads), kThreads, 0, stream>>>(counters_.get(), nearest_bits_.get(),
                                                                                in.vertex_count);
    WEFT_CUDA_CHECK_LAUNCH("reset_kernel");
    if (pairs_.capacity > 0) {
        pair_kernel<<<blocks_for(pairs_.capacity, kThreads), kThreads, 0, stream>>>(
            in, stride, pairs_, pair_geometry_.get(), pair_ids_.get(), nearest_bits_.get(), counters_.get());
        WEFT_CUDA_CHECK_LAUNCH("pair_kernel");
    }
    // Across GPUs every share's nearest distances are partial: the vertex pass takes their minimum.
    const std::uint32_t* nearest = reduce ? reduce(BoundsArray::Nearest, stream) : nearest_bits_.get();
    vertex_kernel<<<blocks_for(in.vertex_count, kThreads), kThreads, 0, stream>>>(in, nearest, bound_.get(), reach_.get(),
                                                                                 counters_.get());
    WEFT_CUDA_CHECK_LAUNCH("vertex_kernel");
}

void GpuDisplacementBounds::truncate(const GpuTruncateInput& t, cudaStream_t stream, bool reset_counts,
                                     const BoundsReduction& reduce) {
    enqueue_limits(t, stream, reset_counts);
    // Across GPUs each share's pair limits are partial: the moves take the minimum over the shares.
    apply_shares(t, reduce ? reduce(BoundsArray::Shares, stream) : share_bits_.get(), stream);
}

void GpuDisplacementBounds::limit_shares(const GpuTruncateInput& t, cudaStream_t stream) { enqueue_limits(t, stream, true); }

void GpuDisplacementBounds::enqueue_limits(const GpuTruncateInput& t, cudaStream_t stream, bool reset_counts) {
    if (std::uint64_t{t.first} + t.vertex_count > in_.vertex_count)
        throw Error("GPU displacement bounds: truncating vertices [" + std::to_string(t.first) + ", " +
                    std::to_string(std::uint64_t{t.first} + t.vertex_count) + ") with bounds for " +
                    std::to_string(in_.vertex_count));
    if (t.vertex_count > 0 && (t.x_detect == nullptr || t.x0 == nullptr))
        throw Error("GPU displacement bounds: truncation arrays missing");
    if (t.h_device == nullptr && !(t.h > 0.0F)) throw Error("GPU displacement bounds: h must be positive");
    const std::uint32_t stride = t.stride != 0 ? t.stride : t.vertex_count;
    const std::uint32_t detect_stride = detect_stride_of(t);
    share_kernel<<<blocks_for(t.vertex_count, kThreads), kThreads, 0, stream>>>(
        t, stride, detect_stride, bound_.get(), reach_.get(), share_bits_.get(), counters_.get(), reset_counts ? 1 : 0);
    WEFT_CUDA_CHECK_LAUNCH("share_kernel");
    if (t.planar && capacity_ > 0) {
        pair_share_kernel<<<blocks_for(capacity_, kThreads), kThreads, 0, stream>>>(
            t, stride, detect_stride, in_.relaxation, pairs_.count, capacity_, pair_ids_.get(), pair_geometry_.get(),
            share_bits_.get());
        WEFT_CUDA_CHECK_LAUNCH("pair_share_kernel");
    }
}

void GpuDisplacementBounds::apply_shares(const GpuTruncateInput& t, const std::uint32_t* share, cudaStream_t stream) {
    const std::uint32_t stride = t.stride != 0 ? t.stride : t.vertex_count;
    apply_kernel<<<blocks_for(t.vertex_count, kThreads), kThreads, 0, stream>>>(t, stride, detect_stride_of(t), share,
                                                                               counters_.get());
    WEFT_CUDA_CHECK_LAUNCH("apply_kernel");
}

std::uint32_t GpuDisplacementBounds::detect_stride_of(const GpuTruncateInput& t) const {
    return t.detect_stride != 0 ? t.detect_stride : (in_.stride != 0 ? in_.stride : in_.vertex_count);
}

const std::uint32_t* GpuDisplacementBounds::reduce_across(std::span<const std::uint32_t* const> arrays, std::uint32_t count,
                                                          cudaStream_t stream) {
    if (arrays.empty() || arrays.size() > kMaxReducedArrays)
        throw Error("GPU displacement bounds: a reduction across " + std::to_string(arrays.size()) + " arrays (1 to " +
                    std::to_string(kMaxReducedArrays) + " GPUs' shares)");
    if (reduced_bits_.size() < count) reduced_bits_.allocate(count, ledger_, "offset bounds: across GPUs");
    ArraySet set{};
    for (std::size_t a = 0; a < arrays.size(); ++a) set.array[a] = arrays[a];
    set.count = static_cast<std::uint32_t>(arrays.size());
    if (count > 0) {
        min_across_kernel<<<blocks_for(count, kThreads), kThreads, 0, stream>>>(set, count, reduced_bits_.get());
        WEFT_CUDA_CHECK_LAUNCH("min_across_kernel");
    }
    return reduced_bits_.get();
}

const GpuBoundsCounters& GpuDisplacementBounds::read_back(cudaStream_t stream) {
    if (counters_.get() == nullptr) throw Error("GPU displacement bounds: read_back before compute");
    WEFT_CUDA_CHECK(cudaMemcpyAsync(counters_host_.get(), counters_.get(), sizeof(GpuBoundsCounters),
                                    cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    return counters();
}

void GpuDisplacementBounds::download(std::vector<float>& bound, std::vector<float>& reach, cudaStream_t stream) const {
    bound.resize(in_.vertex_count);
    reach.resize(in_.vertex_count);
    if (in_.vertex_count == 0) return;
    WEFT_CUDA_CHECK(cudaMemcpyAsync(bound.data(), bound_.get(), bound.size() * sizeof(float), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaMemcpyAsync(reach.data(), reach_.get(), reach.size() * sizeof(float), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
}

std::size_t GpuDisplacementBounds::memory_bytes() const {
    return nearest_bits_.bytes() + share_bits_.bytes() + reduced_bits_.bytes() + bound_.bytes() + reach_.bytes() +
           pair_geometry_.bytes() + pair_ids_.bytes() + counters_.bytes();
}

}  // namespace weft::cuda::collision
