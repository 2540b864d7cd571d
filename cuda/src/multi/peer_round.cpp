// One round of peer stores between the parts (multi/peer_round.h).
#include "multi/peer_round.h"

#include <string>

#include "cuda_check.h"
#include "multi/peer_access.h"
#include "weft/error.h"

namespace weft::cuda::multi {

PeerRound::PeerRound(std::span<const int> devices, std::span<const cudaStream_t> streams) {
    if (devices.size() != streams.size())
        throw Error("PeerRound: " + std::to_string(devices.size()) + " devices and " + std::to_string(streams.size()) + " streams");
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

PeerRound::~PeerRound() {
    for (Part& part : part_) {
        if (part.ready != nullptr) cudaEventDestroy(part.ready);
        if (part.pushed != nullptr) cudaEventDestroy(part.pushed);
        if (part.side != nullptr) cudaStreamDestroy(part.side);
    }
}

void PeerRound::open() {
    for (Part& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        WEFT_CUDA_CHECK(cudaEventRecord(part.ready, part.stream));
    }
    for (Part& from : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(from.device));
        for (const Part& to : part_) WEFT_CUDA_CHECK(cudaStreamWaitEvent(from.side, to.ready, 0));
    }
}

void PeerRound::close() {
    for (Part& from : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(from.device));
        WEFT_CUDA_CHECK(cudaEventRecord(from.pushed, from.side));
    }
    for (Part& to : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(to.device));
        for (const Part& from : part_) WEFT_CUDA_CHECK(cudaStreamWaitEvent(to.stream, from.pushed, 0));
    }
}

}  // namespace weft::cuda::multi
