#pragma once
/// @file
/// The all-gather of a replicated array across the parts (docs/multi-gpu.md): every part holds a
/// whole copy, computes its own run of it, and stores that run into the same place of every other
/// part's copy (peer stores over NVLink; plain stores between parts on one GPU). The multilevel
/// Schwarz preconditioner across GPUs gathers its level 1 this way: the restricted residual every
/// CG iteration, the coupling blocks every Newton iteration.
///
/// Ordered as one round of peer stores (multi/peer_round.h), with no host synchronisation: each push
/// runs on a side stream of its sender after the work enqueued so far on every part's stream (the
/// run is written, the receivers' earlier reads of the copy are done); each part's later work waits
/// for every push.

#include <cuda_runtime_api.h>

#include <cstddef>
#include <span>
#include <vector>

#include "multi/peer_round.h"

namespace weft::cuda::multi {

class AllGather {
public:
    /// Part p on CUDA device `devices[p]`, its work on `streams[p]`. Enables peer access between the
    /// devices; throws weft::Error naming a pair that cannot reach each other.
    AllGather(std::span<const int> devices, std::span<const cudaStream_t> streams);
    AllGather(const AllGather&) = delete;
    AllGather& operator=(const AllGather&) = delete;

    /// Part p's floats [begin[p], end[p]) of arrays[p] into the same floats of every other part's
    /// array (device pointers, one copy per part).
    void enqueue(std::span<float* const> arrays, std::span<const std::size_t> begin, std::span<const std::size_t> end);

private:
    PeerRound round_;
};

}  // namespace weft::cuda::multi
