// Whole-size copies of the vectors contacts read, on every part's GPU (multi/contact_mirror.h).
#include "multi/contact_mirror.h"

#include <algorithm>
#include <string>

#include "cuda_check.h"
#include "kernels.h"
#include "multi/peer_access.h"
#include "weft/error.h"

namespace weft::cuda::multi {
namespace {

/// Rows with a non-empty incidence, appended in any order (each is pushed to its own place, so the
/// order changes no value); the count lives after the list.
__global__ void list_kernel(const std::uint32_t* start, std::uint32_t owned, std::uint32_t* list) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= owned || start[i + 1] == start[i]) return;
    list[atomicAdd(&list[owned], 1u)] = i;
}

__global__ void push_kernel(const float* from, std::uint32_t stride, const std::uint32_t* list, std::uint32_t owned,
                            const std::uint32_t* global, float* to, std::uint32_t whole) {
    const std::uint32_t count = list[owned];
    for (std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x; k < count; k += gridDim.x * blockDim.x) {
        const std::uint32_t i = list[k], g = global[i];
        for (std::uint32_t c = 0; c < 3; ++c) to[c * whole + g] = from[c * stride + i];
    }
}

}  // namespace

ContactMirror::ContactMirror(std::span<const int> devices, std::span<const cudaStream_t> streams,
                             std::span<const std::uint32_t* const> global_of_owned, std::span<const std::uint32_t> owned,
                             std::uint32_t whole)
    : whole_(whole) {
    const std::size_t parts = devices.size();
    if (streams.size() != parts || global_of_owned.size() != parts || owned.size() != parts)
        throw Error("ContactMirror: " + std::to_string(parts) + " devices, " + std::to_string(streams.size()) + " streams, " +
                    std::to_string(global_of_owned.size()) + " index lists");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    part_.resize(parts);
    for (std::size_t p = 0; p < parts; ++p) {
        Part& part = part_[p];
        part.device = devices[p];
        part.stream = streams[p];
        part.global = global_of_owned[p];
        part.owned = owned[p];
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        WEFT_CUDA_CHECK(cudaStreamCreateWithFlags(&part.side, cudaStreamNonBlocking));
        WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&part.ready, cudaEventDisableTiming));
        WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&part.pushed, cudaEventDisableTiming));
        part.copies.allocate(std::size_t{kVectors} * 3 * whole, ledger_, "contact mirrors");
        part.copies.zero(part.stream);
        part.list.allocate(std::size_t{part.owned} + 1, ledger_, "contact mirrors");
        part.list.zero(part.stream);
    }
    for (const Part& a : part_)
        for (const Part& b : part_) enable_peer_access(a.device, b.device);
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

ContactMirror::~ContactMirror() {
    for (Part& part : part_) {
        if (part.ready != nullptr) cudaEventDestroy(part.ready);
        if (part.pushed != nullptr) cudaEventDestroy(part.pushed);
        if (part.side != nullptr) cudaStreamDestroy(part.side);
    }
}

float* ContactMirror::copy(std::size_t p, Vector which) const {
    return part_.at(p).copies.get() + static_cast<std::size_t>(which) * 3 * whole_;
}

void ContactMirror::list_contact_vertices(std::span<const std::uint32_t* const> start) {
    if (start.size() != part_.size())
        throw Error("ContactMirror::list_contact_vertices: " + std::to_string(start.size()) + " incidences for " +
                    std::to_string(part_.size()) + " parts");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    for (std::size_t p = 0; p < part_.size(); ++p) {
        Part& part = part_[p];
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        WEFT_CUDA_CHECK(cudaMemsetAsync(part.list.get() + part.owned, 0, sizeof(std::uint32_t), part.stream));
        if (part.owned == 0) continue;
        list_kernel<<<grid_for(part.owned), kBlockSize, 0, part.stream>>>(start[p], part.owned, part.list.get());
        WEFT_CUDA_CHECK_LAUNCH("contact mirror list_kernel");
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

void ContactMirror::push(Vector which, std::span<const float* const> vectors, std::span<const std::uint32_t> stride) {
    const std::size_t parts = part_.size();
    if (vectors.size() != parts || stride.size() != parts)
        throw Error("ContactMirror::push: " + std::to_string(vectors.size()) + " vectors for " + std::to_string(parts) + " parts");
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
        const unsigned blocks = std::max(1u, std::min(1024u, grid_for(from.owned)));
        for (std::size_t q = 0; q < parts; ++q) {
            push_kernel<<<blocks, kBlockSize, 0, from.side>>>(vectors[p], stride[p], from.list.get(), from.owned, from.global,
                                                             copy(q, which), whole_);
            WEFT_CUDA_CHECK_LAUNCH("contact mirror push_kernel");
        }
        WEFT_CUDA_CHECK(cudaEventRecord(from.pushed, from.side));
    }
    for (std::size_t q = 0; q < parts; ++q) {
        Part& to = part_[q];
        WEFT_CUDA_CHECK(cudaSetDevice(to.device));
        for (std::size_t p = 0; p < parts; ++p) WEFT_CUDA_CHECK(cudaStreamWaitEvent(to.stream, part_[p].pushed, 0));
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

}  // namespace weft::cuda::multi
