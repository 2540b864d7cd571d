#pragma once
/// @file
/// One round of peer stores between the parts (docs/multi-gpu.md), ordered on the devices with no
/// host synchronisation: `open` starts each part's side stream after the work enqueued so far on
/// every part's stream (the values to send are written, the receivers' earlier reads of what the
/// round overwrites are done); the caller then enqueues its stores on the side streams; `close` makes
/// every part's stream wait for every side stream. The all-gather and the contact mirror are such
/// rounds (the halo exchange waits per receiver and splits begin from finish, so it keeps its own).

#include <cuda_runtime_api.h>

#include <cstddef>
#include <span>
#include <vector>

namespace weft::cuda::multi {

class PeerRound {
public:
    /// Part p on CUDA device `devices[p]`, its work on `streams[p]`. Creates a side stream and two
    /// events per part and enables peer access between the devices (throws weft::Error naming a pair
    /// that cannot reach each other).
    PeerRound(std::span<const int> devices, std::span<const cudaStream_t> streams);
    ~PeerRound();
    PeerRound(const PeerRound&) = delete;
    PeerRound& operator=(const PeerRound&) = delete;

    /// Every side stream after the work enqueued so far on every part's stream. Leaves the current
    /// device changed.
    void open();
    /// Every part's stream after every side stream's work. Leaves the current device changed.
    void close();
    [[nodiscard]] std::size_t parts() const { return part_.size(); }
    [[nodiscard]] int device(std::size_t p) const { return part_[p].device; }
    [[nodiscard]] cudaStream_t side(std::size_t p) const { return part_[p].side; }

private:
    struct Part {
        int device = 0;
        cudaStream_t stream = nullptr, side = nullptr;
        cudaEvent_t ready = nullptr, pushed = nullptr;
    };
    std::vector<Part> part_;
};

}  // namespace weft::cuda::multi
