// Positions of the collision stages (device_collisions.h): the cloth part of the collision-space
// arrays, filled from the solver's state before and after the solve.
#include "cuda_check.h"
#include "kernels.h"

namespace weft::cuda {
namespace {

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

}  // namespace weft::cuda
