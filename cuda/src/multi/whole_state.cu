// The whole model's state on one GPU (multi/whole_state.h).
#include "multi/whole_state.h"

#include "cuda_check.h"
#include "kernels.h"

namespace weft::cuda::multi {
namespace {

__global__ void owned_to_whole_kernel(const float* local, std::uint32_t local_n, std::uint32_t owned, const std::uint32_t* global,
                                      float* whole, std::uint32_t whole_n) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= owned) return;
    const std::uint32_t g = global[i];
    for (std::uint32_t c = 0; c < 3; ++c) whole[c * whole_n + g] = local[c * local_n + i];
}

__global__ void whole_to_local_kernel(const float* whole, std::uint32_t whole_n, const std::uint32_t* global, float* local,
                                      std::uint32_t local_n) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= local_n) return;
    const std::uint32_t g = global[i];
    for (std::uint32_t c = 0; c < 3; ++c) local[c * local_n + i] = whole[c * whole_n + g];
}

}  // namespace

void launch_owned_to_whole(const float* local, std::uint32_t local_n, std::uint32_t owned, const std::uint32_t* global,
                           float* whole, std::uint32_t whole_n, cudaStream_t stream) {
    if (owned == 0) return;
    owned_to_whole_kernel<<<grid_for(owned), kBlockSize, 0, stream>>>(local, local_n, owned, global, whole, whole_n);
    WEFT_CUDA_CHECK_LAUNCH("owned_to_whole_kernel");
}

void launch_whole_to_local(const float* whole, std::uint32_t whole_n, const std::uint32_t* global, float* local,
                           std::uint32_t local_n, cudaStream_t stream) {
    if (local_n == 0) return;
    whole_to_local_kernel<<<grid_for(local_n), kBlockSize, 0, stream>>>(whole, whole_n, global, local, local_n);
    WEFT_CUDA_CHECK_LAUNCH("whole_to_local_kernel");
}

}  // namespace weft::cuda::multi
