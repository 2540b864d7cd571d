// Positions of the collision stages (device_collisions.h): the cloth part of the collision-space
// arrays, filled from the solver's state before and after the solve.
#include <cub/block/block_reduce.cuh>

#include <algorithm>

#include "cuda_check.h"
#include "kernels.h"

namespace weft::cuda {
namespace {

// weft::collision::VertexOutcome::Untouched (asserted in device_collisions.cpp); Fixed is 0.
constexpr std::uint8_t kOutcomeUntouched = 1;

__global__ void collision_predict_kernel(const float* x, const float* v, std::uint32_t n, float h, float* x0c,
                                         float* x1c, std::uint32_t stride) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    for (int c = 0; c < 3; ++c) {
        const float xi = x[c * n + i];
        x0c[c * stride + i] = xi;
        // No contraction into an FMA: the CPU rounds x0 + h·v0 as a product, then a sum.
        x1c[c * stride + i] = __fadd_rn(xi, __fmul_rn(h, v[c * n + i]));
    }
}

__global__ void collision_gather_kernel(const float* x, std::uint32_t n, float* x1c, std::uint32_t stride) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    for (int c = 0; c < 3; ++c) x1c[c * stride + i] = x[c * n + i];
}

/// Cloth vertices the impact zones moved (outcome Projected, Rigid, Frozen or Carried) take the
/// corrected end position, the velocity of their corrected motion and the matching warm start of the
/// next solve, as CpuCollisions and CpuSolver do.
__global__ void collision_scatter_kernel(const float* x1c, const float* x0c, const std::uint8_t* outcome,
                                         std::uint32_t n, std::uint32_t stride, float inv_h, float* x, float* v,
                                         const float* v0, float* dv_previous) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    if (outcome[i] <= kOutcomeUntouched) return;  // Fixed (0) or Untouched (1): x and v stand
    for (int c = 0; c < 3; ++c) {
        const float end = x1c[c * stride + i];
        const float velocity = (end - x0c[c * stride + i]) * inv_h;
        x[c * n + i] = end;
        v[c * n + i] = velocity;
        dv_previous[c * n + i] = velocity - v0[c * n + i];
    }
}

/// Linear blend skinning of the mesh colliders (a rigid mesh is one map of weight 1): the maps'
/// weighted sum applied to the rest position, at t, at t + h and for the velocity.
__global__ void place_kinematic_kernel(const float* rest, const std::uint32_t* joints, const float* weights,
                                       const float* maps, std::uint32_t count, float* x0c, float* x1c,
                                       std::uint32_t stride, float* x1, float* v) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= count) return;
    const float p[4] = {rest[i], rest[count + i], rest[2 * count + i], 1.0F};
    float out[3][3] = {};  // [x(t), x(t + h), v][component]
    for (std::uint32_t k = 0; k < 4; ++k) {
        const float w = weights[4 * i + k];
        if (w == 0.0F) continue;
        const float* a = maps + kKinematicMapFloats * joints[4 * i + k];
        for (int m = 0; m < 3; ++m)
            for (int r = 0; r < 3; ++r) {
                const float* row = a + 12 * m + 4 * r;
                out[m][r] += w * (row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + row[3] * p[3]);
            }
    }
    for (int c = 0; c < 3; ++c) {
        x0c[c * stride + i] = out[0][c];
        x1c[c * stride + i] = out[1][c];
        x1[c * count + i] = out[1][c];
        v[c * count + i] = out[2][c];
    }
}

using MomentumReduce = cub::BlockReduce<double, kBlockSize>;

/// Offset mode: Σ m·v and Σ m over the free cloth vertices, for the frame the moves are bounded in.
/// In a fixed order (grid-stride per thread, a block tree, then the blocks in order by
/// offset_momentum_finish_kernel): double atomics would round differently from run to run, and the
/// frame's last bits decide truncations and reruns.
__global__ void offset_momentum_kernel(const float* v, const float* inverse_mass, std::uint32_t n, double* partials) {
    double sum[4] = {0.0, 0.0, 0.0, 0.0};
    for (std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += gridDim.x * blockDim.x) {
        if (!(inverse_mass[i] > 0.0f)) continue;
        const double m = 1.0 / static_cast<double>(inverse_mass[i]);
        for (int c = 0; c < 3; ++c) sum[c] += m * static_cast<double>(v[c * n + i]);
        sum[3] += m;
    }
    __shared__ typename MomentumReduce::TempStorage storage;
    for (int k = 0; k < 4; ++k) {
        const double total = MomentumReduce(storage).Sum(sum[k]);
        if (threadIdx.x == 0) partials[4 * blockIdx.x + k] = total;
        __syncthreads();  // storage is reused by the next sum
    }
}

/// One block: sums[k] = the blocks' partials of sum k, in block order.
__global__ void offset_momentum_finish_kernel(const double* partials, std::uint32_t blocks, double* sums) {
    __shared__ typename MomentumReduce::TempStorage storage;
    for (int k = 0; k < 4; ++k) {
        double acc = 0.0;
        for (std::uint32_t b = threadIdx.x; b < blocks; b += blockDim.x) acc += partials[4 * b + k];
        const double total = MomentumReduce(storage).Sum(acc);
        if (threadIdx.x == 0) sums[k] = total;
        __syncthreads();
    }
}

/// Offset mode: each collision vertex's query radius, 1.5× its move over γ (`move` = x1c − x0c −
/// shift, or `remainder` when given, for the cloth) clamped to [contact, cap]; the largest in
/// `largest` (float bits: non-negative floats order like their bits).
__global__ void offset_radius_kernel(const float* x0c, const float* x1c, const float* remainder, const float* dv_previous,
                                     float h, std::uint32_t n, std::uint32_t vertices, const float* shift,
                                     float relaxation, float contact, float cap, float* radius, std::uint32_t* largest) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= vertices) return;
    float length = 0.0f;
    if (remainder != nullptr) {
        length = i < n ? remainder[i] : 0.0f;
    } else {
        // The predicted move at the start velocity and with the last velocity change repeated; the
        // longer (as the CPU).
        float sq = 0.0f, sq_accelerated = 0.0f;
        for (int c = 0; c < 3; ++c) {
            const float d = x1c[c * vertices + i] - x0c[c * vertices + i] - shift[c];
            const float a = i < n && dv_previous != nullptr ? d + h * dv_previous[c * n + i] : d;
            sq += d * d;
            sq_accelerated += a * a;
        }
        length = sqrtf(fmaxf(sq, sq_accelerated));
    }
    const float r = fminf(fmaxf(1.5f * length / relaxation, contact), cap);
    radius[i] = r;
    atomicMax(largest, __float_as_uint(r));
}

/// Offset mode, a rerun of the detection: the cloth where the truncation left it (x0 + h·v_k), the
/// kinematic vertices at their pose at t + h (x1c).
__global__ void offset_detect_positions_kernel(const float* x0, const float* vk, std::uint32_t n, const float* h,
                                               const float* x1c, std::uint32_t vertices, float* detect) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= vertices) return;
    for (int c = 0; c < 3; ++c)
        detect[c * vertices + i] = i < n ? __fadd_rn(x0[c * n + i], __fmul_rn(*h, vk[c * n + i])) : x1c[c * vertices + i];
}

}  // namespace

void launch_offset_momentum(const float* v, const float* inverse_mass, std::uint32_t n, double* sums, double* partials,
                            cudaStream_t stream) {
    if (n == 0) {
        WEFT_CUDA_CHECK(cudaMemsetAsync(sums, 0, 4 * sizeof(double), stream));
        return;
    }
    const std::uint32_t blocks = std::min(grid_for(n), kOffsetMomentumBlocks);
    offset_momentum_kernel<<<blocks, kBlockSize, 0, stream>>>(v, inverse_mass, n, partials);
    WEFT_CUDA_CHECK_LAUNCH("offset_momentum_kernel");
    offset_momentum_finish_kernel<<<1, kBlockSize, 0, stream>>>(partials, blocks, sums);
    WEFT_CUDA_CHECK_LAUNCH("offset_momentum_finish_kernel");
}

void launch_offset_radius(const float* x0c, const float* x1c, const float* remainder, const float* dv_previous, float h,
                          std::uint32_t n, std::uint32_t vertices, const float* shift, float relaxation, float contact,
                          float cap, float* radius, std::uint32_t* largest, cudaStream_t stream) {
    WEFT_CUDA_CHECK(cudaMemsetAsync(largest, 0, sizeof(std::uint32_t), stream));
    if (vertices == 0) return;
    offset_radius_kernel<<<grid_for(vertices), kBlockSize, 0, stream>>>(
        x0c, x1c, remainder, dv_previous, h, n, vertices, shift, relaxation, contact, cap, radius, largest);
    WEFT_CUDA_CHECK_LAUNCH("offset_radius_kernel");
}

void launch_offset_detect_positions(const float* x0, const float* vk, std::uint32_t n, const float* h, const float* x1c,
                                    std::uint32_t vertices, float* detect, cudaStream_t stream) {
    if (vertices == 0) return;
    offset_detect_positions_kernel<<<grid_for(vertices), kBlockSize, 0, stream>>>(x0, vk, n, h, x1c, vertices, detect);
    WEFT_CUDA_CHECK_LAUNCH("offset_detect_positions_kernel");
}

void launch_collision_predict(const float* x, const float* v, std::uint32_t n, float h, float* x0c, float* x1c,
                              std::uint32_t stride, cudaStream_t stream) {
    if (n == 0) return;
    collision_predict_kernel<<<grid_for(n), kBlockSize, 0, stream>>>(x, v, n, h, x0c, x1c, stride);
    WEFT_CUDA_CHECK_LAUNCH("collision_predict_kernel");
}

void launch_collision_gather(const float* x, std::uint32_t n, float* x1c, std::uint32_t stride, cudaStream_t stream) {
    if (n == 0) return;
    collision_gather_kernel<<<grid_for(n), kBlockSize, 0, stream>>>(x, n, x1c, stride);
    WEFT_CUDA_CHECK_LAUNCH("collision_gather_kernel");
}

void launch_place_kinematic(const float* rest, const std::uint32_t* joints, const float* weights, const float* maps,
                            std::uint32_t count, float* x0c, float* x1c, std::uint32_t stride, float* x1, float* v,
                            cudaStream_t stream) {
    if (count == 0) return;
    place_kinematic_kernel<<<grid_for(count), kBlockSize, 0, stream>>>(rest, joints, weights, maps, count, x0c, x1c,
                                                                        stride, x1, v);
    WEFT_CUDA_CHECK_LAUNCH("place_kinematic_kernel");
}

void launch_collision_scatter(const float* x1c, const float* x0c, const std::uint8_t* outcome, std::uint32_t n,
                              std::uint32_t stride, float inv_h, float* x, float* v, const float* v0,
                              float* dv_previous, cudaStream_t stream) {
    if (n == 0) return;
    collision_scatter_kernel<<<grid_for(n), kBlockSize, 0, stream>>>(x1c, x0c, outcome, n, stride, inv_h, x, v, v0,
                                                                     dv_previous);
    WEFT_CUDA_CHECK_LAUNCH("collision_scatter_kernel");
}

}  // namespace weft::cuda
