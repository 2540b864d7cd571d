// Impact zones: after `resolve`, a brute-force CCD sweep over every vertex–face and edge–edge pair
// (not the broad phase) finds nothing at eta and the exact intersection check finds nothing, on a
// vertex through a triangle, an edge through an edge, two sheets driven through each other, a sheet
// pushed through a fixed mesh and a crumpled sheet; the projection's answer on the single contacts
// against the closed form; fixed vertices never move and untouched ones keep x1 bit for bit; the
// fallbacks (rigid zones, freezing, carrying by a kinematic mesh) end clean and are counted; rigid
// zones keep their linear momentum and shape; the result is the same on any thread count.
#include <gtest/gtest.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <random>
#include <vector>

#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/physics/ccd.h"

#include "collision/broad_phase.h"
#include "collision/impact_zones.h"
#include "collision/intersection_check.h"
#include "impact_zone_scenes.h"

namespace weft::collision {
namespace {

using test::brute_force_ccd;
using test::Collisions;
using test::crumpled_sheet;
using test::Scene;
using test::two_sheets;
using test::expect_clean;
using test::momentum;
using test::print;
using test::Resolved;
using test::same_bits;

// ---- Checks ----------------------------------------------------------------------------------------

/// The CPU reference on the scene (shared with the GPU test as test::resolve_cpu).
Resolved resolve(const Scene& s, int max_iterations = 32, ImpactZoneSolver* reuse = nullptr) {
    return test::resolve_cpu(s, max_iterations, reuse);
}

/// The scene is a real test: x0 clean and separated, the motion colliding, and x1 intersecting unless
/// the surfaces pass through each other completely (tunnelling, which only CCD sees).
void expect_meaningful(const Scene& s, bool x1_intersects = true) {
    EXPECT_TRUE(check_intersections(s.x0, s.triangles).clean()) << "x0 must be free of intersections";
    EXPECT_EQ(brute_force_ccd(s, s.x0, s.eta()).total(), 0U) << "x0 → x0 must be collision free";
    EXPECT_GT(brute_force_ccd(s, s.x1, s.eta()).total(), 0U) << "x0 → x1 must collide";
    EXPECT_EQ(check_intersections(s.x1, s.triangles).clean(), !x1_intersects) << "x1 intersecting";
}

/// Vertices of `points` that lie over a triangle of `surface` in the horizontal (x, z) projection of
/// the positions `x` but on the wrong side of it: below it when `above` (else above it).
std::size_t wrong_side(const std::vector<Vec3d>& x, const std::vector<std::uint32_t>& points,
                       std::span<const Triangle> surface, bool above) {
    std::size_t wrong = 0;
    for (std::uint32_t p : points) {
        for (const Triangle& t : surface) {
            const Vec3d a = x[t.v[0]], b = x[t.v[1]], c = x[t.v[2]], q = x[p];
            const double det = (b.x - a.x) * (c.z - a.z) - (c.x - a.x) * (b.z - a.z);
            if (std::fabs(det) < 1e-12) continue;
            const double u = ((q.x - a.x) * (c.z - a.z) - (c.x - a.x) * (q.z - a.z)) / det;
            const double v = ((b.x - a.x) * (q.z - a.z) - (q.x - a.x) * (b.z - a.z)) / det;
            if (u < 0.0 || v < 0.0 || u + v > 1.0) continue;
            const double y = a.y + u * (b.y - a.y) + v * (c.y - a.y);
            wrong += (above ? q.y < y : q.y > y) ? 1 : 0;
            break;
        }
    }
    return wrong;
}


// ---- Single contacts, against the closed form ------------------------------------------------------------

TEST(ImpactZones, VertexDrivenHeadOnThroughTriangle) {
    // Triangle A in the plane y = 0 with its centroid at the origin; the tip p of a vertical dart
    // goes from 1 cm above the centroid to 1 cm below; all masses 1 kg. The one constraint is
    // p_y − (a_y + b_y + c_y)/3 ≥ δ, violated by δ + 1 cm at the prediction; with weights
    // (1, −⅓, −⅓, −⅓) and equal masses the closest feasible point moves p up by ¾ of that and each
    // corner down by ¼ (x = x̂ + M⁻¹Jᵀλ with λ·(1 + 3·⅑) = violation).
    const auto [s, dart] = test::dart_through_triangle();
    expect_meaningful(s);
    const Resolved r = resolve(s);
    print("vertex through triangle", r);
    expect_clean(s, r);
    const double violation = s.thickness + 0.01;
    const double tol = 1e-4 * s.thickness + 1e-12;
    EXPECT_NEAR(r.x1[dart].y - s.x1[dart].y, 0.75 * violation, tol);
    for (std::uint32_t v = 0; v < 3; ++v) EXPECT_NEAR(r.x1[v].y - s.x1[v].y, -0.25 * violation, tol);
    EXPECT_NEAR(r.x1[dart].x, 0.0, 1e-12);  // the normal is vertical: no sideways push
    EXPECT_EQ(r.outcome[dart + 1], VertexOutcome::Untouched);
    EXPECT_EQ(r.outcome[dart + 2], VertexOutcome::Untouched);
    EXPECT_EQ(r.report.zones, 1);
    EXPECT_EQ(r.report.max_zone_vertices, 4);
    EXPECT_EQ(r.report.rigid_zones, 0);
    EXPECT_EQ(r.report.frozen_vertices, 0);
}

TEST(ImpactZones, EdgeCrossingEdge) {
    // Edge e (along x, y = 0) hangs a vertical triangle below it; edge f (along z, y = +1 cm) carries
    // a vertical triangle above it and drops 2 cm. Weights (½, ½, −½, −½): the four endpoints share
    // the violation δ + 1 cm equally, e down and f up by half of it each.
    Scene s;
    s.add({{-0.05, 0.0, 0.0}, {0.05, 0.0, 0.0}, {0.0, -0.05, 0.0}}, {{{0, 1, 2}}}, 1.0);
    const std::uint32_t top = s.add({{0.0, 0.01, -0.05}, {0.0, 0.01, 0.05}, {0.0, 0.06, 0.0}}, {{{0, 1, 2}}}, 1.0);
    for (std::uint32_t v = top; v < top + 3; ++v) s.x1[v].y -= 0.02;
    expect_meaningful(s);
    const Resolved r = resolve(s);
    print("edge through edge", r);
    expect_clean(s, r);
    const double half = 0.5 * (s.thickness + 0.01), tol = 1e-4 * s.thickness + 1e-12;
    for (std::uint32_t v : {0U, 1U}) EXPECT_NEAR(r.x1[v].y - s.x1[v].y, -half, tol);
    for (std::uint32_t v : {top, top + 1}) EXPECT_NEAR(r.x1[v].y - s.x1[v].y, half, tol);
    EXPECT_EQ(r.outcome[2], VertexOutcome::Untouched);
    EXPECT_EQ(r.outcome[top + 2], VertexOutcome::Untouched);
}

// ---- Sheets --------------------------------------------------------------------------------------------

TEST(ImpactZones, TwoSheetsDrivenThroughEachOther) {
    const Scene s = two_sheets(14, 3);
    expect_meaningful(s, false);  // the sheets swap sides completely
    const Resolved r = resolve(s);
    print("two sheets", r);
    expect_clean(s, r);
    EXPECT_EQ(r.report.rigid_zones, 0);
    EXPECT_EQ(r.report.frozen_vertices, 0);
    EXPECT_EQ(r.report.qp_unconverged, 0);
    // No vertex of inverse mass 0: the constraint impulses are internal (weights sum to zero), so the
    // total momentum of the motion is that of the prediction.
    std::vector<std::uint32_t> all(s.x0.size());
    for (std::uint32_t v = 0; v < all.size(); ++v) all[v] = v;
    const Vec3d p0 = momentum(s, s.x1, all), p1 = momentum(s, r.x1, all);
    EXPECT_NEAR(p1.y, p0.y, 1e-12);
    // The upper sheet stays above the lower one wherever they overlap (the meeting height varies
    // with the local masses), and the lower below the upper.
    const auto cells = static_cast<std::uint32_t>(s.triangles.size() / 2);
    std::vector<std::uint32_t> upper, lower;
    for (std::uint32_t v = 0; v < s.x0.size(); ++v) (s.x0[v].y > 0.0 ? upper : lower).push_back(v);
    const std::span<const Triangle> tris(s.triangles);
    EXPECT_EQ(wrong_side(r.x1, upper, tris.subspan(cells), true), 0U);
    EXPECT_EQ(wrong_side(r.x1, lower, tris.first(cells), false), 0U);
    EXPECT_GT(wrong_side(s.x1, upper, tris.subspan(cells), true), 100U);  // as predicted, they swapped
}

TEST(ImpactZones, SheetPushedThroughFixedMesh) {
    // A 24×24 cloth 30 cm wide falls 1.4 cm into a fixed bumpy patch 10 cm wide (inverse mass 0), to
    // the middle of its bumps. The cloth's rim, far from the patch, falls freely and must keep its x1
    // exactly.
    const test::ClothOnFixedMesh scene = test::sheet_into_bumpy_patch();
    const auto& [s, cloth, fixed] = scene;
    expect_meaningful(s);
    const Resolved r = resolve(s);
    print("sheet through fixed mesh", r);
    expect_clean(s, r);
    EXPECT_EQ(r.report.frozen_vertices, 0);
    const test::FarRim rim = test::far_rim(scene, r);
    EXPECT_GT(rim.far, 100U);
    EXPECT_EQ(rim.untouched, rim.far);
    // The cloth ends above the patch wherever it is over it.
    std::vector<std::uint32_t> cloth_vertices;
    for (std::uint32_t v = cloth; v < fixed; ++v) cloth_vertices.push_back(v);
    const auto patch_triangles = std::span<const Triangle>(s.triangles).subspan(2 * 24 * 24);
    EXPECT_EQ(wrong_side(r.x1, cloth_vertices, patch_triangles, true), 0U);
    EXPECT_GT(wrong_side(s.x1, cloth_vertices, patch_triangles, true), 10U);  // as predicted, it sank in
}

TEST(ImpactZones, CrumplingSheet) {
    const Scene s = crumpled_sheet(22, 7);
    expect_meaningful(s);
    const Resolved r = resolve(s);
    print("crumpled sheet", r);
    expect_clean(s, r);
    EXPECT_GT(r.report.zones, 0);
    EXPECT_EQ(r.report.rigid_zones, 0);  // the projection alone resolves it
    EXPECT_EQ(r.report.frozen_vertices, 0);
}

TEST(ImpactZones, AFirstDetectionReusingTheProximityPairsGivesTheSameBits) {
    // The CPU solver hands the zones the proximity detection's broad phase (bounds grown by the
    // contact thickness around the predicted motion): the first detection reuses its pairs, hashing
    // only the vertices that left those bounds. Everything after must be what hashing gives.
    const Scene s = crumpled_sheet(22, 7);
    std::vector<Vec3d> predicted = s.x1;
    for (std::size_t v = 0; v < predicted.size(); v += 50) predicted[v].y += 3.0 * s.thickness;  // off the prediction
    BroadPhase proximity;
    BroadPhaseResult proximity_pairs;
    BroadPhaseInput pin;
    pin.x0 = s.x0;
    pin.x1 = predicted;
    pin.triangles = s.triangles;
    pin.edges = s.edges;
    pin.triangle_cloth = s.triangle_group;
    pin.thickness = s.thickness;
    proximity.find(pin, proximity_pairs);

    const Resolved plain = resolve(s);
    const Resolved reused = test::resolve_cpu(s, 32, nullptr, kImpactZoneRigidRounds, ImpactZoneInput{}.qp_max_work,
                                              [&](ImpactZoneInput& in) {
                                                  in.earlier_broad_phase = &proximity;
                                                  in.earlier_pairs = &proximity_pairs;
                                              });
    EXPECT_EQ(reused.report.detections_from_earlier_pairs, 1);
    EXPECT_EQ(plain.report.detections_from_earlier_pairs, 0);
    EXPECT_EQ(reused.report.detections, plain.report.detections);
    EXPECT_EQ(reused.report.candidate_pairs, plain.report.candidate_pairs);
    EXPECT_EQ(reused.report.ccd_hits, plain.report.ccd_hits);
    EXPECT_GT(plain.report.zones, 0);
    std::size_t differ = 0;
    for (std::size_t v = 0; v < s.x1.size(); ++v) differ += same_bits(plain.x1[v], reused.x1[v]) ? 0 : 1;
    EXPECT_EQ(differ, 0U);
}

// ---- Fallbacks -----------------------------------------------------------------------------------------

TEST(ImpactZones, RigidFallbackKeepsMomentumAndShape) {
    // One projection round on a hard case, then rigid zones (no vertex of inverse mass 0 here).
    const Scene s = crumpled_sheet(22, 7);
    const Resolved r = resolve(s, 1);
    print("crumpled sheet, 1 round", r);
    expect_clean(s, r);
    EXPECT_EQ(r.report.iterations, 1);
    EXPECT_GT(r.report.rigid_zones, 0);
    EXPECT_GT(r.report.rigid_rounds, 0);
    // Each rigid zone: the momentum of its motion is the prediction's (the projection's impulses
    // were internal, the rigid motion keeps it), and its vertices keep their distances.
    const auto rigid = test::rigid_zones(s, r);
    EXPECT_EQ(static_cast<int>(rigid.size()), r.report.rigid_zones);
    for (const auto& [label, vertices] : rigid) {
        double scale = 0.0;
        for (std::uint32_t v : vertices) scale += (1.0 / s.inverse_mass[v]) * (physics::length(s.x0[v]) + 0.1);
        const Vec3d p_hat = momentum(s, s.x1, vertices), p = momentum(s, r.x1, vertices);
        EXPECT_LE(physics::length(p - p_hat), 1e-13 * scale)
            << "zone " << label << ", " << vertices.size() << " vertices";
        EXPECT_LE(test::largest_distance_change(s, r, vertices), 1e-12) << "zone " << label << " is not rigid";
    }
}

TEST(ImpactZones, FreezingZonesThatTouchFixedVertices) {
    // No projection round: the zones touch the fixed patch, so they cannot move rigidly and are held
    // at x0 instead.
    const Scene s = test::sheet_through_fixed_patch().scene;
    expect_meaningful(s, false);  // the cloth ends below the patch
    const Resolved r = resolve(s, 0);
    print("sheet through fixed mesh, 0 rounds", r);
    expect_clean(s, r);
    EXPECT_EQ(r.report.iterations, 0);
    EXPECT_EQ(r.report.rigid_zones, 0);
    EXPECT_GT(r.report.frozen_vertices, 0);
}

TEST(ImpactZones, AStackFrozenLayerByLayerIsHeldWholeAfterAFewRounds) {
    // 12 sheets falling onto a fixed patch freeze one layer a fallback round; after
    // kImpactZoneFreezeRounds such rounds the rest of the stack (its cloth) is held at x0 at once, so
    // the substep ends after a handful of detections, not one per layer, and clean; a sheet that no
    // hit touches falls on.
    const test::StackScene c = test::falling_stack(12);
    const Scene& s = c.scene;
    expect_meaningful(s, false);
    const Resolved r = test::resolve_cpu(s, 0, nullptr, 0);
    print("stack of 12 frozen", r);
    expect_clean(s, r);
    EXPECT_TRUE(r.report.froze_all);
    EXPECT_EQ(r.report.frozen_vertices, static_cast<int>(c.fixed)) << "every sheet of the stack ends held at x0";
    EXPECT_LE(r.report.detections, kImpactZoneFreezeRounds + 2) << "one detection a layer";
    // Only the cloths a hit touches: the lone sheet falls on, untouched.
    for (std::uint32_t v = c.lone; v < s.x0.size(); ++v) {
        ASSERT_EQ(r.outcome[v], VertexOutcome::Untouched) << "vertex " << v;
        ASSERT_TRUE(test::same_bits(r.x1[v], s.x1[v])) << "vertex " << v;
    }
    // As one cloth (no groups), the lone sheet is held with the stack.
    Scene one = s;
    one.triangle_group.clear();
    const Resolved whole = test::resolve_cpu(one, 0, nullptr, 0);
    expect_clean(one, whole);
    EXPECT_EQ(whole.report.frozen_vertices, static_cast<int>(s.x0.size() - (c.lone - c.fixed)));
    // With the rigid rounds, the same: the zones touch the fixed patch or frozen cloth.
    const Resolved rigid = test::resolve_cpu(s, 0);
    expect_clean(s, rigid);
    EXPECT_LE(rigid.report.detections, kImpactZoneRigidRounds + kImpactZoneFreezeRounds + 2);
}

TEST(ImpactZones, KinematicMeshCarriesFrozenCloth) {
    // A collider plate (inverse mass 0) rises 3 cm through a cloth at rest, with no projection round:
    // the cloth is frozen at x0, the plate still drives into it, so the cloth it meets moves with it.
    const auto [s, cloth, plate, lift] = test::plate_through_cloth();
    expect_meaningful(s, false);  // the plate ends above the cloth
    const Resolved r = resolve(s, 0);
    print("plate through frozen cloth", r);
    expect_clean(s, r);
    EXPECT_GT(r.report.carried_vertices, 0);
    for (std::uint32_t v = cloth; v < plate; ++v) {
        if (r.outcome[v] != VertexOutcome::Carried) continue;
        EXPECT_NEAR(physics::length(r.x1[v] - s.x0[v] - lift), 0.0, 1e-15);
    }
    // With the normal path the plate lifts the cloth instead, by projection alone.
    const Resolved p = resolve(s);
    print("plate through cloth", p);
    expect_clean(s, p);
    EXPECT_EQ(p.report.frozen_vertices, 0);
    EXPECT_EQ(p.report.carried_vertices, 0);
}

// ---- Determinism, options, timing -------------------------------------------------------------------------

TEST(ImpactZones, SameResultOnAnyThreadCount) {
    const Scene s = crumpled_sheet(16, 11);
    tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 4);
    const auto run = [&](int threads, int rounds) {
        Resolved r;
        tbb::task_arena arena(threads);
        arena.execute([&] { r = resolve(s, rounds); });
        return r;
    };
    for (int rounds : {32, 1}) {  // 1: the rigid fallback runs too
        const Resolved one = run(1, rounds);
        for (int threads : {2, 4}) {
            const Resolved many = run(threads, rounds);
            EXPECT_EQ(std::memcmp(one.x1.data(), many.x1.data(), one.x1.size() * sizeof(Vec3d)), 0)
                << threads << " threads, " << rounds << " rounds";
            EXPECT_TRUE(one.outcome == many.outcome);
            EXPECT_TRUE(one.zone == many.zone);
            const ImpactZoneReport &a = one.report, &b = many.report;
            EXPECT_EQ(a.iterations, b.iterations);
            EXPECT_EQ(a.zones, b.zones);
            EXPECT_EQ(a.constraints, b.constraints);
            EXPECT_EQ(a.qp_sweeps, b.qp_sweeps);
            EXPECT_EQ(a.candidate_pairs, b.candidate_pairs);
            EXPECT_EQ(a.ccd_hits, b.ccd_hits);
            EXPECT_EQ(a.rigid_zones, b.rigid_zones);
            EXPECT_EQ(a.frozen_vertices, b.frozen_vertices);
        }
        // A reused solver (warm scratch from another scene) gives the same again.
        ImpactZoneSolver solver;
        (void)resolve(two_sheets(8, 1), 32, &solver);
        const Resolved again = resolve(s, rounds, &solver);
        EXPECT_EQ(std::memcmp(one.x1.data(), again.x1.data(), one.x1.size() * sizeof(Vec3d)), 0);
    }
}

TEST(ImpactZones, AWorkCapSpentHandsTheHitsToTheFallbacksAndEndsClean) {
    // Where no projection can succeed the rounds re-projected a growing zone for up to
    // qp_max_sweeps sweeps each; the work cap stops them and the fallbacks end the substep. Here
    // the projections could succeed (the crumpled sheet in 5 rounds); with a tenth of their work,
    // and with a cap of 1 (no projection at all), the substep must still end clean, through the
    // fallbacks, within the cap, the same on any thread count.
    const Scene s = crumpled_sheet(16, 11);
    const Resolved full = resolve(s);
    expect_clean(s, full);
    EXPECT_FALSE(full.report.qp_work_spent);
    ASSERT_GT(full.report.qp_work, 1000);
    EXPECT_EQ(full.report.rigid_rounds, 0);
    for (const std::int64_t cap : {full.report.qp_work / 10, std::int64_t{1}}) {
        SCOPED_TRACE("cap " + std::to_string(cap));
        const auto run = [&](int threads) {
            Resolved r;
            tbb::task_arena arena(threads);
            arena.execute([&] { r = test::resolve_cpu(s, 32, nullptr, kImpactZoneRigidRounds, cap); });
            return r;
        };
        const Resolved capped = run(1);
        print("crumpled sheet, work capped", capped);
        expect_clean(s, capped);
        test::expect_work_capped(capped.report, full.report, cap);
        const Resolved two = run(2);
        EXPECT_EQ(std::memcmp(capped.x1.data(), two.x1.data(), capped.x1.size() * sizeof(Vec3d)), 0);
        EXPECT_EQ(capped.report.qp_work, two.report.qp_work);
    }
}

TEST(ImpactZones, NothingToDoLeavesEverythingAlone) {
    // Two sheets 2 cm apart moving in parallel (and an empty scene): one detection, no zone, x1 kept.
    Scene s = two_sheets(6, 2);
    for (std::size_t v = 0; v < s.x0.size(); ++v) s.x1[v] = s.x0[v] + Vec3d{0.003, -0.004, 0.001};
    const Resolved r = resolve(s);
    EXPECT_TRUE(r.report.resolved);
    EXPECT_EQ(r.report.detections, 1);
    EXPECT_EQ(r.report.iterations, 0);
    EXPECT_EQ(r.report.zones, 0);
    EXPECT_EQ(r.report.ccd_hits, 0);
    EXPECT_GT(r.report.ccd_tests, 0);  // the sheets' own neighbours are tested
    EXPECT_EQ(std::memcmp(r.x1.data(), s.x1.data(), s.x1.size() * sizeof(Vec3d)), 0);
    for (VertexOutcome o : r.outcome) EXPECT_EQ(o, VertexOutcome::Untouched);
    const Resolved empty = resolve(Scene{});
    EXPECT_TRUE(empty.report.resolved);
    EXPECT_EQ(empty.report.candidate_pairs, 0);
}

TEST(ImpactZones, RejectsBadInput) {
    const Scene s = two_sheets(2, 1);
    std::vector<Vec3d> x1 = s.x1;
    ImpactZoneSolver solver;
    ImpactZoneInput in{.x0 = s.x0,
                       .x1 = x1,
                       .inverse_mass = s.inverse_mass,
                       .triangles = s.triangles,
                       .edges = s.edges,
                       .thickness = 1e-3};
    EXPECT_NO_THROW((void)solver.resolve(in));
    ImpactZoneInput bad = in;
    bad.thickness = 0.0;
    EXPECT_THROW((void)solver.resolve(bad), Error);
    bad = in;
    bad.inverse_mass = std::span<const double>(s.inverse_mass).first(3);
    EXPECT_THROW((void)solver.resolve(bad), Error);
    std::vector<double> negative = s.inverse_mass;
    negative[1] = -1.0;
    bad = in;
    bad.inverse_mass = negative;
    EXPECT_THROW((void)solver.resolve(bad), Error);
    bad = in;
    bad.qp_max_work = 0;
    EXPECT_THROW((void)solver.resolve(bad), Error);
    for (double tolerance : {-1e-6, 1.0, std::nan("")}) {
        bad = in;
        bad.ccd_time_tolerance = tolerance;
        EXPECT_THROW((void)solver.resolve(bad), Error) << tolerance;
    }
}

// Not run by default (about 10 s on 2 cores): --gtest_also_run_disabled_tests.
TEST(ImpactZones, DISABLED_TimingLargerCrumple) {
    // 48×48 cells (4608 triangles). Checked with the exact intersection test only (the brute-force
    // sweep would dominate the test's time); prints the time, asserts none.
    const Scene s = crumpled_sheet(48, 5);
    EXPECT_FALSE(check_intersections(s.x1, s.triangles).clean());
    ImpactZoneSolver solver;
    const Resolved cold = resolve(s, 32, &solver);
    const Resolved warm = resolve(s, 32, &solver);
    print("crumpled 48x48, cold", cold);
    print("crumpled 48x48, warm", warm);
    std::printf("  %zu vertices, %zu triangles, %d threads\n", s.x0.size(), s.triangles.size(),
                tbb::this_task_arena::max_concurrency());
    EXPECT_TRUE(warm.report.resolved);
    EXPECT_TRUE(check_intersections(warm.x1, s.triangles).clean());
    EXPECT_EQ(std::memcmp(cold.x1.data(), warm.x1.data(), cold.x1.size() * sizeof(Vec3d)), 0);
}

}  // namespace
}  // namespace weft::collision
