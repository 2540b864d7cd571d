// CCD on the GPU over the broad phase's candidates (see ccd_gpu.h).
#include "collision/ccd_gpu.h"

#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <cmath>
#include <string>

#include "collision/grow_and_rerun.h"
#include "collision/pair_geometry.cuh"
#include "cuda_check.h"
#include "grid_size.h"

namespace weft::cuda::collision {
namespace {

constexpr unsigned kThreads = 128;  // the search keeps its box queue in local memory: smaller blocks
/// Below this fraction of eta the gap's direction is not trusted for the normal (as the CPU's
/// kNormalFromGapRatio in impact_zones.cpp).
constexpr float kNormalFromGapRatio = 1e-3F;

/// Pass 1: the search. Per candidate: hit flag (the element at `capacity` is the scan's total) and
/// (toi, distance bound, eta, status).
__global__ void __launch_bounds__(kThreads) ccd_kernel(GpuCcdInput in, std::uint32_t stride, GpuPairList pairs,
                                                       std::uint32_t* flags, float4* result,
                                                       GpuCcdCounters* counters) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    std::uint32_t flag = 0;
    bool immovable = false, rejected = false, tested = false, conservative = false;
    if (i < candidates_in_use(pairs)) {
        const PairVertices pv = pair_vertices(pairs.encoding, pairs.keys[i], in.triangles, in.edges);
        if (in.inverse_mass != nullptr)
            immovable = in.inverse_mass[pv.id[0]] == 0.0F && in.inverse_mass[pv.id[1]] == 0.0F &&
                        in.inverse_mass[pv.id[2]] == 0.0F && in.inverse_mass[pv.id[3]] == 0.0F;
        if (!immovable) {
            V3f a0[4], a1[4];
            for (int k = 0; k < 4; ++k) {
                a0[k] = load_position(in.x0, pv.id[k], stride);
                a1[k] = load_position(in.x1, pv.id[k], stride);
            }
            // Swept boxes of the two primitives (exact: min and max of the given floats); within eta
            // on every axis if they ever come within eta (Euclidean), the sums rounded up.
            for (int axis = 0; axis < 3 && !rejected; ++axis) {
                float lo[2] = {a0[0][axis], a0[pv.first_side][axis]}, hi[2] = {lo[0], lo[1]};
                for (int k = 0; k < 4; ++k) {
                    const int side = k < pv.first_side ? 0 : 1;
                    lo[side] = fminf(lo[side], fminf(a0[k][axis], a1[k][axis]));
                    hi[side] = fmaxf(hi[side], fmaxf(a0[k][axis], a1[k][axis]));
                }
                rejected = lo[0] > __fadd_ru(hi[1], in.eta) || lo[1] > __fadd_ru(hi[0], in.eta);
            }
            if (!rejected) {
                // The search in the pair's own frame: its rounding bound δ grows with the largest
                // coordinate (ccd.h), and in world coordinates 15 m from the origin float's δ alone
                // left no room to exclude t ≈ 0 for pairs that start under a millimetre apart, which
                // every round then found again at toi 0 (the character's script ran every substep to
                // the round cap; the CPU's double search never reports them). The differences are
                // exact where the coordinates are within a factor 2 (Sterbenz) and otherwise off by
                // half an ulp of the small result.
                const V3f origin = a0[0];
                for (int k = 0; k < 4; ++k) {
                    a0[k] = a0[k] - origin;
                    a1[k] = a1[k] - origin;
                }
                float eta = in.eta;
                if (in.clamp_to_start_distance) {
                    float w[4];
                    V3f n;
                    float d0 = 0.0F;
                    pair_closest(pv.vf, a0, w, n, d0);
                    eta = physics::min_(eta, 0.5F * d0);
                }
                physics::CcdOptions<float> opt;
                opt.t_tolerance = in.t_tolerance;
                opt.max_iterations = in.max_iterations;
                const physics::CcdResult<float> r =
                    pv.vf ? physics::vertex_face_ccd(a0[0], a0[1], a0[2], a0[3], a1[0], a1[1], a1[2], a1[3], eta, opt)
                          : physics::edge_edge_ccd(a0[0], a0[1], a0[2], a0[3], a1[0], a1[1], a1[2], a1[3], eta, opt);
                tested = true;
                if (r.hit) {
                    flag = 1;
                    conservative = r.diag.status != physics::CcdStatus::Contact;
                    result[i] = float4{r.toi, r.diag.distance_bound, eta,
                                       __uint_as_float(static_cast<unsigned>(r.diag.status))};
                }
            }
        }
    }
    if (i <= pairs.capacity) flags[i] = flag;
    // Block totals, then one integer atomic per block and counter (order-free).
    const int n_immovable = __syncthreads_count(immovable);
    const int n_rejected = __syncthreads_count(rejected);
    const int n_tested = __syncthreads_count(tested);
    const int n_conservative = __syncthreads_count(conservative);
    if (threadIdx.x == 0) {
        if (n_immovable > 0) atomicAdd(&counters->immovable, static_cast<std::uint32_t>(n_immovable));
        if (n_rejected > 0) atomicAdd(&counters->box_rejected, static_cast<std::uint32_t>(n_rejected));
        if (n_tested > 0) atomicAdd(&counters->tests, static_cast<std::uint32_t>(n_tested));
        if (n_conservative > 0) atomicAdd(&counters->conservative, static_cast<std::uint32_t>(n_conservative));
    }
}

/// Pass 2: each hit at its rank, with its contact data at toi (the impact zones' constraint: closest
/// points at toi; the geometric normal turned to the start side when the gap is too small to say).
__global__ void hit_write_kernel(GpuCcdInput in, std::uint32_t stride, GpuPairList pairs, const std::uint32_t* position,
                                 const float4* result, GpuCcdHit* out, std::uint32_t capacity) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= candidates_in_use(pairs)) return;
    const std::uint32_t at = position[i];
    if (position[i + 1] == at || at >= capacity) return;
    const PairVertices pv = pair_vertices(pairs.encoding, pairs.keys[i], in.triangles, in.edges);
    const float4 r = result[i];
    const float toi = r.x;
    V3f a0[4], xt[4];
    for (int k = 0; k < 4; ++k) {
        a0[k] = load_position(in.x0, pv.id[k], stride);
        const V3f a1 = load_position(in.x1, pv.id[k], stride);
        xt[k] = a0[k] + toi * (a1 - a0[k]);
    }
    float w[4];
    V3f n;
    float distance = 0.0F;
    pair_closest(pv.vf, xt, w, n, distance);
    if (!(distance > kNormalFromGapRatio * r.z)) {
        const V3f geometric = pv.vf ? physics::cross(xt[2] - xt[1], xt[3] - xt[1]) : physics::cross(xt[1] - xt[0], xt[3] - xt[2]);
        const V3f g = physics::normalized(geometric);
        if (physics::length_squared(g) > 0.0F) n = g;
        V3f f0{};
        for (int k = 0; k < 4; ++k) f0 += w[k] * a0[k];
        if (physics::dot(n, f0) < 0.0F) n = -n;
    }
    GpuCcdHit h;
    for (int k = 0; k < 4; ++k) {
        h.vertex[k] = pv.id[k];
        h.weight[k] = w[k];
    }
    h.normal[0] = n.x;
    h.normal[1] = n.y;
    h.normal[2] = n.z;
    h.toi = toi;
    h.distance_bound = r.y;
    h.eta = r.z;
    h.pair = i;
    h.status = __float_as_uint(r.w);
    out[at] = h;
}

__global__ void ccd_finish_kernel(GpuPairList pairs, const std::uint32_t* position, std::uint32_t capacity,
                                  GpuCcdCounters* counters) {
    counters->hits = position[pairs.capacity];
    counters->candidates = candidates_in_use(pairs);
    counters->overflow = counters->hits > capacity ? 1U : 0U;
}

}  // namespace

GpuCcd::GpuCcd(std::size_t capacity) : capacity_(capacity) {
    counters_host_.allocate(1);
    *counters_host_.get() = GpuCcdCounters{};
}

const std::uint32_t* GpuCcd::device_count() const { return counters_.get() != nullptr ? &counters_.get()->hits : nullptr; }

std::size_t GpuCcd::memory_bytes() const {
    return position_.bytes() + result_.bytes() + hits_.bytes() + counters_.bytes() + temp_.bytes();
}

void GpuCcd::enqueue(const GpuCcdInput& in, const GpuPairList& pairs, cudaStream_t stream) {
    if (pairs.count == nullptr || (pairs.capacity > 0 && pairs.keys == nullptr))
        throw Error("GPU CCD: no pair list (run the broad phase first)");
    if (in.vertex_count > 0 && (in.x0 == nullptr || in.x1 == nullptr)) throw Error("GPU CCD: positions missing");
    if (!std::isfinite(in.eta) || in.eta < 0.0F) throw Error("GPU CCD: eta must be finite and non-negative, got " + std::to_string(in.eta));
    if (capacity_ == 0) capacity_ = std::max<std::size_t>(1024, pairs.capacity / 16);
    if (apply_trim(trimmed_, capacity_, hits_)) ++trims_;
    const std::size_t slots = std::size_t{pairs.capacity} + 1;
    fit_to(position_, slots, ledger_, "ccd: ranks");
    fit_to(result_, slots, ledger_, "ccd: results");
    if (counters_.size() == 0) counters_.allocate(1, ledger_, "ccd: counters");
    std::size_t bytes = 0;
    WEFT_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(nullptr, bytes, position_.get(), pairs.capacity + 1U));
    if (temp_.size() < bytes) temp_.allocate(bytes, ledger_, "ccd: CUB scratch");

    const std::uint32_t stride = in.stride != 0 ? in.stride : in.vertex_count;
    counters_.zero(stream);
    ranked_ = false;
    ccd_kernel<<<blocks_for(slots, kThreads), kThreads, 0, stream>>>(in, stride, pairs, position_.get(), result_.get(),
                                                                     counters_.get());
    WEFT_CUDA_CHECK_LAUNCH("ccd_kernel");
    enqueue_compaction(in, pairs, stream);
}

void GpuCcd::enqueue_compaction(const GpuCcdInput& in, const GpuPairList& pairs, cudaStream_t stream) {
    if (hits_.size() < capacity_) hits_.allocate(capacity_, ledger_, "ccd: hits");
    const std::uint32_t stride = in.stride != 0 ? in.stride : in.vertex_count;
    const auto capacity = static_cast<std::uint32_t>(capacity_);
    // The flags become ranks in place (a hit is where position[i + 1] > position[i]); a repeated
    // compaction after growing reuses the ranks.
    std::size_t temp_bytes = temp_.bytes();
    if (!ranked_) {
        WEFT_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(temp_.get(), temp_bytes, position_.get(), pairs.capacity + 1U, stream));
        ranked_ = true;
    }
    if (pairs.capacity > 0) {
        hit_write_kernel<<<blocks_for(pairs.capacity, kThreads), kThreads, 0, stream>>>(
            in, stride, pairs, position_.get(), result_.get(), hits_.get(), capacity);
        WEFT_CUDA_CHECK_LAUNCH("hit_write_kernel");
    }
    ccd_finish_kernel<<<1, 1, 0, stream>>>(pairs, position_.get(), capacity, counters_.get());
    WEFT_CUDA_CHECK_LAUNCH("ccd_finish_kernel");
}

const GpuCcdCounters& GpuCcd::read_back(cudaStream_t stream) {
    if (counters_.get() == nullptr) throw Error("GPU CCD: read_back before enqueue");
    WEFT_CUDA_CHECK(cudaMemcpyAsync(counters_host_.get(), counters_.get(), sizeof(GpuCcdCounters),
                                    cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    return counters();
}

bool GpuCcd::needs_rerun() {
    if (grow_after_overflow(counters().overflow != 0, counters().hits, capacity_, reruns_)) return true;
    record_for_trim(trim_, counters().hits, capacity_, sizeof(GpuCcdHit), trimmed_);
    return false;
}

const GpuCcdCounters& GpuCcd::find(const GpuCcdInput& in, const GpuPairList& pairs, cudaStream_t stream) {
    rerun_until_fits(*this, stream, "GPU CCD: buffer", 4, [&](int attempt) {
        if (attempt == 0)
            enqueue(in, pairs, stream);
        else
            enqueue_compaction(in, pairs, stream);  // the search results are kept: only the scatter again
    });
    return counters();
}

void GpuCcd::download(std::vector<GpuCcdHit>& out, cudaStream_t stream) const {
    const std::size_t count = std::min<std::size_t>(counters().hits, capacity_);
    out.resize(count);
    if (count == 0) return;
    WEFT_CUDA_CHECK(cudaMemcpyAsync(out.data(), hits_.get(), count * sizeof(GpuCcdHit), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
}

}  // namespace weft::cuda::collision
