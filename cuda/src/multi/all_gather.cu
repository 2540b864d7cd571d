// The all-gather of a replicated array across the parts (multi/all_gather.h).
#include "multi/all_gather.h"

#include <algorithm>
#include <string>

#include "cuda_check.h"
#include "kernels.h"
#include "multi/peer_access.h"
#include "weft/error.h"

namespace weft::cuda::multi {
namespace {

__global__ void copy_run_kernel(const float* from, float* to, std::size_t count) {
    for (std::size_t k = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x; k < count;
         k += static_cast<std::size_t>(gridDim.x) * blockDim.x)
        to[k] = from[k];
}

}  // namespace

AllGather::AllGather(std::span<const int> devices, std::span<const cudaStream_t> streams) {
    if (devices.size() != streams.size())
        throw Error("AllGather: " + std::to_string(devices.size()) + " devices and " + std::to_string(streams.size()) + " streams");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    part_.resize(devices.size());
    for (std::size_t p = 0; p < devices.size(); ++p) {
        Part& part = part_[p];
        part.device = devices[p];
        part.stream = streams[p];
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        WEFT_CUDA_CHECK(cudaStreamCreateWithFlags(&part.side, cudaStreamNonBlocking));
        WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&part.ready, cudaEventDisableTiming));
        WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&part.pushed, cudaEventDisableTiming));
    }
    for (const Part& a : part_)
        for (const Part& b : part_) enable_peer_access(a.device, b.device);
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

AllGather::~AllGather() {
    for (Part& part : part_) {
        if (part.ready != nullptr) cudaEventDestroy(part.ready);
        if (part.pushed != nullptr) cudaEventDestroy(part.pushed);
        if (part.side != nullptr) cudaStreamDestroy(part.side);
    }
}

void AllGather::enqueue(std::span<float* const> arrays, std::span<const std::size_t> begin, std::span<const std::size_t> end) {
    const std::size_t parts = part_.size();
    if (arrays.size() != parts || begin.size() != parts || end.size() != parts)
        throw Error("AllGather::enqueue: " + std::to_string(arrays.size()) + " arrays for " + std::to_string(parts) + " parts");
    if (parts < 2) return;
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    for (Part& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        WEFT_CUDA_CHECK(cudaEventRecord(part.ready, part.stream));
    }
    for (std::size_t p = 0; p < parts; ++p) {
        Part& from = part_[p];
        WEFT_CUDA_CHECK(cudaSetDevice(from.device));
        for (const Part& to : part_) WEFT_CUDA_CHECK(cudaStreamWaitEvent(from.side, to.ready, 0));
        const std::size_t count = end[p] > begin[p] ? end[p] - begin[p] : 0;
        if (count > 0)
            for (std::size_t q = 0; q < parts; ++q) {
                if (q == p) continue;
                const unsigned blocks = std::min(1024u, grid_for(static_cast<std::uint32_t>(std::min<std::size_t>(count, 1u << 30))));
                copy_run_kernel<<<blocks, kBlockSize, 0, from.side>>>(arrays[p] + begin[p], arrays[q] + begin[p], count);
                WEFT_CUDA_CHECK_LAUNCH("copy_run_kernel");
            }
        WEFT_CUDA_CHECK(cudaEventRecord(from.pushed, from.side));
    }
    for (std::size_t q = 0; q < parts; ++q) {
        Part& to = part_[q];
        WEFT_CUDA_CHECK(cudaSetDevice(to.device));
        for (std::size_t p = 0; p < parts; ++p)
            if (p != q) WEFT_CUDA_CHECK(cudaStreamWaitEvent(to.stream, part_[p].pushed, 0));
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

}  // namespace weft::cuda::multi
