#pragma once
/// @file
/// What the impact-zone stage reports, in the same form on the CPU (runtime/src/collision/) and the
/// GPU, and the defaults both use (backend kit; docs/collisions.md, step 4).

#include <cstdint>

#include "weft/stats.h"

namespace weft::collision {

/// CCD separation eta as a fraction of the gap the zones restore (the default of both backends).
inline constexpr double kImpactZoneSeparationRatio = 0.1;
/// Rounds of rigid impact zones before the last resort, freezing (the default of both backends).
inline constexpr int kImpactZoneRigidRounds = 8;
/// Fallback rounds after the rigid ones that freeze zone by zone. Past them every movable vertex not
/// yet carried of each cloth (broad-phase group) that a hit still touches is held at x0 at once:
/// freezing one zone lets the next layer of cloth run into it, one detection per layer, and a float
/// run through a fold took thousands of rounds a substep.
inline constexpr int kImpactZoneFreezeRounds = 4;
/// Fallback rounds at most: past them the substep ends with its hits left (reported unresolved)
/// rather than loop on (carried vertices meeting frozen cloth, one ring a round).
inline constexpr int kImpactZoneMaxFallbackRounds = 64;

/// Outcome and work of one `resolve` call (for CollisionStats).
struct ImpactZoneReport {
    int iterations = 0;                ///< impact-zone rounds run (detection + projection), ≤ max_iterations
    int zones = 0;                     ///< zones at the end (connected groups of constrained movable vertices)
    int max_zone_vertices = 0;         ///< movable vertices of the largest zone
    int constraints = 0;               ///< constraints collected (one per CCD hit)
    int rigid_zones = 0;               ///< zones moving rigidly at the end (the round cap was hit)
    int rigid_rounds = 0;              ///< fallback rounds that applied rigid motion
    int frozen_vertices = 0;           ///< movable vertices held at x0 by the last resort
    int carried_vertices = 0;          ///< frozen vertices carried along by kinematic geometry driving into them
    /// The fallbacks held whole cloths at x0 at once (kImpactZoneFreezeRounds); the vertices frozen
    /// that way belong to no zone.
    bool froze_all = false;
    bool resolved = false;             ///< no collision left at the final detection
    int remaining_hits = 0;            ///< CCD hits at the final detection (0 when resolved)
    int qp_unconverged = 0;            ///< zone projections that reached qp_max_sweeps
    std::int64_t qp_sweeps = 0;        ///< projection sweeps, summed over zone solves
    std::int64_t qp_work = 0;          ///< constraint updates of the projections (≤ qp_max_work)
    bool qp_work_spent = false;        ///< the rounds stopped because qp_max_work was spent
    int detections = 0;                ///< broad phase + CCD passes over the whole mesh
    /// Of those, the first detections that reused the proximity detection's pairs (the CPU:
    /// ImpactZoneInput::earlier_broad_phase).
    int detections_from_earlier_pairs = 0;
    std::int64_t candidate_pairs = 0;  ///< broad-phase pairs, summed over detections
    std::int64_t ccd_tests = 0;        ///< CCD queries run (pairs with a movable vertex), summed
    std::int64_t ccd_hits = 0;         ///< of those, reported as colliding, summed
    double eta = 0.0;                  ///< CCD separation used, m
    double broad_phase_ms = 0.0;       ///< wall time in the broad phase, ms
    double ccd_ms = 0.0;               ///< wall time in CCD and constraint building, ms
    double zones_ms = 0.0;             ///< wall time in zone building, projections and fallbacks, ms
};

/// What happened to each vertex in the last `resolve` call.
enum class VertexOutcome : std::uint8_t {
    Fixed,      ///< inverse mass 0: never moved
    Untouched,  ///< in no zone: x1 kept bit for bit
    Projected,  ///< in a zone solved by the inelastic projection
    Rigid,      ///< in a zone moved rigidly (fallback)
    Frozen,     ///< held at x0 (last resort)
    Carried,    ///< frozen, then moved with the kinematic geometry that drove into it (last resort)
};

/// Zone label of a vertex in no zone.
inline constexpr std::uint32_t kNoZone = 0xFFFFFFFFu;

/// Adds a `resolve` report to the step's collision statistics and stage times (both backends).
void add_to_stats(const ImpactZoneReport& report, StepStats& stats);

}  // namespace weft::collision
