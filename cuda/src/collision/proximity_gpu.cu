// Proximity contacts on the GPU from the broad phase's candidates (see proximity_gpu.h).
#include "collision/proximity_gpu.h"

#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <string>

#include "collision/grow_and_rerun.h"
#include "collision/pair_geometry.cuh"
#include "cuda_check.h"
#include "device_contacts.h"
#include "grid_size.h"
#include "weft/backend/proximity_contact.h"

namespace weft::cuda::collision {
namespace {

constexpr unsigned kThreads = 256;

/// True for a pair of rest neighbours (rest_neighbours in runtime/src/collision/proximity_contacts.cpp).
__device__ bool rest_neighbours(const GpuProximityInput& in, const PairVertices& pv, float thickness) {
    if (!(in.rest_exclusion > 0.0F) || in.rest == nullptr) return false;
    for (int i = 0; i < 4; ++i)
        if (pv.id[i] >= in.rest_count) return false;
    if (in.vertex_cloth[pv.id[0]] != in.vertex_cloth[pv.id[3]]) return false;
    V3f r[4];
    for (int i = 0; i < 4; ++i) r[i] = load_position(in.rest, pv.id[i], in.rest_count);
    float w[4];
    V3f normal;
    float distance = 0.0F;
    pair_closest(pv.vf, r, w, normal, distance);
    return distance < in.rest_exclusion * thickness;
}

/// The contact of one candidate, or false when it is none (too far at both ends, or nothing moves).
/// The same steps as make_contact in runtime/src/collision/proximity_contacts.cpp, in float. Not
/// inlined: both passes must run the very same instructions (the compiler could otherwise fuse
/// multiply-adds differently in the two kernels, and the passes disagree on a borderline contact).
__device__ __noinline__ bool make_contact(const GpuProximityInput& in, std::uint32_t stride, const PairEncoding& enc,
                             unsigned long long key, GpuProximityContact& c) {
    const PairVertices pv = pair_vertices(enc, key, in.triangles, in.edges);
    V3f x[4];
    for (int i = 0; i < 4; ++i) x[i] = load_position(in.x0, pv.id[i], stride);
    float w[4];
    V3f normal;
    float gap0 = 0.0F;
    pair_closest(pv.vf, x, w, normal, gap0);
    float inverse_effective_mass = 0.0F, movable_weight = 0.0F;
    float thickness_a = 0.0F, thickness_b = 0.0F, friction_a = 0.0F, friction_b = 0.0F;
    V3f predicted{};
    for (int i = 0; i < 4; ++i) {
        const std::uint32_t v = pv.id[i];
        inverse_effective_mass += w[i] * w[i] * in.inverse_mass[v];
        if (in.inverse_mass[v] > 0.0F) movable_weight += w[i] < 0.0F ? -w[i] : w[i];
        predicted += w[i] * load_position(in.x1, v, stride);
        float& thickness_side = i < pv.first_side ? thickness_a : thickness_b;
        float& friction_side = i < pv.first_side ? friction_a : friction_b;
        thickness_side = physics::max_(thickness_side, in.thickness[v]);
        friction_side = physics::max_(friction_side, in.friction[v]);
    }
    if (!(inverse_effective_mass > 0.0F) || !(movable_weight >= static_cast<float>(weft::collision::kMinMovableContactWeight))) return false;
    const float thickness =
        in.thickness_override > 0.0F ? in.thickness_override : physics::max_(thickness_a, thickness_b);
    if (in.offset_bound == nullptr) {
        const float gap1 = physics::dot(normal, predicted);
        if (!(physics::min_(gap0, gap1) < thickness)) return false;
    } else {
        // The most the gap can shrink under the bounds: each primitive moves at most as far as its
        // farthest vertex.
        float reach_a = 0.0F, reach_b = 0.0F;
        for (int i = 0; i < 4; ++i) {
            float& reach = i < pv.first_side ? reach_a : reach_b;
            reach = physics::max_(reach, in.offset_bound[pv.id[i]]);
        }
        if (!(gap0 - (reach_a + reach_b) < thickness)) return false;
    }
    if (rest_neighbours(in, pv, thickness)) return false;
    for (int i = 0; i < 4; ++i) {
        c.vertex[i] = pv.id[i];
        c.weight[i] = w[i];
    }
    c.normal[0] = normal.x;
    c.normal[1] = normal.y;
    c.normal[2] = normal.z;
    c.gap = gap0;
    c.thickness = thickness;
    c.stiffness = in.stiffness_override > 0.0F ? in.stiffness_override
                                               : 100.0F / (inverse_effective_mass * in.h * in.h);
    c.friction = 0.5F * (friction_a + friction_b);
    return true;
}

/// Pass 1: 1 for each candidate that is a contact (the element at `capacity` is the scan's total).
__global__ void contact_flags_kernel(GpuProximityInput in, std::uint32_t stride, GpuPairList pairs,
                                     std::uint32_t* flags) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i > pairs.capacity) return;
    std::uint32_t flag = 0;
    if (i < candidates_in_use(pairs)) {
        GpuProximityContact c;
        flag = make_contact(in, stride, pairs.encoding, pairs.keys[i], c) ? 1U : 0U;
    }
    flags[i] = flag;
}

/// Pass 2: the kept candidates again, each written at its rank.
__global__ void contact_write_kernel(GpuProximityInput in, std::uint32_t stride, GpuPairList pairs,
                                     const std::uint32_t* position, GpuProximityContact* out,
                                     std::uint32_t capacity) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= candidates_in_use(pairs)) return;
    const std::uint32_t at = position[i];
    if (position[i + 1] == at || at >= capacity) return;
    GpuProximityContact c;
    (void)make_contact(in, stride, pairs.encoding, pairs.keys[i], c);  // true: the same code decided pass 1
    c.pair = i;
    if (in.offset_bound != nullptr) c.pair |= kOffsetContactBit | (pairs.encoding.is_ee(pairs.keys[i]) ? kEdgeEdgeContactBit : 0U);
    out[at] = c;
}

__global__ void contact_finish_kernel(GpuPairList pairs, const std::uint32_t* position, std::uint32_t capacity,
                                      GpuProximityCounters* counters) {
    GpuProximityCounters c{};
    c.contacts = position[pairs.capacity];
    c.candidates = candidates_in_use(pairs);
    c.overflow = c.contacts > capacity ? 1U : 0U;
    *counters = c;
}

}  // namespace

GpuProximityContacts::GpuProximityContacts(std::size_t capacity) : capacity_(capacity) {
    counters_host_.allocate(1);
    *counters_host_.get() = GpuProximityCounters{};
}

const std::uint32_t* GpuProximityContacts::device_count() const {
    return counters_.get() != nullptr ? &counters_.get()->contacts : nullptr;
}

std::size_t GpuProximityContacts::memory_bytes() const {
    return position_.bytes() + contacts_.bytes() + counters_.bytes() + temp_.bytes();
}

void GpuProximityContacts::enqueue(const GpuProximityInput& in, const GpuPairList& pairs, cudaStream_t stream) {
    if (pairs.count == nullptr || (pairs.capacity > 0 && pairs.keys == nullptr))
        throw Error("GPU proximity contacts: no pair list (run the broad phase first)");
    if (in.vertex_count > 0 && (in.x0 == nullptr || in.x1 == nullptr || in.inverse_mass == nullptr ||
                                in.thickness == nullptr || in.friction == nullptr))
        throw Error("GPU proximity contacts: per-vertex arrays missing");
    if (in.rest != nullptr && (in.vertex_cloth == nullptr || in.rest_count > in.vertex_count))
        throw Error("GPU proximity contacts: rest positions without cloth ids, or more of them than vertices");
    if (!(in.h > 0.0F)) throw Error("GPU proximity contacts: substep must be positive, got " + std::to_string(in.h));
    if (capacity_ == 0) capacity_ = std::max<std::size_t>(1024, pairs.capacity / 4);
    if (apply_trim(trimmed_, capacity_, contacts_)) ++trims_;
    fit_to(position_, std::size_t{pairs.capacity} + 1, ledger_, "contacts: ranks");
    if (contacts_.size() < capacity_) contacts_.allocate(capacity_, ledger_, "contacts");
    if (counters_.size() == 0) counters_.allocate(1, ledger_, "contacts: counters");
    std::size_t bytes = 0;
    WEFT_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(nullptr, bytes, position_.get(), pairs.capacity + 1U));
    if (temp_.size() < bytes) temp_.allocate(bytes, ledger_, "contacts: CUB scratch");

    const std::uint32_t stride = in.stride != 0 ? in.stride : in.vertex_count;
    const auto capacity = static_cast<std::uint32_t>(capacity_);
    contact_flags_kernel<<<blocks_for(std::uint64_t{pairs.capacity} + 1, kThreads), kThreads, 0, stream>>>(
        in, stride, pairs, position_.get());
    WEFT_CUDA_CHECK_LAUNCH("contact_flags_kernel");
    std::size_t temp_bytes = temp_.bytes();
    WEFT_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(temp_.get(), temp_bytes, position_.get(), pairs.capacity + 1U, stream));
    if (pairs.capacity > 0) {
        contact_write_kernel<<<blocks_for(pairs.capacity, kThreads), kThreads, 0, stream>>>(
            in, stride, pairs, position_.get(), contacts_.get(), capacity);
        WEFT_CUDA_CHECK_LAUNCH("contact_write_kernel");
    }
    contact_finish_kernel<<<1, 1, 0, stream>>>(pairs, position_.get(), capacity, counters_.get());
    WEFT_CUDA_CHECK_LAUNCH("contact_finish_kernel");
}

const GpuProximityCounters& GpuProximityContacts::read_back(cudaStream_t stream) {
    if (counters_.get() == nullptr) throw Error("GPU proximity contacts: read_back before enqueue");
    WEFT_CUDA_CHECK(cudaMemcpyAsync(counters_host_.get(), counters_.get(), sizeof(GpuProximityCounters),
                                    cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    return counters();
}

bool GpuProximityContacts::needs_rerun() {
    if (grow_after_overflow(counters().overflow != 0, counters().contacts, capacity_, reruns_)) return true;
    record_for_trim(trim_, counters().contacts, capacity_, sizeof(GpuProximityContact), trimmed_);
    return false;
}

const GpuProximityCounters& GpuProximityContacts::find(const GpuProximityInput& in, const GpuPairList& pairs,
                                                       cudaStream_t stream) {
    rerun_until_fits(*this, stream, "GPU proximity contacts: buffer", 4, [&](int) { enqueue(in, pairs, stream); });
    return counters();
}

void GpuProximityContacts::download(std::vector<GpuProximityContact>& out, cudaStream_t stream) const {
    const std::size_t count = std::min<std::size_t>(counters().contacts, capacity_);
    out.resize(count);
    if (count == 0) return;
    WEFT_CUDA_CHECK(cudaMemcpyAsync(out.data(), contacts_.get(), count * sizeof(GpuProximityContact),
                                    cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
}

}  // namespace weft::cuda::collision
