#pragma once
/// @file
/// Proximity contacts of the solve on the GPU: weft::collision::find_proximity_contacts
/// (runtime/src/collision/proximity_contacts.h) in float, over the GPU broad phase's sorted
/// candidates. A candidate becomes a contact when its primitives are within the contact thickness at
/// the start of the substep or predicted to be at its end (x0 + h·v0), and something of it can move;
/// normal and weights come from the closest points at the start (weft/physics/proximity.h, the same
/// functions the CPU calls). Stiffness 100·m/h² with m the pair's effective mass, or the override;
/// thickness the larger of the two sides', friction their mean; as on the CPU.
///
/// Order: contacts are compacted in candidate order (flags, an exclusive sum, a scatter), and the
/// candidates are in the broad phase's canonical order, so the list is the CPU's order and the same
/// on every run. Two passes over the candidates: the first decides, the second recomputes the few
/// kept ones and writes them (cheaper than storing a 64-byte contact per candidate).
///
/// Capacity: the contact buffer has a host-side capacity; `read_back` reports the count, and
/// `needs_rerun()` grows the buffer when it was too small (`find` does both). No host
/// synchronisation in `enqueue`; launch sizes depend only on capacities (CUDA-graph friendly).

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "collision/pair_keys.h"
#include "device_array.h"
#include "weft/backend/buffer_trim.h"

namespace weft::cuda::collision {

/// What the proximity kernels read (device pointers, valid until the work is done on the stream).
struct GpuProximityInput {
    const float* x0 = nullptr;  ///< start of the substep, m, structure of arrays (see GpuBroadPhaseInput)
    const float* x1 = nullptr;  ///< predicted end positions, m
    std::uint32_t vertex_count = 0;
    std::uint32_t stride = 0;  ///< component stride; 0 means vertex_count
    const float* inverse_mass = nullptr;  ///< per vertex, 1/kg; 0 for pinned and kinematic vertices
    const float* thickness = nullptr;     ///< per vertex, m
    const float* friction = nullptr;      ///< per vertex, Coulomb coefficient
    const std::uint32_t* triangles = nullptr;  ///< as given to the broad phase
    const std::uint32_t* edges = nullptr;
    /// Rest exclusion, as ProximityInput in runtime/src/collision/proximity_contacts.h: pairs whose
    /// vertices all lie below `rest_count` (the cloth vertices), belong to one cloth and are closer
    /// than rest_exclusion × thickness in the rest positions are no contacts. Null `rest` or a factor
    /// of 0 excludes nothing.
    const float* rest = nullptr;                  ///< rest positions, SoA with stride rest_count, m
    const std::uint32_t* vertex_cloth = nullptr;  ///< owning cloth of each of the rest_count vertices
    std::uint32_t rest_count = 0;
    float rest_exclusion = 0.0F;
    float h = 0.0F;                   ///< substep, s (> 0)
    float thickness_override = 0.0F;  ///< m; > 0 replaces the per-vertex thickness
    float stiffness_override = 0.0F;  ///< N/m; > 0 replaces the 100·m/h² rule
    /// Offset contact, as ProximityInput::offset_bound on the CPU: per vertex its displacement bound
    /// (m, device). Given, a pair is kept when d − (largest bound of the first primitive + largest of
    /// the second) < thickness, d its distance at x0, and is flagged kOffsetContactBit (with
    /// kEdgeEdgeContactBit for an edge–edge pair) in `pair`.
    const float* offset_bound = nullptr;
};

/// One contact (64 bytes): the gap vector g = Σ weight[i]·x[vertex[i]] held along `normal`.
struct GpuProximityContact {
    std::uint32_t vertex[4];
    float weight[4];   ///< vertex–face (1, −(1−u−v), −u, −v); edge–edge (1−a, a, −(1−b), −b)
    float normal[3];   ///< unit, from the second primitive towards the first, at the start
    float gap;         ///< n·g at the start, m
    float thickness;   ///< m
    float stiffness;   ///< N/m
    float friction;
    std::uint32_t pair;  ///< index of the candidate in the pair list
};
static_assert(sizeof(GpuProximityContact) == 64);

struct GpuProximityCounters {
    std::uint32_t contacts = 0;    ///< contacts found (more than the capacity after an overflow)
    std::uint32_t candidates = 0;  ///< candidates examined
    std::uint32_t overflow = 0;    ///< 1 when the contact buffer was too small
    std::uint32_t pad_ = 0;
};

class GpuProximityContacts {
public:
    /// `capacity`: initial contact capacity (0: a quarter of the candidate capacity on first use).
    explicit GpuProximityContacts(std::size_t capacity = 0);

    /// Enqueues both passes on `stream` over `pairs` (from GpuBroadPhase::pairs(), same stream).
    /// Throws weft::Error for missing arrays or h ≤ 0.
    void enqueue(const GpuProximityInput& in, const GpuPairList& pairs, cudaStream_t stream);
    /// Copies the counters to the host and waits (the one synchronisation).
    const GpuProximityCounters& read_back(cudaStream_t stream);
    /// After `read_back`: true (and the buffer grown) when the contacts did not fit; enqueue again.
    [[nodiscard]] bool needs_rerun();
    /// enqueue + read_back, rerun after growing until the contacts fit.
    const GpuProximityCounters& find(const GpuProximityInput& in, const GpuPairList& pairs, cudaStream_t stream);

    /// Device: the contacts [0, counters().contacts) in candidate order.
    [[nodiscard]] const GpuProximityContact* contacts() const { return contacts_.get(); }
    /// Device: the contact count (for kernels that follow on the stream).
    [[nodiscard]] const std::uint32_t* device_count() const;
    /// Downloads the contacts (after `read_back`); synchronises.
    void download(std::vector<GpuProximityContact>& out, cudaStream_t stream) const;

    [[nodiscard]] const GpuProximityCounters& counters() const { return *counters_host_.get(); }
    [[nodiscard]] std::size_t capacity() const { return capacity_; }
    [[nodiscard]] int reruns() const { return reruns_; }
    /// Times the contact buffer was cut back after a window that needed far less (buffer_trim.h).
    [[nodiscard]] int trims() const { return trims_; }
    [[nodiscard]] std::size_t memory_bytes() const;

private:
    std::size_t capacity_ = 0;
    int reruns_ = 0;
    CapacityTrim trim_;
    std::size_t trimmed_ = 0;  // the cut capacity for the next enqueue, 0 = none
    int trims_ = 0;
    MemoryLedger ledger_;
    DeviceArray<std::uint32_t> position_;  // candidate capacity + 1: flags, then their exclusive sum
    DeviceArray<GpuProximityContact> contacts_;
    DeviceArray<GpuProximityCounters> counters_;
    DeviceArray<unsigned char> temp_;
    PinnedArray<GpuProximityCounters> counters_host_;
};

}  // namespace weft::cuda::collision
