#pragma once
/// @file
/// Continuous collision detection on the GPU over the broad phase's candidates: one thread per
/// candidate runs weft::physics::vertex_face_ccd / edge_edge_ccd (weft/physics/ccd.h, float: the
/// inclusion-based search with no false negatives for the given float positions) and the hits are
/// compacted in candidate order with their contact data at the time of impact, as the CPU impact
/// zones take them (runtime/src/collision/impact_zones.cpp): the weights and the normal from the
/// closest points at toi, or, too close for that direction, the triangle normal or the edges' cross
/// product turned towards the side the pair started on.
///
/// Per candidate, before the search (both sound, so the no-false-negative guarantee stands):
///   - a pair whose four vertices all have inverse mass 0 is skipped (nothing can move);
///   - a box test: two primitives that come within eta of each other at some t have swept boxes
///     within eta of each other on every axis, tested with the sum rounded up. It removes most
///     candidates when eta is well below the broad phase's thickness (the impact zones use
///     eta = 0.1·thickness), at the cost of a few loads.
/// Optionally (`clamp_to_start_distance`, the impact zones' rule) eta is lowered to half the pair's
/// start distance, so that a pair already within eta at t = 0 is not reported at t = 0 forever.
///
/// Two passes: the search writes hit, toi, bound and eta per candidate; an exclusive sum ranks the
/// hits; a second kernel computes the contact data of the hits only. Deterministic (a pure function
/// per candidate, compaction in order); no host synchronisation in `enqueue`.
///
/// The search is one thread per candidate with its box queue in local memory (2 KiB); candidates
/// that take many iterations hold their warp. Fine for the hit rates of cloth (most candidates are
/// decided by the box test or the first few boxes); a work queue that regroups long searches is
/// the next step if profiles say so.

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "collision/pair_keys.h"
#include "device_array.h"
#include "weft/backend/buffer_trim.h"
#include "weft/physics/ccd.h"

namespace weft::cuda::collision {

struct GpuCcdInput {
    const float* x0 = nullptr;  ///< start of the step, m, structure of arrays (see GpuBroadPhaseInput)
    const float* x1 = nullptr;  ///< end of the step, m
    std::uint32_t vertex_count = 0;
    std::uint32_t stride = 0;                 ///< component stride; 0 means vertex_count
    const float* inverse_mass = nullptr;      ///< optional, per vertex; null: every vertex can move
    const std::uint32_t* triangles = nullptr;  ///< as given to the broad phase
    const std::uint32_t* edges = nullptr;
    float eta = 0.0F;  ///< minimum separation, m (≥ 0)
    /// Lower eta to half the pair's start distance (the impact zones' rule).
    bool clamp_to_start_distance = true;
    float t_tolerance = physics::CcdDefaults<float>::t_tolerance;
    int max_iterations = physics::CcdDefaults<float>::max_iterations;
};

/// One hit (64 bytes).
struct GpuCcdHit {
    std::uint32_t vertex[4];  ///< vertex–face (p, a, b, c); edge–edge (e0, e1, f0, f1)
    float weight[4];          ///< of the closest points at toi, as GpuProximityContact
    float normal[3];          ///< unit, from the second primitive towards the first
    float toi;                ///< conservative time of impact in [0, 1]
    float distance_bound;     ///< CCD's rigorous bound on the distance at its contact time, m
    float eta;                ///< separation used for this pair, m
    std::uint32_t pair;       ///< index of the candidate in the pair list
    std::uint32_t status;     ///< physics::CcdStatus
};
static_assert(sizeof(GpuCcdHit) == 64);

struct GpuCcdCounters {
    std::uint32_t hits = 0;          ///< hits found (more than the capacity after an overflow)
    std::uint32_t candidates = 0;    ///< candidates examined
    std::uint32_t immovable = 0;     ///< skipped: all four vertices fixed
    std::uint32_t box_rejected = 0;  ///< skipped: swept boxes farther apart than eta
    std::uint32_t tests = 0;         ///< CCD searches run
    std::uint32_t conservative = 0;  ///< hits reported conservatively (budget, queue, non-finite)
    std::uint32_t overflow = 0;      ///< 1 when the hit buffer was too small
    std::uint32_t pad_ = 0;
};

class GpuCcd {
public:
    /// `capacity`: initial hit capacity (0: 1/16 of the candidate capacity on first use).
    explicit GpuCcd(std::size_t capacity = 0);

    /// Enqueues the search and the compaction on `stream` over `pairs` (same stream as the broad
    /// phase). Throws weft::Error for missing arrays or a negative eta.
    void enqueue(const GpuCcdInput& in, const GpuPairList& pairs, cudaStream_t stream);
    const GpuCcdCounters& read_back(cudaStream_t stream);
    /// After `read_back`: true (and the hit buffer grown) when the hits did not fit. The search
    /// results are kept: `enqueue_compaction` then writes the hits again without searching again.
    [[nodiscard]] bool needs_rerun();
    /// The compaction of the last `enqueue` again (after `needs_rerun`), with the same arguments.
    void enqueue_compaction(const GpuCcdInput& in, const GpuPairList& pairs, cudaStream_t stream);
    const GpuCcdCounters& find(const GpuCcdInput& in, const GpuPairList& pairs, cudaStream_t stream);

    [[nodiscard]] const GpuCcdHit* hits() const { return hits_.get(); }
    [[nodiscard]] const std::uint32_t* device_count() const;
    void download(std::vector<GpuCcdHit>& out, cudaStream_t stream) const;

    [[nodiscard]] const GpuCcdCounters& counters() const { return *counters_host_.get(); }
    [[nodiscard]] std::size_t capacity() const { return capacity_; }
    [[nodiscard]] int reruns() const { return reruns_; }
    /// Times the hit buffer was cut back after a window that needed far less (buffer_trim.h).
    [[nodiscard]] int trims() const { return trims_; }
    [[nodiscard]] std::size_t memory_bytes() const;

private:
    std::size_t capacity_ = 0;
    int reruns_ = 0;
    CapacityTrim trim_;
    std::size_t trimmed_ = 0;  // the cut capacity for the next search, 0 = none
    int trims_ = 0;
    bool ranked_ = false;  // the flags of the last search have been turned into ranks
    MemoryLedger ledger_;
    DeviceArray<std::uint32_t> position_;  // candidate capacity + 1: hit flags, then their exclusive sum
    DeviceArray<float4> result_;           // per candidate: toi, distance bound, eta, status
    DeviceArray<GpuCcdHit> hits_;
    DeviceArray<GpuCcdCounters> counters_;
    DeviceArray<unsigned char> temp_;
    PinnedArray<GpuCcdCounters> counters_host_;
};

}  // namespace weft::cuda::collision
