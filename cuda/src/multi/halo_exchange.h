#pragma once
/// @file
/// The halo exchange of the multi-GPU solve (docs/multi-gpu.md): every part pushes the values of
/// its boundary vertices that other parts read straight into those parts' ghost ranges, with a
/// gather kernel that writes to the receiver's memory (peer access over NVLink between GPUs, plain
/// stores between parts on one GPU, the test mode). No host synchronisation: the pushes run on a
/// halo stream of each part, ordered by events after the work already enqueued on the sender's and
/// the receiver's streams, and each receiver's later work waits for the pushes it needs.
///
/// Pipelined use (P-Cloth's SpMV): `begin`, then the interior rows on the parts' streams (they read
/// owned values only, and run while the pushes travel), then `finish`, then the boundary rows.
///
/// Vectors are a part's local structure-of-arrays float3 (x, y, z runs of `local` values each): its
/// owned vertices, then its ghosts grouped by owner (PartitionPart), so the values from one sender
/// land in one contiguous run per component.

#include <cuda_runtime_api.h>

#include <cstdint>
#include <span>
#include <vector>

#include "device_array.h"
#include "weft/backend/vertex_partition.h"

namespace weft::cuda::multi {

class HaloExchange {
public:
    /// For `partition`, part p on CUDA device `devices[p]` with stream `streams[p]` (several parts
    /// may share a device; then give them distinct streams). Enables peer access between the
    /// devices that exchange; throws weft::Error naming the pair when two devices cannot reach each
    /// other, or when the sizes disagree.
    HaloExchange(const VertexPartition& partition, std::span<const int> devices, std::span<const cudaStream_t> streams);
    ~HaloExchange();
    HaloExchange(const HaloExchange&) = delete;
    HaloExchange& operator=(const HaloExchange&) = delete;

    /// Starts filling every part's ghosts in `vectors[p]` (device pointers, one local vector per
    /// part) from their owners: each push waits for the work enqueued so far on its sender's stream
    /// (the values) and its receiver's stream (earlier reads of the ghosts).
    void begin(std::span<float* const> vectors);
    /// Makes each part's stream wait for the pushes into it (enqueued; no host wait).
    void finish();
    /// begin then finish.
    void exchange(std::span<float* const> vectors) {
        begin(vectors);
        finish();
    }

    /// One run of a part's values that another part reads as ghosts: the sender's owned rows
    /// send[0, count) land at the receiver's local indices [to_first, to_first + count).
    struct Route {
        std::uint32_t to_part = 0;
        const std::uint32_t* send = nullptr;  ///< on the sender's device
        std::uint32_t count = 0;
        std::uint32_t to_first = 0;
    };
    /// The runs part `from` sends (none to itself), for loops that push from inside their own kernels.
    [[nodiscard]] std::vector<Route> routes(std::uint32_t from) const;

    [[nodiscard]] std::uint32_t parts() const { return static_cast<std::uint32_t>(part_.size()); }
    /// Local vertices (owned + ghosts) of part p: the component stride of its vectors.
    [[nodiscard]] std::uint32_t local_count(std::uint32_t p) const { return part_[p].local; }
    /// Bytes one exchange moves between different devices (float3 per ghost whose owner is on
    /// another device).
    [[nodiscard]] std::uint64_t bytes_between_devices() const { return bytes_between_devices_; }
    /// Device memory of the send lists, bytes (all devices).
    [[nodiscard]] std::size_t memory_bytes() const { return ledger_.total(); }

private:
    struct Part {
        int device = 0;
        cudaStream_t stream = nullptr;
        std::uint32_t owned = 0, local = 0;
        std::vector<std::uint32_t> send_start, ghost_start;  // host copies (PartitionPart)
        DeviceArray<std::uint32_t> send;                      // on the part's device
        cudaStream_t halo = nullptr;                          // the pushes this part sends
        cudaEvent_t ready = nullptr, pushed = nullptr;
    };
    std::vector<Part> part_;
    MemoryLedger ledger_;
    std::uint64_t bytes_between_devices_ = 0;
};

}  // namespace weft::cuda::multi
