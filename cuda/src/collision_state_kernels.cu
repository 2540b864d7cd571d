// Positions of the collision stages (device_collisions.h): the cloth part of the collision-space
// arrays, filled from the solver's state before and after the solve.
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

}  // namespace

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

void launch_collision_scatter(const float* x1c, const float* x0c, const std::uint8_t* outcome, std::uint32_t n,
                              std::uint32_t stride, float inv_h, float* x, float* v, const float* v0,
                              float* dv_previous, cudaStream_t stream) {
    if (n == 0) return;
    collision_scatter_kernel<<<grid_for(n), kBlockSize, 0, stream>>>(x1c, x0c, outcome, n, stride, inv_h, x, v, v0,
                                                                     dv_previous);
    WEFT_CUDA_CHECK_LAUNCH("collision_scatter_kernel");
}

}  // namespace weft::cuda
