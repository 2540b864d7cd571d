// The halo exchange of the multi-GPU solve (multi/halo_exchange.h).
#include "multi/halo_exchange.h"

#include <string>

#include "cuda_check.h"
#include "kernels.h"
#include "multi/peer_access.h"
#include "weft/error.h"

namespace weft::cuda::multi {
namespace {

/// Sender side: value k of the run for one receiver is the sender's owned vertex send[k]; it lands at
/// the receiver's local index `to_first + k`, in each of the three component runs.
__global__ void push_kernel(const float* from, std::uint32_t from_stride, const std::uint32_t* send, std::uint32_t count,
                            float* to, std::uint32_t to_stride, std::uint32_t to_first) {
    const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= count) return;
    const std::uint32_t i = send[k];
    for (std::uint32_t c = 0; c < 3; ++c) to[c * to_stride + to_first + k] = from[c * from_stride + i];
}

}  // namespace

HaloExchange::HaloExchange(const VertexPartition& partition, std::span<const int> devices,
                           std::span<const cudaStream_t> streams) {
    const std::uint32_t parts = partition.parts;
    if (devices.size() != parts || streams.size() != parts || partition.part.size() != parts)
        throw Error("HaloExchange: " + std::to_string(parts) + " parts, " + std::to_string(devices.size()) + " devices and " +
                    std::to_string(streams.size()) + " streams");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    part_.resize(parts);
    for (std::uint32_t p = 0; p < parts; ++p) {
        const PartitionPart& src = partition.part[p];
        Part& part = part_[p];
        part.device = devices[p];
        part.stream = streams[p];
        part.owned = static_cast<std::uint32_t>(src.owned.size());
        part.local = part.owned + static_cast<std::uint32_t>(src.ghosts.size());
        part.send_start = src.send_start;
        part.ghost_start = src.ghost_start;
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        part.send.upload(src.send, ledger_, "halo send lists");
        WEFT_CUDA_CHECK(cudaStreamCreateWithFlags(&part.halo, cudaStreamNonBlocking));
        WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&part.ready, cudaEventDisableTiming));
        WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&part.pushed, cudaEventDisableTiming));
    }
    for (std::uint32_t p = 0; p < parts; ++p)
        for (std::uint32_t q = 0; q < parts; ++q) {
            const std::uint32_t count = part_[p].send_start[q + 1] - part_[p].send_start[q];
            if (count == 0 || part_[p].device == part_[q].device) continue;
            enable_peer_access(part_[p].device, part_[q].device);
            bytes_between_devices_ += 12ULL * count;
        }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

HaloExchange::~HaloExchange() {
    for (Part& part : part_) {
        if (part.ready != nullptr) cudaEventDestroy(part.ready);
        if (part.pushed != nullptr) cudaEventDestroy(part.pushed);
        if (part.halo != nullptr) cudaStreamDestroy(part.halo);
    }
}

void HaloExchange::begin(std::span<float* const> vectors) {
    const std::uint32_t parts = this->parts();
    if (vectors.size() != parts)
        throw Error("HaloExchange::begin: " + std::to_string(vectors.size()) + " vectors for " + std::to_string(parts) + " parts");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    for (Part& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        WEFT_CUDA_CHECK(cudaEventRecord(part.ready, part.stream));
    }
    for (std::uint32_t p = 0; p < parts; ++p) {
        Part& from = part_[p];
        if (from.send.size() == 0) continue;  // sends nothing (its halo stream stays out of a capture)
        WEFT_CUDA_CHECK(cudaSetDevice(from.device));
        WEFT_CUDA_CHECK(cudaStreamWaitEvent(from.halo, from.ready, 0));  // the values to send are written
        for (std::uint32_t q = 0; q < parts; ++q) {
            const std::uint32_t first = from.send_start[q], count = from.send_start[q + 1] - first;
            if (count == 0) continue;
            const Part& to = part_[q];
            WEFT_CUDA_CHECK(cudaStreamWaitEvent(from.halo, to.ready, 0));  // the old ghosts are read
            push_kernel<<<grid_for(count), kBlockSize, 0, from.halo>>>(vectors[p], from.local, from.send.get() + first, count,
                                                                       vectors[q], to.local, to.owned + to.ghost_start[p]);
            WEFT_CUDA_CHECK_LAUNCH("push_kernel");
        }
        WEFT_CUDA_CHECK(cudaEventRecord(from.pushed, from.halo));
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

std::vector<HaloExchange::Route> HaloExchange::routes(std::uint32_t from) const {
    const Part& sender = part_.at(from);
    std::vector<Route> out;
    for (std::uint32_t q = 0; q < parts(); ++q) {
        const std::uint32_t first = sender.send_start[q], count = sender.send_start[q + 1] - first;
        if (q == from || count == 0) continue;
        out.push_back({q, sender.send.get() + first, count, part_[q].owned + part_[q].ghost_start[from]});
    }
    return out;
}

void HaloExchange::finish() {
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    for (std::uint32_t q = 0; q < parts(); ++q) {
        Part& to = part_[q];
        WEFT_CUDA_CHECK(cudaSetDevice(to.device));
        for (std::uint32_t p = 0; p < parts(); ++p)
            if (p != q && to.ghost_start[p + 1] > to.ghost_start[p])
                WEFT_CUDA_CHECK(cudaStreamWaitEvent(to.stream, part_[p].pushed, 0));
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

}  // namespace weft::cuda::multi
