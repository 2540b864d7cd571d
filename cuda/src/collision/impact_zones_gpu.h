#pragma once
/// @file
/// Impact zones on the GPU: the penetration-handling stage of a CUDA substep. Same contract as the
/// CPU reference, weft::collision::ImpactZoneSolver (runtime/src/collision/impact_zones.h): given the
/// start positions x0 of a substep (free of intersections) and the solved end positions x1, it
/// changes x1 as little as it can (mass-weighted) so that no vertex–face or edge–edge pair comes
/// within the CCD separation eta on the straight paths from x0 to x1; what it cannot resolve within
/// its caps it reports, never hides.
///
/// Rounds, as on the CPU (Provot 1997; Bridson, Fedkiw & Anderson 2002; Harmon, Vouga, Tamstorf &
/// Grinspun 2008, "Robust treatment of simultaneous collisions"), every stage a kernel or a CUB call:
///   1. detection: the GPU broad phase over x0 → x1 with bounds grown by eta, then the GPU CCD
///      (ccd_gpu.h: no false negatives); the hit count is the one value read back per round;
///   2. each hit becomes a linear constraint g_k(x) = n_k · Σ_i w_ki x_i − δ ≥ 0 on the end positions
///      (weights and normal at the time of impact, as GpuCcdHit gives them); constraints accumulate;
///   3. zones: lock-free union–find over the constraints' movable vertices (hooking the larger root
///      under the smaller with atomicCAS, so a zone's label is its smallest vertex whatever order
///      the hooks land in); stable radix sorts by label give each zone its constraints (detection
///      order) and its vertices, and a per-vertex incidence list (constraint order);
///   4. per zone that gained a constraint, one thread block solves Harmon et al.'s inelastic
///      projection, min ½ Σ m |x − x̂|² s.t. g(x) ≥ 0 — the same QP as the CPU — on its dual by
///      projected gradient with a diagonal majoriser and Nesterov momentum (see the .cu: the CPU's
///      projected Gauss–Seidel is sequential within a zone; this is its parallel counterpart and
///      converges to the same unique minimiser);
///   5. after `max_iterations` rounds: rigid impact zones (Bridson et al. 2002 §7.4; one block per
///      zone, reductions in double), then freezing zones at x0, and carrying frozen cloth with the
///      kinematic geometry that drives into it — the CPU's fallbacks, in the same order and with
///      the same rules.
/// Deterministic: labels do not depend on hook order, sorts are stable, every reduction has a fixed
/// order, and the vertex updates are gathers (no floating-point atomics).
///
/// Differences from the CPU reference, each sound: every detection tests every candidate again
/// (the CPU re-tests only pairs with a vertex that moved; a full pass is cheaper than tracking that
/// on the GPU); positions are float (the CPU's are double); within one fallback round a vertex
/// carried by one hit does not yet drive another (the next round sees it).

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "collision/broad_phase_gpu.h"
#include "collision/ccd_gpu.h"
#include "collision/colored_zone_projection.h"
#include "weft/backend/impact_zone_report.h"
#include "device_array.h"
#include "weft/backend/buffer_trim.h"

namespace weft::cuda::collision {

/// What `GpuImpactZones::resolve` works on: device pointers, valid for the call.
struct GpuImpactZoneInput {
    /// Start of the substep, m, structure of arrays with component stride `vertex_count`; free of
    /// intersections.
    const float* x0 = nullptr;
    /// In/out: end of the substep, m, same layout; corrected in place. Vertices of inverse mass 0
    /// (pinned cloth, kinematic mesh vertices) hold their prescribed end positions and never move.
    float* x1 = nullptr;
    std::uint32_t vertex_count = 0;
    const float* inverse_mass = nullptr;  ///< per vertex, 1/kg, finite and ≥ 0
    const std::uint32_t* triangles = nullptr;  ///< 3 ids per triangle, cloth then kinematic
    std::uint32_t triangle_count = 0;
    const std::uint32_t* edges = nullptr;  ///< 2 ids per edge (build_edges order)
    std::uint32_t edge_count = 0;
    const std::uint32_t* triangle_group = nullptr;  ///< broad-phase group per triangle (optional)
    bool self_pairs = true;
    /// Gap δ the zones restore along each contact normal, m; finite and > 0.
    double thickness = 0.0;
    /// CCD separation as a fraction of the thickness, in (0, 1): eta = ratio × thickness.
    double separation_ratio = weft::collision::kImpactZoneSeparationRatio;
    /// The CCD's time tolerance as a fraction of the substep, in [0, 1): hits are resolved to it
    /// (collision.ccd_time_tolerance). 0: the float CCD's default, physics::CcdDefaults<float>.
    double ccd_time_tolerance = 0.0;
    /// Projection rounds before the fallbacks (≥ 0) and fallback rounds of rigid zones (≥ 0).
    int max_iterations = 32;
    int max_rigid_rounds = weft::collision::kImpactZoneRigidRounds;
    /// Cap on the iterations of one zone's projection per round, ≥ 1. Each is a parallel step over the
    /// whole zone; an unconverged zone is detected again next round. The default and the tolerance's
    /// are the cheapest measured on the 200K twist's heaviest frames (docs/results.md) with the same
    /// outcome (intersection-free, about as many rigid zones) as the CPU's 1000 and 1 %.
    int max_sweeps = 200;
    /// Cap on the projections' work in one `resolve`, in constraint updates (a zone's iteration
    /// updates each of its constraints once), summed over zones and rounds, ≥ 1: the CPU's
    /// `qp_max_work` (collision.max_impact_work). A round's zones get an iteration cap that fits what
    /// is left (the same for every zone of the round); when not one iteration of every constraint
    /// fits, the rounds stop and the hits left go to the fallbacks. Why: the game prototype's skirt,
    /// pressed between the legs, spent up to 3.2 s of one substep's rounds on the GPU (docs/results.md).
    std::int64_t max_work = 20'000'000;
    /// Convergence tolerance of a zone's projection as a fraction of the thickness (the CPU's rule:
    /// every constraint satisfied to it, every active one tight to it). 10 % keeps every corrected
    /// gap ≥ 0.9·δ, 9× the CCD separation.
    double tolerance_ratio = 0.1;
    /// Zones of more constraints than this are projected by the whole device (a kernel per phase of
    /// each iteration, ~4 launches) instead of one thread block each, ≥ 1. One 1024-thread block
    /// takes ~70 µs an iteration on 16K constraints (H200), the grid path a few launch latencies.
    std::uint32_t giant_zone_constraints = 4096;
    /// Zones of at most colored_zone_vertices vertices (≤ kColoredZoneVertices) and more than
    /// colored_zone_constraints constraints are projected by projected Gauss–Seidel over colours of
    /// their constraints (collision/colored_zone_projection.h), the CPU's method, one block a zone;
    /// the others by the projected gradient above. Not the default: Gauss–Seidel needs far fewer
    /// rounds on stacked contact (the game prototype's skirt with its rigged runner: 3.7 rounds a
    /// substep against 12.9), but a sweep is a barrier a colour, and on the zones the gradient
    /// solves it is 15–25× slower (docs/results.md, measured on an H200). 0 vertices (the default):
    /// the projected gradient for every zone.
    std::uint32_t colored_zone_vertices = 0;
    std::uint32_t colored_zone_constraints = 0;
    /// Optional: called before each detection with its index and the broad-phase input about to be
    /// used, to attach filters that depend on the motion (normal-cone patch ids over x0 → x1).
    std::function<void(int detection, GpuBroadPhaseInput& input)> refresh_broad_phase;
};

/// The GPU impact-zone solver. Keeps every buffer between calls (grows only); one object per stream
/// of work; use and destroy it with its device current.
class GpuImpactZones {
public:
    GpuImpactZones();
    ~GpuImpactZones();
    GpuImpactZones(const GpuImpactZones&) = delete;
    GpuImpactZones& operator=(const GpuImpactZones&) = delete;

    /// Corrects `in.x1` in place and reports (same fields as the CPU's report; broad_phase_ms and
    /// ccd_ms are the detections' wall times, zones_ms the rest). Synchronises `stream` once per
    /// detection and per round. Throws weft::Error for bad options or missing arrays.
    weft::collision::ImpactZoneReport resolve(const GpuImpactZoneInput& in, cudaStream_t stream);

    /// Per vertex, what the last `resolve` did (weft::collision::VertexOutcome values), on the device.
    [[nodiscard]] const std::uint8_t* outcome() const { return outcome_.get(); }
    /// Downloads the outcome and the zone label (smallest member id, or kNoZone) per vertex.
    void download(std::vector<weft::collision::VertexOutcome>& outcome, std::vector<std::uint32_t>& zone,
                  cudaStream_t stream) const;

    [[nodiscard]] std::size_t memory_bytes() const;
    /// Times its broad phase and CCD grew a buffer to a measured need (collision/grow_and_rerun.h).
    [[nodiscard]] int buffer_growths() const { return broad_.reruns() + ccd_.reruns(); }

    /// Counters the kernels leave on the device (read back once per round).
    struct Counters {
        std::uint32_t fixed_slots = 0;       ///< constraint slots on vertices of inverse mass 0
        std::uint32_t incidence_runs = 0;    ///< distinct vertices in the incidence sort (+1 with fixed slots)
        std::uint32_t zones = 0;             ///< zones (runs of the constraint sort)
        std::uint32_t zone_vertex_runs = 0;  ///< runs of the vertex sort (equals zones)
        std::uint32_t sweeps = 0;            ///< projection iterations this round, summed over zones
        std::uint32_t unconverged = 0;       ///< projections that reached max_sweeps this round
        std::uint32_t progress = 0;          ///< fallbacks: something was made rigid, frozen or carried
        std::uint32_t any_rigid = 0;         ///< fallbacks: a zone was made rigid this round
        std::uint32_t max_zone_vertices = 0;
        std::uint32_t rigid_zones = 0;
        std::uint32_t frozen = 0;
        std::uint32_t carried = 0;
        unsigned long long work = 0;  ///< constraint updates of this round's projections (sweeps × constraints)
    };

    /// About the device bytes a constraint's capacity holds (its vertices, weights, normal and
    /// multipliers, the incidence and zone sorts' slots, the coloured projection's packing).
    static constexpr std::size_t kBytesPerConstraint = 400;
    /// The constraint arrays' capacity (constraints), and how often the trim window cut it back.
    [[nodiscard]] std::size_t constraint_capacity() const { return capacity_; }
    [[nodiscard]] int trims() const { return trims_; }

private:
    /// Frees the per-constraint arrays (capacity 0: the next reserve allocates what it needs).
    void release_constraints();
    /// Broad phase + CCD over x0 → x1 into ccd_; returns the hit count (after any rerun).
    std::uint32_t detect(const GpuImpactZoneInput& in, weft::collision::ImpactZoneReport& report, cudaStream_t stream);
    /// Appends the `hits` CCD hits as constraints, merges zones, and rebuilds the zone lists.
    void add_hits(const GpuImpactZoneInput& in, std::uint32_t hits, cudaStream_t stream);
    void reserve_constraints(std::size_t count, cudaStream_t stream);
    void reserve_vertices(std::uint32_t count);
    const Counters& read_counters(cudaStream_t stream);
    void fallbacks(const GpuImpactZoneInput& in, std::uint32_t hits, weft::collision::ImpactZoneReport& report,
                   cudaStream_t stream);
    /// The coloured projection's view of this call's zones, constraints and scratch.
    ColoredZoneProjection colored_projection(const GpuImpactZoneInput& in);
    /// Projects the zones of more than in.giant_zone_constraints constraints (and more vertices than
    /// the coloured projection takes) that this round marked.
    void project_giant_zones(const GpuImpactZoneInput& in, double tol, int max_sweeps, cudaStream_t stream);

    GpuBroadPhase broad_;
    GpuCcd ccd_;
    std::uint32_t vertices_ = 0;       // capacity of the per-vertex arrays
    std::size_t capacity_ = 0;         // constraint capacity
    CapacityTrim constraint_trim_;     // the constraints each call needed (weft/backend/buffer_trim.h)
    int trims_ = 0;
    std::uint32_t constraints_ = 0;    // constraints of this call
    std::uint32_t zones_ = 0, unique_ = 0;
    std::uint32_t remaining_ = 0;         // hits of the last detection
    std::uint32_t vertices_in_call_ = 0;  // vertex count of the last call
    // Where the sorts left their values (one of the two buffers each).
    const std::uint32_t* slot_sorted_ = nullptr;
    const std::uint32_t* cvalue_sorted_ = nullptr;
    const std::uint32_t* vvalue_sorted_ = nullptr;

    // Per vertex.
    DeviceArray<float> x_hat_;
    DeviceArray<std::uint32_t> parent_, label_, incidence_count_, flags_, rigid_size_, claim_;
    DeviceArray<std::uint8_t> member_, outcome_, action_;
    // Per constraint (and per slot: 4 a constraint).
    DeviceArray<std::uint32_t> c_vertex_;  // 4 per constraint
    DeviceArray<float> c_weight_;          // 4 per constraint
    DeviceArray<float> c_normal_;          // 3 per constraint
    DeviceArray<double> c_scale_, lambda_, momentum_, previous_;
    DeviceArray<std::uint32_t> slot_key_[2], slot_value_[2];  // incidence sort
    DeviceArray<std::uint32_t> unique_vertex_, unique_count_, unique_offset_;
    DeviceArray<std::uint32_t> ckey_[2], cvalue_[2], zone_label_, zone_ccount_, zone_coffset_;
    DeviceArray<std::uint32_t> vkey_[2], vvalue_[2], zone_label2_, zone_vcount_, zone_voffset_;
    DeviceArray<std::uint8_t> hit_free_;  // fallbacks, per hit of the round
    DeviceArray<std::uint32_t> vertex_group_;  // fallbacks' whole-cloth freeze: each vertex's group
    DeviceArray<std::uint8_t> hit_group_;      // and the groups the round's hits touch
    DeviceArray<float> carry_;            // fallbacks, per hit: the displacement it carries frozen cloth by
    // The coloured projection's scratch (collision/colored_zone_projection.h).
    DeviceArray<std::uint32_t> zone_slot_, color_claim_;                // per vertex
    DeviceArray<std::uint32_t> color_, color_order_, color_start_;      // per constraint (+ zones + 1)
    DeviceArray<uint4> packed_slot_;                                    // per constraint, colour order
    DeviceArray<float4> packed_weight_, packed_move_, packed_normal_;
    DeviceArray<double> packed_offset_, packed_inverse_diagonal_, packed_lambda_;
    // Scratch.
    DeviceArray<unsigned char> temp_;
    DeviceArray<double> giant_scratch_;  // the giant-zone iteration's state and per-block partials
    PinnedArray<std::uint32_t> giant_flag_;
    std::vector<std::uint32_t> host_coffset_, host_voffset_, host_label_;
    int multiprocessors_ = 0;
    DeviceArray<Counters> counters_;
    PinnedArray<Counters> counters_host_;
};

}  // namespace weft::cuda::collision
