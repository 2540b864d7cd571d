// Substep bookkeeping on the device: start-of-substep copies, pins, the Newton update, the commit
// with its non-finite check and rollback, the swept test of fast analytic colliders, and the output
// of positions and normals.
#include "cuda_check.h"
#include "device_math.cuh"
#include "weft/backend/runaway.h"
#include "weft/physics/swept_collider.h"

namespace weft::cuda {
namespace {

struct FloatMax {
    __device__ float operator()(float a, float b) const { return a < b ? b : a; }
};

/// kRunawaySpeed² in float (m²/s²).
constexpr float kRunawaySpeedSquared = static_cast<float>(kRunawaySpeed * kRunawaySpeed);

__global__ void begin_substep_kernel(DeviceView d) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i == 0) *d.stats = DeviceStats{};
    if (i >= 3 * d.n) return;
    d.x0[i] = d.x[i];
    d.v0[i] = d.v[i];
    d.vk[i] = d.v[i];
    d.wk[i] = 0.0f;
}

__global__ void pin_velocities_kernel(DeviceView d) {
    const std::uint32_t p = blockIdx.x * blockDim.x + threadIdx.x;
    const StepParams& sp = step_params(d);
    if (p >= d.pins) return;
    const std::uint32_t i = d.pin_vertex[p];
    const V3 target = staged<V3>(d, sp.pin_target_offset)[p];
    store3(d.pin_velocity, i, d.n, (target - load3(d.x, i, d.n)) / sp.h);
}

__global__ void begin_newton_kernel(DeviceView d) {
    d.control->counter = 0;
    d.control->running = 0;
    d.control->iterations = 0;
    d.control->converged = 0;
    d.stats->contacts = 0;
}

__global__ void newton_update_kernel(DeviceView d) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= 3 * d.n) return;
    const float v = d.vk[i] + d.dv[i];
    d.vk[i] = v;
    d.wk[i] = v;
}

__global__ void line_search_trial_kernel(DeviceView d, float alpha, float* trial_x, float* trial_dv) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= d.n) return;
    const float a = d.fixed[i] ? 1.0f : alpha;
    const V3 v = load3(d.vk, i, d.n) + a * load3(d.dv, i, d.n);
    store3(trial_x, i, d.n, load3(d.x0, i, d.n) + step_params(d).h * v);
    store3(trial_dv, i, d.n, v - load3(d.v0, i, d.n));
}

__global__ void scale_update_kernel(DeviceView d, float alpha) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= d.n || d.fixed[i]) return;
    for (int c = 0; c < 3; ++c) d.dv[c * d.n + i] *= alpha;
}

__global__ void commit_kernel(DeviceView d) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    const StepParams& sp = step_params(d);
    float moved = 0.0f;
    if (i < d.n) {
        const float h = sp.h;
        const V3 v = load3(d.vk, i, d.n);
        const V3 x0 = load3(d.x0, i, d.n);
        const V3 x = x0 + h * v;
        store3(d.v, i, d.n, v);
        store3(d.x, i, d.n, x);
        store3(d.dv_previous, i, d.n, v - load3(d.v0, i, d.n));
        if (!physics::is_finite(x) || !physics::is_finite(v)) atomicAdd(&d.stats->non_finite, 1);
        else if (!d.fixed[i] && physics::length_squared(v) > kRunawaySpeedSquared) atomicAdd(&d.stats->runaway, 1);
        // The vertex's own share of the relative motion the swept test measures (swept_collider.h);
        // pinned vertices are never swept, as on the CPU.
        if (sp.bounded_shape_count > 0 && !d.fixed[i]) {
            moved = physics::length(x - x0);
            // A slow vertex that ends inside a bounded collider it started outside is put back on
            // its surface by the sweep (swept_shape_contact's slow case): ask for the sweep.
            const auto* start = staged<physics::Shape<float>>(d, sp.shape_start_offset);
            const auto* end = staged<physics::Shape<float>>(d, sp.shape_offset);
            V3 n{};
            for (int s = 0; s < sp.shape_count && sp.correct_overshoots != 0; ++s) {
                if (!(physics::shape_min_width(start[s]) > 0.0f)) continue;
                if (physics::shape_distance(end[s], x, n, static_cast<physics::Mat3<float>*>(nullptr)) < 0.0f &&
                    !(physics::shape_distance(start[s], x0, n, static_cast<physics::Mat3<float>*>(nullptr)) < 0.0f))
                    moved = 3.0e38f;
            }
        }
    }
    // The largest over the grid: one block reduction and one atomic per block (a float ≥ 0 orders
    // like its bits). The condition is the same for the whole grid, so the barrier inside is safe.
    if (sp.bounded_shape_count > 0) {
        using Reduce = cub::BlockReduce<float, kBlockSize>;
        __shared__ typename Reduce::TempStorage storage;
        const float block_moved = Reduce(storage).Reduce(moved, FloatMax{});
        if (threadIdx.x == 0 && block_moved > 0.0f) atomicMax(&d.stats->largest_move_bits, __float_as_uint(block_moved));
    }
}

// A NaN or Inf anywhere rolls the whole substep back, as on the CPU; the stats say so.
__global__ void rollback_kernel(DeviceView d, int always) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= 3 * d.n || (always == 0 && d.stats->non_finite == 0)) return;
    d.x[i] = d.x0[i];
    d.v[i] = d.v0[i];
    d.dv_previous[i] = 0.0f;
}

// A runaway solve (a free vertex over kRunawaySpeed, no NaN) is dropped, as on the CPU: the free
// vertices keep their start velocity through the substep; the collision stages still sweep it.
// `always`: whatever this device's stats say (part mode: another part's vertex ran away).
__global__ void drop_runaway_kernel(DeviceView d, int always) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= d.n || (always == 0 && d.stats->runaway == 0) || d.stats->non_finite != 0) return;
    const V3 x0 = load3(d.x0, i, d.n);
    const V3 v = d.fixed[i] ? load3(d.v, i, d.n) : load3(d.v0, i, d.n);
    store3(d.v, i, d.n, v);
    store3(d.x, i, d.n, x0 + step_params(d).h * v);
    store3(d.dv_previous, i, d.n, V3{});
}

// The per-vertex loop of CpuSolver::sweep_fast_colliders, in float: every collider in the CPU's
// order, each one tested against the path x0 → x as corrected by the ones before it.
__global__ void sweep_colliders_kernel(DeviceView d) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= d.n || d.fixed[i]) return;
    const StepParams& sp = step_params(d);
    const auto* start = staged<physics::Shape<float>>(d, sp.shape_start_offset);
    const auto* end = staged<physics::Shape<float>>(d, sp.shape_offset);
    const float thickness = staged<ClothParams>(d, sp.cloth_offset)[d.vertex_cloth[i]].thickness;
    const V3 x0 = load3(d.x0, i, d.n);
    V3 x = load3(d.x, i, d.n);
    int hits = 0, overshoots = 0;
    for (int s = 0; s < sp.shape_count; ++s) {
        const physics::SweptContact<float> c = physics::swept_shape_contact(start[s], end[s], sp.h, x0, x, thickness);
        if (!c.hit || (c.samples == 0 && sp.correct_overshoots == 0)) continue;
        x = c.position;
        if (c.samples > 0)
            ++hits;
        else
            ++overshoots;  // a slow end inside, put back onto the surface
    }
    if (hits + overshoots == 0) return;
    const V3 v = (x - x0) / sp.h;
    store3(d.x, i, d.n, x);
    store3(d.v, i, d.n, v);
    store3(d.dv_previous, i, d.n, v - load3(d.v0, i, d.n));  // the CPU's v − v0 after a sweep
    // Integers, and only the few vertices hit: order-free. A ghost's hits are its owner's to count.
    if (i < d.rows && hits > 0) atomicAdd(&d.stats->swept_hits, hits);
    if (i < d.rows && overshoots > 0) atomicAdd(&d.stats->overshoot_hits, overshoots);
}

__global__ void write_output_kernel(DeviceView d, unsigned char* out, std::size_t stride, const std::uint32_t* index) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= d.rows) return;
    // Area-weighted vertex normal: the sum of the incident faces' cross products, in a fixed order.
    V3 normal{};
    for (std::uint32_t e = d.vertex_triangle_start[i]; e < d.vertex_triangle_start[i + 1]; ++e) {
        const std::uint32_t t = d.vertex_triangle[e] >> 2;
        const V3 a = load3(d.x, d.triangle_vertices[3 * t], d.n);
        const V3 b = load3(d.x, d.triangle_vertices[3 * t + 1], d.n);
        const V3 c = load3(d.x, d.triangle_vertices[3 * t + 2], d.n);
        normal += physics::cross(b - a, c - a);
    }
    normal = physics::normalized(normal);
    const V3 x = load3(d.x, i, d.n);
    float* o = reinterpret_cast<float*>(out + stride * (index != nullptr ? index[i] : i));
    o[0] = x.x;
    o[1] = x.y;
    o[2] = x.z;
    o[3] = normal.x;
    o[4] = normal.y;
    o[5] = normal.z;
}

__global__ void write_stamp_kernel(std::uint64_t* where, std::uint64_t stamp) { *where = stamp; }

}  // namespace

void launch_begin_substep(const DeviceView& d, cudaStream_t stream) {
    begin_substep_kernel<<<grid_for(3 * d.n), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("begin_substep_kernel");
}

void launch_pin_velocities(const DeviceView& d, cudaStream_t stream) {
    if (d.pins == 0) return;
    pin_velocities_kernel<<<grid_for(d.pins), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("pin_velocities_kernel");
}

void launch_begin_newton(const DeviceView& d, cudaStream_t stream) {
    begin_newton_kernel<<<1, 1, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("begin_newton_kernel");
}

void launch_newton_update(const DeviceView& d, cudaStream_t stream) {
    newton_update_kernel<<<grid_for(3 * d.n), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("newton_update_kernel");
}

void launch_line_search_trial(const DeviceView& d, float alpha, float* trial_x, float* trial_dv, cudaStream_t stream) {
    line_search_trial_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d, alpha, trial_x, trial_dv);
    WEFT_CUDA_CHECK_LAUNCH("line_search_trial_kernel");
}

void launch_scale_update(const DeviceView& d, float alpha, cudaStream_t stream) {
    scale_update_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d, alpha);
    WEFT_CUDA_CHECK_LAUNCH("scale_update_kernel");
}

void launch_commit(const DeviceView& d, cudaStream_t stream) {
    commit_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("commit_kernel");
    rollback_kernel<<<grid_for(3 * d.n), kBlockSize, 0, stream>>>(d, 0);
    WEFT_CUDA_CHECK_LAUNCH("rollback_kernel");
    drop_runaway_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d, 0);
    WEFT_CUDA_CHECK_LAUNCH("drop_runaway_kernel");
}

void launch_drop_solve(const DeviceView& d, cudaStream_t stream) {
    drop_runaway_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d, 1);
    WEFT_CUDA_CHECK_LAUNCH("drop_runaway_kernel");
}

void launch_rollback(const DeviceView& d, cudaStream_t stream) {
    rollback_kernel<<<grid_for(3 * d.n), kBlockSize, 0, stream>>>(d, 1);
    WEFT_CUDA_CHECK_LAUNCH("rollback_kernel");
}

void launch_sweep_colliders(const DeviceView& d, cudaStream_t stream) {
    sweep_colliders_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("sweep_colliders_kernel");
}

void launch_write_output(const DeviceView& d, void* out, std::size_t stride, cudaStream_t stream, const std::uint32_t* index) {
    write_output_kernel<<<grid_for(d.rows), kBlockSize, 0, stream>>>(d, static_cast<unsigned char*>(out), stride, index);
    WEFT_CUDA_CHECK_LAUNCH("write_output_kernel");
}

void launch_write_stamp(void* where, std::uint64_t stamp, cudaStream_t stream) {
    write_stamp_kernel<<<1, 1, 0, stream>>>(static_cast<std::uint64_t*>(where), stamp);
    WEFT_CUDA_CHECK_LAUNCH("write_stamp_kernel");
}

}  // namespace weft::cuda
