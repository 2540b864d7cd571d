#pragma once
/// @file
/// Impact zones, the CPU reference of the penetration-handling stage of the collision pipeline
/// (docs/collisions.md step 5; docs/methods.md §7). Given the start positions x0 of a substep (free of
/// intersections) and the solved end positions x1, it changes x1 as little as it can (mass-weighted)
/// so that no vertex–face or edge–edge pair comes within the CCD separation eta anywhere on the
/// straight paths from x0 to x1.
///
/// Rounds (Provot 1997; Bridson, Fedkiw & Anderson 2002; Harmon, Vouga, Tamstorf & Grinspun 2008,
/// "Robust treatment of simultaneous collisions"):
///   1. broad phase over x0 → x1 (collision/broad_phase.h) and conservative CCD on every candidate
///      (weft/physics/ccd.h: no false negatives); no hit: done;
///   2. each hit becomes a linear constraint on the end positions,
///        g_k(x) = n_k · Σ_i w_ki x_i − δ ≥ 0,
///      with the pair's barycentric weights and contact normal at the time of impact;
///   3. constraints accumulate over the call; vertices sharing a constraint form a zone (union–find;
///      vertices with inverse mass 0 never join zones together);
///   4. per zone, the inelastic projection of Harmon et al.: the closest end positions in the
///      mass norm that satisfy all of the zone's constraints, a convex QP solved exactly (to a
///      tolerance) by dual coordinate ascent; zones are solved in parallel;
///   5. repeat to `max_iterations` rounds; then the fallbacks: rigid impact zones (Bridson et al.
///      2002 §7.4) for a few rounds, and last, freezing zones at x0 (frozen cloth that a kinematic
///      collider still drives into is carried along with it).
/// The result is bit-identical on any thread count. Every fallback is counted; what cannot be
/// resolved is reported (`resolved == false`), never hidden.

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "weft/backend/impact_zone_report.h"
#include "weft/stats.h"
#include "weft/types.h"

#include "collision/broad_phase.h"

namespace weft::collision {

/// What `ImpactZoneSolver::resolve` works on. The spans must stay valid for the call only.
struct ImpactZoneInput {
    /// Positions at the start of the substep, m. Assumed free of intersections, and every non-adjacent
    /// pair farther apart than the CCD separation eta (a pair closer than that at x0 is checked with
    /// half its start distance instead, so that it is not reported at t = 0 forever).
    std::span<const Vec3d> x0;
    /// In/out: positions at the end of the substep (same size as x0), m; corrected in place.
    std::span<Vec3d> x1;
    /// Inverse mass per vertex, 1/kg, finite and ≥ 0 (same size as x0). 0: pinned or kinematic (a
    /// collider mesh vertex); such a vertex is never moved and its x1 is the prescribed end position.
    std::span<const double> inverse_mass;
    /// Global vertex ids: cloth and kinematic collider triangles together.
    std::span<const Triangle> triangles;
    /// The unique edges, normally `build_edges(triangles)`.
    std::span<const Edge> edges;
    /// Cloth of each triangle (optional, empty: one cloth); forwarded to the broad phase.
    std::span<const std::uint32_t> triangle_cloth;
    /// Pairs within one cloth (self-collision); false keeps pairs between different cloths (the
    /// `triangle_cloth` groups) only. Forwarded to the broad phase.
    bool self_pairs = true;
    /// Gap δ the zones restore between surfaces along each contact normal, m; finite and > 0. The
    /// proximity contacts of the solve keep surfaces about this far apart.
    double thickness = 0.0;
    /// Impact-zone rounds (detection + projection) before the fallbacks, ≥ 0 (0: straight to them).
    int max_iterations = 32;
    /// Rounds of rigid impact zones before the last resort (freezing), ≥ 0.
    int max_rigid_rounds = kImpactZoneRigidRounds;
    /// CCD separation as a fraction of the thickness, in (0, 1): eta = ratio × thickness (m).
    double separation_ratio = kImpactZoneSeparationRatio;
    /// Cap on the sweeps of one zone's projection (dual coordinate ascent; a sweep updates each of
    /// the zone's constraints once), ≥ 1.
    int qp_max_sweeps = 1000;
    /// Convergence tolerance of the projection as a fraction of the thickness, > 0: a zone is solved
    /// when every constraint is satisfied to within it and every active one is tight to within it.
    /// The default 1 % keeps every corrected gap ≥ 0.99·δ, far above eta, and costs 10–100× fewer
    /// sweeps than 0.1 % on the nearly redundant rows of stacked contacts (see project_zone).
    double qp_tolerance_ratio = 1e-2;
    /// Cap on the projections' work in one `resolve`, in constraint updates (each sweep of a zone
    /// updates its constraints once), summed over every zone and round, ≥ 1. A round's zones get
    /// sweep caps that fit what is left (the same for every zone of the round, so the result does not
    /// depend on threads); when not one sweep of each fits, the rounds stop and the hits left go to
    /// the fallbacks. Why: where no projection can succeed (cloth pinched between two colliders, or
    /// between a collider's own overlapping parts) every round re-projected a growing zone for up to
    /// qp_max_sweeps sweeps, and a substep of a 1,500-triangle cape took minutes.
    std::int64_t qp_max_work = 20'000'000;
    /// The CCD's time tolerance (physics::CcdOptions::t_tolerance), a fraction of the step in
    /// (0, 1); 0: the CCD's default. Larger resolves hits faster and may take near misses within
    /// about eta + this × the pair's motion for hits.
    double ccd_time_tolerance = 0.0;

    // ---- Broad-phase extension point ----------------------------------------------------------------
    /// Template of every broad-phase call: the solver overwrites x0, x1, triangles, edges, self_pairs,
    /// thickness (with eta) and triangle_cloth (when the template's is empty), and forwards every
    /// other field unchanged: cell_size, and the optional per-primitive filters added later (e.g. the
    /// normal-cone ids of docs/methods.md §5). A filter must only cull pairs that cannot collide over
    /// their motion: pairs whose vertices did not move since the last detection are not tested again.
    BroadPhaseInput broad_phase{};
    /// Optional: called before each broad-phase call with the detection's index (0, 1, …) and the
    /// input about to be used (positions already set to x0 and the current x1). A filter that depends
    /// on positions must be refreshed here: the zones change x1 between detections, and a normal cone
    /// bounded over the old motion could cull a pair that now collides.
    std::function<void(int detection, BroadPhaseInput& input)> refresh_broad_phase;
    /// Optional: a broad phase whose last `find` wrote `earlier_pairs` (the proximity detection of
    /// the same substep). The first detection reuses those pairs (`BroadPhase::find_reusing`: the
    /// same pairs, with only the vertices that left the earlier bounds hashed again).
    BroadPhase* earlier_broad_phase = nullptr;
    const BroadPhaseResult* earlier_pairs = nullptr;
};

/// The impact-zone solver. Keeps its scratch (and the broad phase's) between calls, so that a
/// substep does not allocate once sizes have settled; one object per thread of control (`resolve` is
/// not reentrant; it runs its own parallel loops on TBB).
class ImpactZoneSolver {
public:
    /// Corrects `in.x1` in place (see the file comment) and reports. Throws `weft::Error` for
    /// mismatched sizes, out-of-range indices, a negative or non-finite inverse mass, a thickness
    /// that is not finite and > 0, or options out of range.
    ImpactZoneReport resolve(const ImpactZoneInput& in);

    /// Per vertex, what the last `resolve` did to it.
    [[nodiscard]] std::span<const VertexOutcome> outcome() const { return outcome_; }
    /// Per vertex, its zone at the end of the last `resolve`: the smallest vertex id of the zone, or
    /// kNoZone.
    [[nodiscard]] std::span<const std::uint32_t> zone_of_vertex() const { return zone_label_; }

private:
    /// One linear non-penetration constraint g(x) = n · Σ_k w[k] x[v[k]] − δ ≥ 0 on end positions.
    struct Constraint {
        std::uint32_t v[4];  ///< vertex–face {p, a, b, c}; edge–edge {e0, e1, f0, f1}
        double w[4];         ///< weights: {1, −(1−u−v), −u, −v} or {1−u, u, −(1−v), −v}
        Vec3d n;             ///< unit contact normal at the time of impact, towards the side of v[0]
        double diag;         ///< Σ_k w[k]² / m[v[k]] (1/kg): the diagonal of J M⁻¹ Jᵀ
    };

    /// Broad phase + CCD over x0 → x1; fills `hits_` in candidate order.
    void detect(const ImpactZoneInput& in, ImpactZoneReport& report);
    /// Appends `hits_` to the constraints and merges their vertices' zones.
    void add_hits(const ImpactZoneInput& in);
    /// Labels the zones (smallest member id) and lists each zone's vertices and constraints.
    void build_zones();
    /// The inelastic projection of zone z from the predicted positions; returns the iterations used,
    /// negated when it stopped before converging.
    int project_zone(const ImpactZoneInput& in, std::size_t z, int max_sweeps);
    /// The rigid motion of zone z that keeps the linear and angular momentum of its displacement.
    void rigid_zone(const ImpactZoneInput& in, std::size_t z);
    /// Rigid zones, then freezing and carrying, until clean or out of options.
    void fallbacks(const ImpactZoneInput& in, ImpactZoneReport& report);

    std::uint32_t find(std::uint32_t v);
    void unite(std::uint32_t a, std::uint32_t b);

    // ---- Detection scratch ----------------------------------------------------------------------------
    BroadPhase broad_phase_;
    BroadPhaseResult pairs_;
    std::vector<std::uint8_t> slot_state_;  // per candidate: skipped, tested (miss) or hit
    std::vector<Constraint> slot_;          // per candidate: the constraint of a hit
    std::vector<Constraint> hits_;          // hits of the last detection, compacted in candidate order
    // Per vertex: x1 may have changed since the last detection (or the vertex's zone was worked on).
    // A pair none of whose vertices is stale gets the same CCD answer as last time, a miss (a hit
    // would have put its vertices in a zone worked on since), so only stale pairs are tested again.
    std::vector<std::uint8_t> stale_;

    // ---- Zones --------------------------------------------------------------------------------------
    // The predicted end positions (x1 as given), m.
    std::vector<Vec3d> x_hat_;
    // All constraints of the call in detection order, and their multipliers (kg·m), warm-started
    // across rounds.
    std::vector<Constraint> constraints_;
    std::vector<double> lambda_;
    // Union–find over vertices (a root is its set's smallest id), and per root the zone flags (see
    // the .cpp), the member count and the member count when last made rigid.
    std::vector<std::uint32_t> parent_;
    std::vector<std::uint8_t> flags_;
    std::vector<std::uint32_t> size_, rigid_size_;
    // Per vertex: in a zone; the vertices in zones (ascending after build_zones); zone label (root).
    std::vector<std::uint8_t> member_;
    std::vector<std::uint32_t> members_;
    std::vector<std::uint32_t> zone_label_;
    // Zones of the current round: index per root, root per zone, and per zone the offsets (size
    // zones + 1) of its vertices and constraints in the flat lists.
    std::vector<std::uint32_t> zone_index_, zone_root_;
    std::vector<std::size_t> zone_vbegin_, zone_cbegin_;
    std::vector<std::uint32_t> zone_vertices_, zone_constraints_;
    std::vector<std::uint8_t> zone_action_;  // per zone: what this round does to it
    std::vector<int> zone_sweeps_;           // per zone: sweeps of its last projection (< 0: unconverged)
    std::vector<std::uint8_t> hit_free_;     // fallbacks, per hit: has a movable vertex not frozen
    std::vector<std::size_t> cursor_;        // counting-sort scratch
    std::vector<VertexOutcome> outcome_;
};

}  // namespace weft::collision
