// The all-gather of a replicated array across the parts (multi/all_gather.h).
#include "multi/all_gather.h"

#include <algorithm>
#include <string>

#include "cuda_check.h"
#include "kernels.h"
#include "weft/error.h"

namespace weft::cuda::multi {
namespace {

__global__ void copy_run_kernel(const float* from, float* to, std::size_t count) {
    for (std::size_t k = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x; k < count;
         k += static_cast<std::size_t>(gridDim.x) * blockDim.x)
        to[k] = from[k];
}

}  // namespace

AllGather::AllGather(std::span<const int> devices, std::span<const cudaStream_t> streams) : round_(devices, streams) {}

void AllGather::enqueue(std::span<float* const> arrays, std::span<const std::size_t> begin, std::span<const std::size_t> end) {
    const std::size_t parts = round_.parts();
    if (arrays.size() != parts || begin.size() != parts || end.size() != parts)
        throw Error("AllGather::enqueue: " + std::to_string(arrays.size()) + " arrays for " + std::to_string(parts) + " parts");
    if (parts < 2) return;
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    round_.open();
    for (std::size_t p = 0; p < parts; ++p) {
        const std::size_t count = end[p] > begin[p] ? end[p] - begin[p] : 0;
        if (count == 0) continue;
        WEFT_CUDA_CHECK(cudaSetDevice(round_.device(p)));
        const unsigned blocks = std::min(1024u, grid_for(static_cast<std::uint32_t>(std::min<std::size_t>(count, 1u << 30))));
        for (std::size_t q = 0; q < parts; ++q) {
            if (q == p) continue;
            copy_run_kernel<<<blocks, kBlockSize, 0, round_.side(p)>>>(arrays[p] + begin[p], arrays[q] + begin[p], count);
            WEFT_CUDA_CHECK_LAUNCH("copy_run_kernel");
        }
    }
    round_.close();
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

}  // namespace weft::cuda::multi
