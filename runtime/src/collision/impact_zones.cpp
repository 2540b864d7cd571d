// Impact zones (Harmon et al. 2008 inelastic projection; Bridson et al. 2002 rigid zones), the CPU
// reference. Everything lives in flat arrays indexed by vertex, candidate, constraint or zone, so that
// each stage maps to a GPU kernel (or a sort) of its own:
//   detect        broad phase kernels (spatial hash), then one CCD thread per candidate writing a
//                 fixed slot, then a stream compaction (prefix sum over the slot states);
//   add_hits      connected components over the constraints' vertices (hooking with atomicMin on the
//                 parent array: the label of a set is its smallest vertex id, so the labels do not
//                 depend on the order the hooks land in);
//   build_zones   two sorts by zone label (vertices, constraints) and the segment offsets;
//   project_zone  one warp or block per zone, the constraints of a zone visited in the fixed order of
//                 the CPU (the determinism contract; a colouring of the constraints into independent
//                 sets would parallelise within a zone but change the order, hence the bits);
//   rigid_zone    segmented reductions per zone (mass, momentum, angular momentum, inertia), then one
//                 thread per vertex;
//   freeze/carry  one thread per vertex / per hit (first hit wins: atomicMin on the hit index).
#include "collision/impact_zones.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "weft/backend/timing.h"
#include "weft/error.h"
#include "weft/physics/ccd.h"
#include "weft/physics/eigen_sym.h"
#include "weft/physics/proximity.h"

#include "deterministic_parallel.h"

namespace weft::collision {
namespace {

/// The largest per-axis gap between the bounding box of points p[0, split) and that of p[split, 4)
/// (a vertex against a triangle: split 1; two edges: split 2): a lower bound of the distance between
/// the two primitives, 0 or negative where the boxes overlap.
double start_boxes_gap(const Vec3d p[4], int split) {
    double gap = -std::numeric_limits<double>::infinity();
    for (int axis = 0; axis < 3; ++axis) {
        double lo_a = p[0][axis], hi_a = p[0][axis], lo_b = p[split][axis], hi_b = p[split][axis];
        for (int k = 1; k < split; ++k) lo_a = std::min(lo_a, p[k][axis]), hi_a = std::max(hi_a, p[k][axis]);
        for (int k = split + 1; k < 4; ++k) lo_b = std::min(lo_b, p[k][axis]), hi_b = std::max(hi_b, p[k][axis]);
        gap = std::max(gap, std::max(lo_b - hi_a, lo_a - hi_b));
    }
    return gap;
}


using Clock = std::chrono::steady_clock;

// Candidate slot states: no movable vertex; unchanged since a miss (not tested again); tested, miss;
// tested, hit.
constexpr std::uint8_t kSkipped = 0, kReused = 1, kMiss = 2, kHit = 3;

// Zone flags, kept on the root of each set and OR-ed when sets merge.
constexpr std::uint8_t kTouchesFixed = 1;  // a constraint of the zone has a vertex of inverse mass 0
constexpr std::uint8_t kIsRigid = 2;       // moved rigidly by the fallback
constexpr std::uint8_t kHasFrozen = 4;     // holds frozen (or carried) vertices

// What a round does to a zone.
constexpr std::uint8_t kNone = 0, kProject = 1, kPending = 2, kRigid = 3, kFreeze = 4;

// A closest-point direction is trusted as the contact normal while the primitives are at least this
// fraction of eta apart at the time of impact; closer, rounding dominates it and the geometric normal
// (triangle normal, edge cross product) is used instead.
constexpr double kNormalFromGapRatio = 1e-3;

// Eigenvalues of the inertia tensor below this fraction of the largest are treated as zero (a zone of
// collinear vertices cannot spin about their line; the pseudo-inverse leaves that axis alone).
constexpr double kInertiaCutoff = 1e-12;

Vec3d lerp(Vec3d a, Vec3d b, double t) { return a + t * (b - a); }

}  // namespace

std::uint32_t ImpactZoneSolver::find(std::uint32_t v) {
    while (parent_[v] != v) {  // path halving
        parent_[v] = parent_[parent_[v]];
        v = parent_[v];
    }
    return v;
}

void ImpactZoneSolver::unite(std::uint32_t a, std::uint32_t b) {
    std::uint32_t ra = find(a), rb = find(b);
    if (ra == rb) return;
    if (rb < ra) std::swap(ra, rb);
    // The smaller id stays the root: a set's label is then its smallest member, whatever the order
    // of the unions (the GPU's hooking order is not fixed).
    parent_[rb] = ra;
    flags_[ra] = static_cast<std::uint8_t>(flags_[ra] | flags_[rb]);
    size_[ra] += size_[rb];
}

// ---- Detection --------------------------------------------------------------------------------------

void ImpactZoneSolver::detect(const ImpactZoneInput& in, ImpactZoneReport& report) {
    const auto t_begin = Clock::now();
    BroadPhaseInput bp = in.broad_phase;
    bp.x0 = in.x0;
    bp.x1 = in.x1;
    bp.triangles = in.triangles;
    bp.edges = in.edges;
    if (bp.triangle_cloth.empty()) bp.triangle_cloth = in.triangle_cloth;
    bp.self_pairs = in.self_pairs;
    // Bounds grown by eta on each side pair primitives within 2·eta per axis: every pair CCD could
    // report at eta, plus its false-positive margin (ccd.h: far below eta), so the stage agrees with
    // a brute-force CCD sweep at eta. eta/2 would be the bare minimum for distances ≤ eta.
    bp.thickness = report.eta;
    if (in.refresh_broad_phase) in.refresh_broad_phase(report.detections, bp);
    // After the first detection only pairs with a vertex that moved (or hit) can hit: the rest were
    // tested and missed, or could not collide, and are not formed again (they would be kReused below).
    if (report.detections > 0) bp.vertex_changed = stale_;
    if (report.detections == 0 && in.earlier_broad_phase != nullptr && in.earlier_pairs != nullptr) {
        if (broad_phase_.find_reusing(*in.earlier_broad_phase, *in.earlier_pairs, bp, pairs_))
            ++report.detections_from_earlier_pairs;
    } else {
        broad_phase_.find(bp, pairs_);
    }
    ++report.detections;
    const std::size_t nvf = pairs_.vf.size(), total = nvf + pairs_.ee.size();
    report.candidate_pairs += static_cast<std::int64_t>(total);
    report.broad_phase_ms += ms_since(t_begin);
    const auto t_ccd = Clock::now();

    slot_state_.resize(total);
    slot_.resize(total);
    const double eta = report.eta;
    const auto im = in.inverse_mass;
    physics::CcdOptions<double> ccd_options;
    if (in.ccd_time_tolerance > 0.0) ccd_options.t_tolerance = in.ccd_time_tolerance;
    parallel_chunks(total, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const bool vf = i < nvf;
            std::uint32_t id[4];
            if (vf) {
                const VertexFacePair& p = pairs_.vf[i];
                const Triangle& t = in.triangles[p.triangle];
                id[0] = p.vertex;
                id[1] = t.v[0];
                id[2] = t.v[1];
                id[3] = t.v[2];
            } else {
                const EdgeEdgePair& p = pairs_.ee[i - nvf];
                id[0] = in.edges[p.a].v[0];
                id[1] = in.edges[p.a].v[1];
                id[2] = in.edges[p.b].v[0];
                id[3] = in.edges[p.b].v[1];
            }
            // Nothing of the pair can move (collider against collider, pinned against pinned).
            if (im[id[0]] == 0.0 && im[id[1]] == 0.0 && im[id[2]] == 0.0 && im[id[3]] == 0.0) {
                slot_state_[i] = kSkipped;
                continue;
            }
            // Same start and end positions as at the last detection, where it missed: CCD is a pure
            // function of them, so it misses again. (A filter in the broad phase may have let the
            // pair through only now; a sound filter culls only pairs that cannot collide, so the
            // pair's unchanged motion stays collision-free.)
            if (stale_[id[0]] == 0 && stale_[id[1]] == 0 && stale_[id[2]] == 0 && stale_[id[3]] == 0) {
                slot_state_[i] = kReused;
                continue;
            }
            Vec3d a0[4], a1[4];
            for (int k = 0; k < 4; ++k) {
                a0[k] = in.x0[id[k]];
                a1[k] = in.x1[id[k]];
            }
            // A pair already within eta at x0 (allowed: x0 is only free of intersections) would be
            // reported at t = 0 by every detection, whatever the zones do to x1. Half its start
            // distance still separates it from any crossing, which is what must not be missed.
            // Only a start distance under 2·eta changes eta_pair, and most candidates start farther
            // apart than that: where the boxes of the two primitives at x0 are already 2·eta apart on
            // some axis (a lower bound of the distance; the margin covers the rounding of both
            // sides), eta_pair is eta and the proximity query is skipped (a sixth of the CPU's time
            // on `layers`). The same eta_pair either way: the same bits.
            const bool far_at_start = start_boxes_gap(a0, vf ? 1 : 2) > 2.0 * eta * (1.0 + 1e-9);
            const double d0 = far_at_start ? 2.0 * eta
                              : vf         ? physics::point_triangle_proximity(a0[0], a0[1], a0[2], a0[3]).distance
                                           : physics::edge_edge_proximity(a0[0], a0[1], a0[2], a0[3]).distance;
            const double eta_pair = std::min(eta, 0.5 * d0);
            const physics::CcdResult<double> r =
                vf ? physics::vertex_face_ccd(a0[0], a0[1], a0[2], a0[3], a1[0], a1[1], a1[2], a1[3], eta_pair, ccd_options)
                   : physics::edge_edge_ccd(a0[0], a0[1], a0[2], a0[3], a1[0], a1[1], a1[2], a1[3], eta_pair, ccd_options);
            if (!r.hit) {
                slot_state_[i] = kMiss;
                continue;
            }
            // The constraint (Harmon et al. 2008): the pair's closest points at the time of impact
            // give the weights, and the direction between them the normal. CCD reports no contact
            // before toi, so the pair is still on the side it started on there, at a distance about
            // eta: the direction is well defined and points the way that separates the pair.
            const double t = r.toi;
            Vec3d xt[4];
            for (int k = 0; k < 4; ++k) xt[k] = lerp(a0[k], a1[k], t);
            Constraint& c = slot_[i];
            double distance = 0.0;
            Vec3d n, geometric;
            if (vf) {
                const auto pr = physics::point_triangle_proximity(xt[0], xt[1], xt[2], xt[3]);
                c.w[0] = 1.0;
                c.w[1] = -(1.0 - pr.u - pr.v);
                c.w[2] = -pr.u;
                c.w[3] = -pr.v;
                n = pr.normal;
                distance = pr.distance;
                geometric = physics::cross(xt[2] - xt[1], xt[3] - xt[1]);
            } else {
                const auto pr = physics::edge_edge_proximity(xt[0], xt[1], xt[2], xt[3]);
                c.w[0] = 1.0 - pr.u;
                c.w[1] = pr.u;
                c.w[2] = -(1.0 - pr.v);
                c.w[3] = -pr.v;
                n = pr.normal;
                distance = pr.distance;
                geometric = physics::cross(xt[1] - xt[0], xt[3] - xt[2]);
            }
            if (!(distance > kNormalFromGapRatio * eta)) {
                // Too close for the gap's direction (a start distance near zero): the triangle normal
                // or the edges' cross product, turned towards the side the pair started on.
                const Vec3d g = physics::normalized(geometric);
                if (physics::length_squared(g) > 0.0) n = g;
                Vec3d f0{};
                for (int k = 0; k < 4; ++k) f0 += c.w[k] * a0[k];
                if (physics::dot(n, f0) < 0.0) n = -n;
            }
            c.n = n;
            c.diag = 0.0;
            for (int k = 0; k < 4; ++k) {
                c.v[k] = id[k];
                c.diag += c.w[k] * c.w[k] * im[id[k]];
            }
            slot_state_[i] = kHit;
        }
    });
    // Compaction in candidate order (the broad phase's sorted order): thread-count free.
    hits_.clear();
    std::int64_t tests = 0;
    for (std::size_t i = 0; i < total; ++i) {
        tests += slot_state_[i] >= kMiss ? 1 : 0;
        if (slot_state_[i] == kHit) hits_.push_back(slot_[i]);
    }
    // From here on only what moves, or what hit, is stale: every vertex of a hit is, so that a pair
    // that collided is always tested again whatever the zones do with it.
    std::fill(stale_.begin(), stale_.end(), std::uint8_t{0});
    for (const Constraint& c : hits_)
        for (std::uint32_t v : c.v) stale_[v] = 1;
    report.ccd_tests += tests;
    report.ccd_hits += static_cast<std::int64_t>(hits_.size());
    report.ccd_ms += ms_since(t_ccd);
}

// ---- Zones ------------------------------------------------------------------------------------------

void ImpactZoneSolver::add_hits(const ImpactZoneInput& in) {
    const auto im = in.inverse_mass;
    for (const Constraint& c : hits_) {
        constraints_.push_back(c);
        lambda_.push_back(0.0);
        // Vertices of inverse mass 0 do not join zones together: they do not move, so two zones
        // touching the same collider vertex stay independent problems.
        std::uint32_t first = kNoZone;
        bool fixed = false;
        for (std::uint32_t v : c.v) {
            if (im[v] == 0.0) {
                fixed = true;
                continue;
            }
            if (member_[v] == 0) {
                member_[v] = 1;
                members_.push_back(v);
                size_[v] = 1;
            }
            if (first == kNoZone) {
                first = v;
            } else {
                unite(first, v);
            }
        }
        // detect() skips pairs with no movable vertex, so `first` is set.
        if (fixed) flags_[find(first)] |= kTouchesFixed;
    }
}

void ImpactZoneSolver::build_zones() {
    std::sort(members_.begin(), members_.end());
    zone_root_.clear();
    // A root is the smallest member of its set, so walking the members in ascending order meets it
    // first: zones come out numbered by their smallest vertex.
    for (std::uint32_t v : members_) {
        const std::uint32_t r = find(v);
        zone_label_[v] = r;
        if (r == v) {
            zone_index_[r] = static_cast<std::uint32_t>(zone_root_.size());
            zone_root_.push_back(r);
        }
    }
    const std::size_t zones = zone_root_.size();
    // Counting sorts (stable): vertices ascending and constraints in detection order within a zone.
    const auto zone_of_constraint = [&](const Constraint& c) {
        for (std::uint32_t v : c.v)
            if (member_[v] != 0) return zone_index_[zone_label_[v]];
        return 0U;  // unreachable: every constraint has a movable vertex
    };
    zone_vbegin_.assign(zones + 1, 0);
    zone_cbegin_.assign(zones + 1, 0);
    for (std::uint32_t v : members_) ++zone_vbegin_[zone_index_[zone_label_[v]] + 1];
    for (const Constraint& c : constraints_) ++zone_cbegin_[zone_of_constraint(c) + 1];
    for (std::size_t z = 0; z < zones; ++z) {
        zone_vbegin_[z + 1] += zone_vbegin_[z];
        zone_cbegin_[z + 1] += zone_cbegin_[z];
    }
    zone_vertices_.resize(members_.size());
    zone_constraints_.resize(constraints_.size());
    cursor_.assign(zone_vbegin_.begin(), zone_vbegin_.end() - 1);
    for (std::uint32_t v : members_) zone_vertices_[cursor_[zone_index_[zone_label_[v]]]++] = v;
    cursor_.assign(zone_cbegin_.begin(), zone_cbegin_.end() - 1);
    for (std::size_t k = 0; k < constraints_.size(); ++k)
        zone_constraints_[cursor_[zone_of_constraint(constraints_[k])]++] = static_cast<std::uint32_t>(k);
    zone_action_.assign(zones, kNone);
    zone_sweeps_.assign(zones, 0);
}

int ImpactZoneSolver::project_zone(const ImpactZoneInput& in, std::size_t z, int max_sweeps) {
    // Harmon et al. 2008, inelastic projection: minimise ½ Σ_i m_i |x_i − x̂_i|² subject to
    // g_k(x) = J_k x − δ ≥ 0, J_k = (w_k1 n_kᵀ, …, w_k4 n_kᵀ). The KKT conditions give
    // x = x̂ + M⁻¹ Jᵀ λ, λ ≥ 0, g(x) ≥ 0, λ_k g_k(x) = 0, and λ maximises the concave dual
    //   −½ λᵀ A λ − λᵀ c,  A = J M⁻¹ Jᵀ,  c = J x̂ − δ,  λ ≥ 0,
    // whose gradient is −g(x(λ)). Dual coordinate ascent (Hildreth 1957; projected Gauss–Seidel on the
    // dual) maximises it exactly in one λ_k at a time,
    //   λ_k ← max(0, λ_k − g_k(x) / A_kk),  then x moves by M⁻¹ J_kᵀ Δλ_k,
    // and x converges (linearly) to the QP's unique minimiser x* whenever the constraints are
    // feasible, also when A is singular, i.e. redundant constraints (Luo & Tseng 1992, coordinate
    // descent on the dual of a strictly convex QP). Stop: the KKT residual (the violation of
    // a constraint without force, |g| of one with force) is ≤ tol for every constraint over a whole
    // sweep. The sweep order is the zone's constraint order (detection order), fixed, so the result
    // does not depend on threads. Multipliers are warm-started from the previous round.
    //
    // Rate: linear, and slow where nearly parallel rows meet (a vertex–face pair and the edge–edge
    // pairs of the same crossing; a cloth vertex over a collider vertex, found both ways round): λ
    // then moves between them by a factor cos²θ per sweep. Two sheets through each other (1,736
    // constraints, 450 vertices) need ~670 sweeps at tol = 1e-2·δ and > 1000 at 1e-3·δ (~250 without
    // the edge–edge rows). MPRGP (Dostál & Schöberl 2005: CG on the free multipliers, gradient-
    // projection expansions) was tried and did no better there: it spent its iterations releasing
    // the redundant rows a few at a time.
    const auto im = in.inverse_mass;
    const double delta = in.thickness;
    const double tol = in.qp_tolerance_ratio * in.thickness;
    const std::size_t vb = zone_vbegin_[z], ve = zone_vbegin_[z + 1];
    const std::size_t cb = zone_cbegin_[z], ce = zone_cbegin_[z + 1];
    const auto apply = [&](const Constraint& c, double dl) {
        for (int k = 0; k < 4; ++k) {
            const std::uint32_t v = c.v[k];
            if (im[v] > 0.0) in.x1[v] += (im[v] * c.w[k] * dl) * c.n;
        }
    };
    for (std::size_t i = vb; i < ve; ++i) in.x1[zone_vertices_[i]] = x_hat_[zone_vertices_[i]];
    for (std::size_t i = cb; i < ce; ++i) {
        const std::uint32_t k = zone_constraints_[i];
        if (lambda_[k] != 0.0) apply(constraints_[k], lambda_[k]);
    }
    for (int sweep = 1; sweep <= max_sweeps; ++sweep) {
        double worst = 0.0;  // largest KKT residual of the sweep, each taken before its update
        for (std::size_t i = cb; i < ce; ++i) {
            const std::uint32_t k = zone_constraints_[i];
            const Constraint& c = constraints_[k];
            if (!(c.diag > 0.0)) continue;  // only weight-0 movable vertices: no say (the fallbacks act)
            Vec3d f{};
            for (int j = 0; j < 4; ++j) f += c.w[j] * in.x1[c.v[j]];
            const double g = physics::dot(c.n, f) - delta;
            const double lambda = lambda_[k];
            worst = std::max(worst, lambda > 0.0 ? std::fabs(g) : std::max(0.0, -g));
            const double next = std::max(0.0, lambda - g / c.diag);
            if (next != lambda) {
                apply(c, next - lambda);
                lambda_[k] = next;
            }
        }
        // Every update of the sweep was at most tol: x is within tol of a KKT point.
        if (worst <= tol) return sweep;
    }
    return -max_sweeps;
}

void ImpactZoneSolver::rigid_zone(const ImpactZoneInput& in, std::size_t z) {
    // Bridson et al. 2002 §7.4: the zone moves as one rigid body with the linear and angular momentum
    // of its vertices' motion, reading the displacement d_i = x1_i − x0_i as h·velocity (h cancels).
    // About the centre of mass c at x0: v = Σ m d / M, L = Σ m r × d, I = Σ m (|r|² 1 − r rᵀ),
    // ω = I⁻¹ L (pseudo-inverse), and x1_i = c + v + R(ω) r_i with R the rotation by |ω| about ω.
    // Only zones with no vertex of inverse mass 0 come here, so every mass is finite.
    const auto im = in.inverse_mass;
    const std::size_t vb = zone_vbegin_[z], ve = zone_vbegin_[z + 1];
    double mass = 0.0;
    Vec3d moment{}, momentum{};
    for (std::size_t i = vb; i < ve; ++i) {
        const std::uint32_t v = zone_vertices_[i];
        const double m = 1.0 / im[v];
        mass += m;
        moment += m * in.x0[v];
        momentum += m * (in.x1[v] - in.x0[v]);
    }
    const Vec3d centre = moment / mass, velocity = momentum / mass;
    Vec3d angular{};
    double inertia[3][3] = {};
    for (std::size_t i = vb; i < ve; ++i) {
        const std::uint32_t v = zone_vertices_[i];
        const double m = 1.0 / im[v];
        const Vec3d r = in.x0[v] - centre;
        angular += m * physics::cross(r, in.x1[v] - in.x0[v]);
        const double rr = physics::dot(r, r);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) inertia[a][b] += m * ((a == b ? rr : 0.0) - r[a] * r[b]);
    }
    double eval[3], evec[3][3];
    physics::eigen_sym<3>(inertia, eval, evec);
    const double largest = std::max(eval[0], std::max(eval[1], eval[2]));
    Vec3d omega{};
    for (int k = 0; k < 3; ++k) {
        if (!(largest > 0.0) || !(eval[k] > kInertiaCutoff * largest)) continue;
        const Vec3d axis{evec[0][k], evec[1][k], evec[2][k]};
        omega += (physics::dot(axis, angular) / eval[k]) * axis;
    }
    const double angle = physics::length(omega);
    const Vec3d axis = angle > 0.0 ? omega / angle : Vec3d{};
    const double cs = std::cos(angle), sn = std::sin(angle);
    for (std::size_t i = vb; i < ve; ++i) {
        const std::uint32_t v = zone_vertices_[i];
        const Vec3d r = in.x0[v] - centre;
        // Rodrigues: R r = r cos θ + (k × r) sin θ + k (k·r)(1 − cos θ); R r − r written out so that a
        // small rotation does not lose the displacement to cancellation against the position.
        const Vec3d turn = (cs - 1.0) * r + sn * physics::cross(axis, r) + ((1.0 - cs) * physics::dot(axis, r)) * axis;
        in.x1[v] = in.x0[v] + (velocity + turn);
    }
}

// ---- Fallbacks ----------------------------------------------------------------------------------------

void ImpactZoneSolver::fallbacks(const ImpactZoneInput& in, ImpactZoneReport& report) {
    const auto im = in.inverse_mass;
    const std::size_t n = in.x0.size();
    const auto stuck = [&](std::uint32_t v) {
        return outcome_[v] == VertexOutcome::Frozen || outcome_[v] == VertexOutcome::Carried;
    };
    for (int round = 0; round < kImpactZoneMaxFallbackRounds; ++round) {
        const auto t_begin = Clock::now();
        // Hits whose movable vertices are all frozen or carried already cannot be helped by moving
        // their zone again: something with inverse mass 0 (a collider) drives into frozen cloth.
        hit_free_.assign(hits_.size(), 0);
        for (std::size_t h = 0; h < hits_.size(); ++h)
            for (std::uint32_t v : hits_[h].v)
                if (im[v] > 0.0 && !stuck(v)) hit_free_[h] = 1;
        const std::size_t first_new = constraints_.size();
        add_hits(in);  // colliding zones merge
        build_zones();
        for (std::size_t h = 0; h < hits_.size(); ++h) {
            if (hit_free_[h] == 0) continue;
            for (std::uint32_t v : constraints_[first_new + h].v)
                if (member_[v] != 0) zone_action_[zone_index_[zone_label_[v]]] = kPending;
        }
        bool progress = false, any_rigid = false;
        for (std::size_t z = 0; z < zone_root_.size(); ++z) {
            if (zone_action_[z] != kPending) continue;
            const std::uint32_t r = zone_root_[z];
            // Rigid while rounds are left, for zones that can move freely (no vertex of inverse
            // mass 0, nothing frozen) and that grew since they were last made rigid: a rigid zone hit
            // again without merging would only repeat the same motion.
            const bool repeat = (flags_[r] & kIsRigid) != 0 && rigid_size_[r] == size_[r];
            const bool can_rigid =
                round < in.max_rigid_rounds && (flags_[r] & (kTouchesFixed | kHasFrozen)) == 0 && !repeat;
            if (can_rigid) {
                zone_action_[z] = kRigid;
                flags_[r] |= kIsRigid;
                rigid_size_[r] = size_[r];
                progress = any_rigid = true;
            } else {
                zone_action_[z] = kFreeze;
                flags_[r] |= kHasFrozen;
            }
        }
        if (any_rigid) ++report.rigid_rounds;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, zone_root_.size(), 1),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t z = range.begin(); z != range.end(); ++z) {
                                  if (zone_action_[z] == kRigid) {
                                      rigid_zone(in, z);
                                      for (std::size_t i = zone_vbegin_[z]; i < zone_vbegin_[z + 1]; ++i) {
                                          outcome_[zone_vertices_[i]] = VertexOutcome::Rigid;
                                          stale_[zone_vertices_[i]] = 1;
                                      }
                                  } else if (zone_action_[z] == kFreeze) {
                                      // Last resort: the zone's movable vertices stay at x0. x0 is
                                      // free of intersections and CCD misses nothing, so frozen
                                      // cloth only collides again with something still moving.
                                      for (std::size_t i = zone_vbegin_[z]; i < zone_vbegin_[z + 1]; ++i) {
                                          const std::uint32_t v = zone_vertices_[i];
                                          if (outcome_[v] == VertexOutcome::Carried) continue;
                                          in.x1[v] = in.x0[v];
                                          outcome_[v] = VertexOutcome::Frozen;
                                          stale_[v] = 1;
                                      }
                                  }
                              }
                          });
        for (std::size_t z = 0; z < zone_root_.size() && !progress; ++z)
            if (zone_action_[z] == kFreeze) progress = true;  // a new zone, or one grown by free vertices
        if (round == in.max_rigid_rounds + kImpactZoneFreezeRounds) {
            // The cloths a hit of this round touches, whole, at x0 (kImpactZoneFreezeRounds). A
            // vertex's cloth is its triangles' broad-phase group (one group when none is given).
            report.froze_all = true;
            std::vector<std::uint32_t> group(n, 0);
            std::uint32_t groups = 1;
            if (!in.triangle_cloth.empty())
                for (std::size_t t = 0; t < in.triangles.size(); ++t)
                    for (const std::uint32_t v : in.triangles[t].v) {
                        group[v] = in.triangle_cloth[t];
                        groups = std::max(groups, group[v] + 1);
                    }
            std::vector<std::uint8_t> hit_group(groups, 0);
            for (const Constraint& h : hits_)
                for (const std::uint32_t v : h.v) hit_group[group[v]] = 1;
            for (std::size_t v = 0; v < n; ++v) {
                if (!(im[v] > 0.0) || stuck(static_cast<std::uint32_t>(v)) || hit_group[group[v]] == 0) continue;
                in.x1[v] = in.x0[v];
                outcome_[v] = VertexOutcome::Frozen;
                stale_[v] = 1;
                progress = true;
            }
        }
        // Kinematic geometry driving into frozen cloth: the frozen vertices of the hit move with the
        // kinematic (or already carried) points of the pair, weighted by the pair's |w| (the
        // barycentric interpolation at the contact), so the pair keeps its start configuration along
        // the whole step. The first hit in detection order wins a vertex.
        for (std::size_t h = 0; h < hits_.size(); ++h) {
            if (hit_free_[h] != 0) continue;
            const Constraint& c = constraints_[first_new + h];
            double weight = 0.0;
            Vec3d carry{};
            for (int k = 0; k < 4; ++k) {
                const std::uint32_t v = c.v[k];
                if (im[v] > 0.0 && outcome_[v] != VertexOutcome::Carried) continue;
                weight += std::fabs(c.w[k]);
                carry += std::fabs(c.w[k]) * (in.x1[v] - in.x0[v]);
            }
            if (!(weight > 0.0)) continue;
            carry = carry / weight;
            for (std::uint32_t v : c.v) {
                if (im[v] == 0.0 || outcome_[v] != VertexOutcome::Frozen) continue;
                in.x1[v] = in.x0[v] + carry;
                outcome_[v] = VertexOutcome::Carried;
                stale_[v] = 1;
                progress = true;
            }
        }
        report.zones_ms += ms_since(t_begin);
        // No move left to try: report what still collides rather than loop.
        if (!progress) return;
        detect(in, report);
        if (hits_.empty()) return;
    }
}

// ---- The rounds ---------------------------------------------------------------------------------------

ImpactZoneReport ImpactZoneSolver::resolve(const ImpactZoneInput& in) {
    const std::size_t n = in.x0.size();
    if (in.x1.size() != n || in.inverse_mass.size() != n)
        throw Error("impact zones: " + std::to_string(n) + " start positions, " + std::to_string(in.x1.size()) +
                    " end positions and " + std::to_string(in.inverse_mass.size()) + " inverse masses");
    if (n >= kNoZone) throw Error("impact zones: more than 2^32 − 1 vertices");
    if (!std::isfinite(in.thickness) || !(in.thickness > 0.0))
        throw Error("impact zones: thickness must be finite and > 0 (got " + std::to_string(in.thickness) + ")");
    if (!(in.separation_ratio > 0.0 && in.separation_ratio < 1.0))
        throw Error("impact zones: separation_ratio must be in (0, 1) (got " + std::to_string(in.separation_ratio) +
                    ")");
    if (in.max_iterations < 0 || in.max_rigid_rounds < 0 || in.qp_max_sweeps < 1 || in.qp_max_work < 1)
        throw Error("impact zones: max_iterations and max_rigid_rounds must be ≥ 0, qp_max_sweeps and qp_max_work ≥ 1");
    if (!std::isfinite(in.qp_tolerance_ratio) || !(in.qp_tolerance_ratio > 0.0))
        throw Error("impact zones: qp_tolerance_ratio must be finite and > 0");
    if (!(in.ccd_time_tolerance >= 0.0 && in.ccd_time_tolerance < 1.0))
        throw Error("impact zones: ccd_time_tolerance must be in [0, 1) (0: the CCD's default), got " +
                    std::to_string(in.ccd_time_tolerance));
    for (std::size_t v = 0; v < n; ++v)
        if (!std::isfinite(in.inverse_mass[v]) || in.inverse_mass[v] < 0.0)
            throw Error("impact zones: inverse mass of vertex " + std::to_string(v) + " is " +
                        std::to_string(in.inverse_mass[v]));

    ImpactZoneReport report;
    // eta: the CCD separation. Below the gap δ = thickness the zones restore (by 1 − ratio of it, room
    // for the primitives' turning between the linearised constraint and the true distance, so a
    // corrected pair is rarely found again) and below the ~thickness the proximity contacts keep at
    // x0; far above CCD's false-positive margin (~1e-6 of the scene's extent in double).
    report.eta = in.separation_ratio * in.thickness;

    x_hat_.assign(in.x1.begin(), in.x1.end());
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), 0U);
    flags_.assign(n, 0);
    size_.assign(n, 0);
    rigid_size_.assign(n, 0);
    member_.assign(n, 0);
    stale_.assign(n, 1);  // the first detection tests every pair
    zone_label_.assign(n, kNoZone);
    zone_index_.resize(n);
    outcome_.resize(n);
    for (std::size_t v = 0; v < n; ++v)
        outcome_[v] = in.inverse_mass[v] == 0.0 ? VertexOutcome::Fixed : VertexOutcome::Untouched;
    members_.clear();
    constraints_.clear();
    lambda_.clear();
    zone_root_.clear();

    detect(in, report);
    while (!hits_.empty() && report.iterations < in.max_iterations) {
        // Not one sweep of every constraint the round could project fits what is left of the work
        // budget (qp_max_work): the fallbacks take the hits.
        if (in.qp_max_work - report.qp_work < static_cast<std::int64_t>(constraints_.size() + hits_.size())) {
            report.qp_work_spent = true;
            break;
        }
        ++report.iterations;
        const auto t_begin = Clock::now();
        const std::size_t first_new = constraints_.size();
        add_hits(in);
        build_zones();
        // Only zones that gained a constraint change; the others keep their converged projection.
        for (std::size_t k = first_new; k < constraints_.size(); ++k)
            for (std::uint32_t v : constraints_[k].v)
                if (member_[v] != 0) zone_action_[zone_index_[zone_label_[v]]] = kProject;
        // The round's sweep cap: what is left of the work budget over the constraints to project (at
        // least one sweep: the check above counted every constraint).
        std::int64_t round_constraints = 0;
        for (std::size_t z = 0; z < zone_root_.size(); ++z)
            if (zone_action_[z] == kProject) round_constraints += static_cast<std::int64_t>(zone_cbegin_[z + 1] - zone_cbegin_[z]);
        const std::int64_t affordable = (in.qp_max_work - report.qp_work) / std::max<std::int64_t>(round_constraints, 1);
        const int max_sweeps = static_cast<int>(std::min<std::int64_t>(in.qp_max_sweeps, std::max<std::int64_t>(affordable, 1)));
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, zone_root_.size(), 1),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t z = range.begin(); z != range.end(); ++z) {
                                  if (zone_action_[z] != kProject) continue;
                                  zone_sweeps_[z] = project_zone(in, z, max_sweeps);
                                  for (std::size_t i = zone_vbegin_[z]; i < zone_vbegin_[z + 1]; ++i) {
                                      outcome_[zone_vertices_[i]] = VertexOutcome::Projected;
                                      stale_[zone_vertices_[i]] = 1;
                                  }
                              }
                          });
        for (std::size_t z = 0; z < zone_root_.size(); ++z) {
            if (zone_action_[z] != kProject) continue;
            report.qp_sweeps += std::abs(zone_sweeps_[z]);
            report.qp_work += std::int64_t{std::abs(zone_sweeps_[z])} * static_cast<std::int64_t>(zone_cbegin_[z + 1] - zone_cbegin_[z]);
            if (zone_sweeps_[z] < 0) ++report.qp_unconverged;
        }
        report.zones_ms += ms_since(t_begin);
        detect(in, report);
    }
    if (!hits_.empty()) fallbacks(in, report);

    report.resolved = hits_.empty();
    report.remaining_hits = static_cast<int>(hits_.size());
    report.constraints = static_cast<int>(constraints_.size());
    report.zones = static_cast<int>(zone_root_.size());
    for (std::uint32_t r : zone_root_) {
        report.max_zone_vertices = std::max(report.max_zone_vertices, static_cast<int>(size_[r]));
        if ((flags_[r] & kIsRigid) != 0 && (flags_[r] & kHasFrozen) == 0) ++report.rigid_zones;
    }
    for (std::size_t v = 0; v < n; ++v) {
        if (outcome_[v] == VertexOutcome::Frozen) ++report.frozen_vertices;
        if (outcome_[v] == VertexOutcome::Carried) ++report.carried_vertices;
    }
    return report;
}

void add_to_stats(const ImpactZoneReport& r, StepStats& stats) {
    CollisionStats& c = stats.collision;
    c.candidate_pairs += r.candidate_pairs;
    c.ccd_tests += r.ccd_tests;
    c.ccd_hits += r.ccd_hits;
    c.impact_zones += r.zones;
    c.impact_iterations = std::max(c.impact_iterations, r.iterations);
    c.rigid_zones += r.rigid_zones;
    c.frozen_vertices += r.frozen_vertices;
    if (r.qp_work_spent) ++c.impact_work_spent;
    if (!r.resolved) ++c.unresolved_substeps;
    c.reused_detections += r.detections_from_earlier_pairs;
    stats.ms(Stage::BroadPhase) += r.broad_phase_ms;
    stats.ms(Stage::Ccd) += r.ccd_ms;
    stats.ms(Stage::ImpactZones) += r.zones_ms;
}

}  // namespace weft::collision
