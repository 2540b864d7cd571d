// GPU impact zones (cuda/src/collision/impact_zones_gpu.h) held to the promises of the CPU reference
// (tests/solver/test_impact_zones.cpp), on the same scenes rounded to float: after `resolve`, a
// brute-force double CCD sweep over every pair finds nothing at eta and the exact intersection check
// finds nothing; fixed vertices never move, untouched ones keep x1 bit for bit, frozen ones sit at x0;
// the fallbacks (rigid zones, freezing, carrying by a kinematic mesh) end clean and are counted, rigid
// zones keep their momentum and shape; the projection lands where the CPU's does (same QP: the
// mass-weighted correction agrees); the same bits on every run. Every test skips without a GPU.
#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "collision/impact_zones.h"
#include "collision/impact_zones_gpu.h"
#include "collision/intersection_check.h"
#include "cuda_check.h"
#include "device_array.h"
#include "float_positions.h"
#include "gpu_test_util.h"
#include "impact_zone_scenes.h"
#include "weft/backend/buffer_trim.h"

namespace weft::collision {
namespace {

using cuda::DeviceArray;
using cuda::MemoryLedger;
using cuda::collision::GpuImpactZoneInput;
using cuda::collision::GpuImpactZones;
using test::brute_force_ccd;
using test::expect_clean;
using test::momentum;
using test::print;
using test::resolve_cpu;
using test::Resolved;
using test::same_bits;
using test::Scene;

/// The scene with every position rounded to float (what the GPU sees), so that the double judges
/// look at exactly the GPU's input.
Scene rounded(Scene s) {
    weft::test::snap_to_float(s);
    return s;
}

Resolved resolve_gpu(const Scene& s, int max_iterations, GpuImpactZones& zones,
                     std::uint32_t giant = GpuImpactZoneInput{}.giant_zone_constraints,
                     std::uint32_t colored = GpuImpactZoneInput{}.colored_zone_vertices,
                     std::int64_t max_work = GpuImpactZoneInput{}.max_work) {
    const std::size_t n = s.x0.size();
    const std::vector<float> x0 = weft::test::soa_floats(s.x0);
    std::vector<float> x1 = weft::test::soa_floats(s.x1), im(n);
    for (std::size_t v = 0; v < n; ++v) im[v] = static_cast<float>(s.inverse_mass[v]);
    std::vector<std::uint32_t> tris, edges;
    for (const Triangle& t : s.triangles) tris.insert(tris.end(), {t.v[0], t.v[1], t.v[2]});
    for (const Edge& e : s.edges) edges.insert(edges.end(), {e.v[0], e.v[1]});
    MemoryLedger ledger;
    DeviceArray<float> d0, d1, dim;
    DeviceArray<std::uint32_t> dt, de, dg;
    d0.upload(x0, ledger, "x0");
    d1.upload(x1, ledger, "x1");
    dim.upload(im, ledger, "inverse mass");
    dt.upload(tris, ledger, "triangles");
    de.upload(edges, ledger, "edges");
    GpuImpactZoneInput in;
    in.x0 = d0.get();
    in.x1 = d1.get();
    in.vertex_count = static_cast<std::uint32_t>(n);
    in.inverse_mass = dim.get();
    in.triangles = dt.get();
    in.triangle_count = static_cast<std::uint32_t>(s.triangles.size());
    in.edges = de.get();
    in.edge_count = static_cast<std::uint32_t>(s.edges.size());
    if (!s.triangle_group.empty()) {
        dg.upload(s.triangle_group, ledger, "triangle groups");
        in.triangle_group = dg.get();
    }
    in.thickness = s.thickness;
    in.max_iterations = max_iterations;
    in.giant_zone_constraints = giant;
    in.colored_zone_vertices = colored;
    in.colored_zone_constraints = 0;  // with `colored` > 0: every zone small enough by colours
    in.max_work = max_work;
    Resolved r;
    r.report = zones.resolve(in, nullptr);
    WEFT_CUDA_CHECK(cudaMemcpy(x1.data(), d1.get(), x1.size() * sizeof(float), cudaMemcpyDeviceToHost));
    r.x1.resize(n);
    for (std::size_t v = 0; v < n; ++v)
        for (int c = 0; c < 3; ++c) r.x1[v][c] = x1[static_cast<std::size_t>(c) * n + v];
    zones.download(r.outcome, r.zone, nullptr);
    return r;
}

Resolved resolve_gpu(const Scene& s, int max_iterations = 32) {
    GpuImpactZones zones;
    return resolve_gpu(s, max_iterations, zones);
}


/// ½ Σ m |x1 − x̂|²: what the inelastic projection minimises.
double correction(const Scene& s, const std::vector<Vec3d>& x1) {
    double e = 0.0;
    for (std::size_t v = 0; v < s.x0.size(); ++v)
        if (s.inverse_mass[v] > 0.0) e += 0.5 / s.inverse_mass[v] * physics::length_squared(x1[v] - s.x1[v]);
    return e;
}


TEST(GpuImpactZones, VertexDrivenHeadOnThroughTriangle) {
    WEFT_REQUIRE_GPU();
    // As the CPU test: the dart's tip p through the centroid of a triangle, all masses 1 kg. The
    // closest feasible point moves p up by ¾ of the violation and each corner down by ¼.
    const test::DartScene scene = test::dart_through_triangle();
    const Scene s = rounded(scene.scene);
    const std::uint32_t dart = scene.dart;
    const Resolved r = resolve_gpu(s);
    print("vertex through triangle", r);
    expect_clean(s, r);
    const double violation = s.thickness + 0.01;
    const double tol = 2e-2 * s.thickness;  // the projection's tolerance, 1 % of δ, and float rounding
    EXPECT_NEAR(r.x1[dart].y - s.x1[dart].y, 0.75 * violation, tol);
    for (std::uint32_t v = 0; v < 3; ++v) EXPECT_NEAR(r.x1[v].y - s.x1[v].y, -0.25 * violation, tol);
}

TEST(GpuImpactZones, TwoSheetsDrivenThroughEachOther) {
    WEFT_REQUIRE_GPU();
    const Scene s = rounded(test::two_sheets(14, 3));
    const Resolved r = resolve_gpu(s);
    print("two sheets (GPU)", r);
    expect_clean(s, r);
    EXPECT_EQ(r.report.rigid_zones, 0);
    EXPECT_EQ(r.report.frozen_vertices, 0);
    EXPECT_EQ(r.report.qp_unconverged, 0);
    // Internal impulses only: the total momentum of the motion is the prediction's (up to float
    // rounding of the positions, ~1e-7 m per vertex).
    std::vector<std::uint32_t> all(s.x0.size());
    for (std::uint32_t v = 0; v < all.size(); ++v) all[v] = v;
    double mass = 0.0;
    for (double im : s.inverse_mass) mass += 1.0 / im;
    EXPECT_NEAR(momentum(s, r.x1, all).y, momentum(s, s.x1, all).y, 1e-6 * mass);
    // Same QP as the CPU: the mass-weighted correction agrees (the constraint sets differ only where
    // float and double CCD disagree at the margin).
    const Resolved cpu = resolve_cpu(s);
    const double e_gpu = correction(s, r.x1), e_cpu = correction(s, cpu.x1);
    std::printf("correction: GPU %.6g, CPU %.6g (ratio %.4f)\n", e_gpu, e_cpu, e_gpu / e_cpu);
    EXPECT_GT(e_gpu, 0.8 * e_cpu);
    EXPECT_LT(e_gpu, 1.25 * e_cpu);
}

TEST(GpuImpactZones, SheetPushedThroughFixedMesh) {
    WEFT_REQUIRE_GPU();
    test::ClothOnFixedMesh scene = test::sheet_into_bumpy_patch();
    scene.scene = rounded(scene.scene);
    const Scene& s = scene.scene;
    const Resolved r = resolve_gpu(s);
    print("sheet through fixed mesh (GPU)", r);
    expect_clean(s, r);
    EXPECT_EQ(r.report.frozen_vertices, 0);
    const test::FarRim rim = test::far_rim(scene, r);
    EXPECT_GT(rim.far, 100U);
    EXPECT_EQ(rim.untouched, rim.far);
}

TEST(GpuImpactZones, CrumplingSheet) {
    WEFT_REQUIRE_GPU();
    const Scene s = rounded(test::crumpled_sheet(22, 7));
    const Resolved r = resolve_gpu(s);
    print("crumpled sheet (GPU)", r);
    expect_clean(s, r);
    EXPECT_GT(r.report.zones, 0);
    EXPECT_EQ(r.report.rigid_zones, 0);  // the projection alone resolves it, as on the CPU
    EXPECT_EQ(r.report.frozen_vertices, 0);
    const Resolved cpu = resolve_cpu(s);
    print("crumpled sheet (CPU)", cpu);
    const double e_gpu = correction(s, r.x1), e_cpu = correction(s, cpu.x1);
    std::printf("correction: GPU %.6g, CPU %.6g (ratio %.4f)\n", e_gpu, e_cpu, e_gpu / e_cpu);
    EXPECT_GT(e_gpu, 0.8 * e_cpu);
    EXPECT_LT(e_gpu, 1.25 * e_cpu);
}

TEST(GpuImpactZones, GiantZonePathMatchesTheBlockPath) {
    WEFT_REQUIRE_GPU();
    // Every zone through the grid-wide projection (giant_zone_constraints = 1, no coloured zones):
    // the same promises, the same minimiser as the CPU (and so as the one-block path), the same bits
    // on every run.
    for (const Scene& s : {rounded(test::two_sheets(14, 3)), rounded(test::crumpled_sheet(22, 7))}) {
        GpuImpactZones zones;
        const Resolved r = resolve_gpu(s, 32, zones, 1, 0);
        print("grid-wide projection (GPU)", r);
        expect_clean(s, r);
        EXPECT_EQ(r.report.rigid_zones, 0);
        EXPECT_EQ(r.report.frozen_vertices, 0);
        const Resolved cpu = resolve_cpu(s);
        const double e_gpu = correction(s, r.x1), e_cpu = correction(s, cpu.x1);
        std::printf("correction: GPU %.6g, CPU %.6g (ratio %.4f)\n", e_gpu, e_cpu, e_gpu / e_cpu);
        EXPECT_GT(e_gpu, 0.8 * e_cpu);
        EXPECT_LT(e_gpu, 1.25 * e_cpu);
        const Resolved again = resolve_gpu(s, 32, zones, 1, 0);
        std::size_t differ = 0;
        for (std::size_t v = 0; v < s.x0.size(); ++v) differ += same_bits(r.x1[v], again.x1[v]) ? 0 : 1;
        EXPECT_EQ(differ, 0U);
    }
}

TEST(GpuImpactZones, ColouredGaussSeidelAndProjectedGradientLandOnTheSameMinimiser) {
    WEFT_REQUIRE_GPU();
    // The same QP by both projections (colored_zone_projection.h; the projected gradient for every
    // zone with colored_zone_vertices = 0): both clean, both converged, the same mass-weighted
    // correction as each other and as the CPU's Gauss–Seidel; the coloured one the same bits on
    // every run. The stack of sheets falling onto each other is the stacked contact where the
    // gradient's diagonal majoriser is weakest.
    const test::StackScene stack = test::falling_stack(6);
    for (const Scene& s : {rounded(test::two_sheets(14, 3)), rounded(test::crumpled_sheet(22, 7)), rounded(stack.scene)}) {
        GpuImpactZones zones;
        const std::uint32_t giant = GpuImpactZoneInput{}.giant_zone_constraints;
        const Resolved coloured = resolve_gpu(s, 32, zones, giant, cuda::collision::kColoredZoneVertices);
        const Resolved gradient = resolve_gpu(s, 32, zones, giant, 0);
        print("coloured Gauss-Seidel (GPU)", coloured);
        print("projected gradient (GPU)", gradient);
        expect_clean(s, coloured);
        const Resolved cpu = resolve_cpu(s);
        print("Gauss-Seidel (CPU)", cpu);
        // Gauss–Seidel by colours converges where the CPU's does (within a zone of the round count).
        EXPECT_LE(coloured.report.qp_unconverged, cpu.report.qp_unconverged + 1);
        if (coloured.report.rigid_zones == 0 && coloured.report.frozen_vertices == 0 && cpu.report.rigid_zones == 0 &&
            cpu.report.frozen_vertices == 0) {
            const double e_col = correction(s, coloured.x1), e_cpu = correction(s, cpu.x1);
            std::printf("correction: coloured %.6g, gradient %.6g, CPU %.6g\n", e_col, correction(s, gradient.x1), e_cpu);
            EXPECT_GT(e_col, 0.8 * e_cpu);
            EXPECT_LT(e_col, 1.25 * e_cpu);
        }
        const Resolved again = resolve_gpu(s, 32, zones, giant, cuda::collision::kColoredZoneVertices);
        std::size_t differ = 0;
        for (std::size_t v = 0; v < s.x0.size(); ++v) differ += same_bits(coloured.x1[v], again.x1[v]) ? 0 : 1;
        EXPECT_EQ(differ, 0U);
        EXPECT_EQ(again.report.qp_sweeps, coloured.report.qp_sweeps);
    }
}

TEST(GpuImpactZones, AWorkCapSpentHandsTheHitsToTheFallbacksAndEndsClean) {
    WEFT_REQUIRE_GPU();
    // The CPU test's promise on the device (max_work, the CPU's qp_max_work): with a tenth of the
    // projections' work, and with a cap of 1 (no projection at all), the substep still ends clean
    // through the fallbacks, within the cap, the same bits on every run; by both projections.
    const Scene s = rounded(test::crumpled_sheet(16, 11));
    const std::uint32_t giant = GpuImpactZoneInput{}.giant_zone_constraints;
    for (const std::uint32_t colored : {0U, cuda::collision::kColoredZoneVertices}) {
        GpuImpactZones zones;
        const Resolved full = resolve_gpu(s, 32, zones, giant, colored);
        expect_clean(s, full);
        EXPECT_FALSE(full.report.qp_work_spent);
        ASSERT_GT(full.report.qp_work, 1000);
        for (const std::int64_t cap : {full.report.qp_work / 10, std::int64_t{1}}) {
            SCOPED_TRACE("cap " + std::to_string(cap) + (colored > 0 ? ", colours" : ", gradient"));
            const Resolved capped = resolve_gpu(s, 32, zones, giant, colored, cap);
            print("crumpled sheet, work capped (GPU)", capped);
            expect_clean(s, capped);
            test::expect_work_capped(capped.report, full.report, cap);
            const Resolved again = resolve_gpu(s, 32, zones, giant, colored, cap);
            std::size_t differ = 0;
            for (std::size_t v = 0; v < s.x0.size(); ++v) differ += same_bits(capped.x1[v], again.x1[v]) ? 0 : 1;
            EXPECT_EQ(differ, 0U);
        }
    }
}

TEST(GpuImpactZones, RigidFallbackKeepsMomentumAndShape) {
    WEFT_REQUIRE_GPU();
    const Scene s = rounded(test::crumpled_sheet(22, 7));
    const Resolved r = resolve_gpu(s, 1);
    print("crumpled sheet, 1 round (GPU)", r);
    expect_clean(s, r);
    EXPECT_EQ(r.report.iterations, 1);
    EXPECT_GT(r.report.rigid_zones, 0);
    EXPECT_GT(r.report.rigid_rounds, 0);
    const auto rigid = test::rigid_zones(s, r);
    EXPECT_EQ(static_cast<int>(rigid.size()), r.report.rigid_zones);
    for (const auto& [label, vertices] : rigid) {
        // Float positions: the momentum and the distances hold to the rounding of the end positions.
        double mass = 0.0;
        for (std::uint32_t v : vertices) mass += 1.0 / s.inverse_mass[v];
        const Vec3d p_hat = momentum(s, s.x1, vertices), p = momentum(s, r.x1, vertices);
        EXPECT_LE(physics::length(p - p_hat), 1e-6 * mass) << "zone " << label << ", " << vertices.size() << " vertices";
        EXPECT_LE(test::largest_distance_change(s, r, vertices), 1e-6) << "zone " << label << " is not rigid";
    }
}

TEST(GpuImpactZones, FreezingZonesThatTouchFixedVertices) {
    WEFT_REQUIRE_GPU();
    const Scene s = rounded(test::sheet_through_fixed_patch().scene);
    const Resolved r = resolve_gpu(s, 0);
    print("sheet through fixed mesh, 0 rounds (GPU)", r);
    expect_clean(s, r);
    EXPECT_EQ(r.report.iterations, 0);
    EXPECT_EQ(r.report.rigid_zones, 0);
    EXPECT_GT(r.report.frozen_vertices, 0);
}

TEST(GpuImpactZones, AStackFrozenLayerByLayerIsHeldWholeAfterAFewRounds) {
    WEFT_REQUIRE_GPU();
    const test::StackScene c = test::falling_stack(12);
    const Scene s = rounded(c.scene);
    const Resolved r = resolve_gpu(s, 0);
    print("stack of 12 frozen (GPU)", r);
    expect_clean(s, r);
    EXPECT_EQ(r.report.frozen_vertices, static_cast<int>(c.fixed)) << "every sheet of the stack ends held at x0";
    EXPECT_LE(r.report.detections, weft::collision::kImpactZoneRigidRounds + weft::collision::kImpactZoneFreezeRounds + 2);
    for (std::uint32_t v = c.lone; v < s.x0.size(); ++v)
        ASSERT_EQ(r.outcome[v], VertexOutcome::Untouched) << "the lone sheet, in no hit, was frozen with the stack";
    // The CPU reference takes the same rounds.
    const Resolved cpu = test::resolve_cpu(s, 0);
    EXPECT_EQ(r.report.detections, cpu.report.detections);
    EXPECT_EQ(r.report.frozen_vertices, cpu.report.frozen_vertices);
}

TEST(GpuImpactZones, KinematicMeshCarriesFrozenCloth) {
    WEFT_REQUIRE_GPU();
    const test::PlateScene scene = test::plate_through_cloth();
    const Scene s = rounded(scene.scene);
    const std::uint32_t cloth = scene.cloth, plate = scene.plate;
    const Vec3d lift = scene.lift;
    const Resolved r = resolve_gpu(s, 0);
    print("plate through frozen cloth (GPU)", r);
    expect_clean(s, r);
    EXPECT_GT(r.report.carried_vertices, 0);
    for (std::uint32_t v = cloth; v < plate; ++v) {
        if (r.outcome[v] != VertexOutcome::Carried) continue;
        EXPECT_NEAR(physics::length(r.x1[v] - s.x0[v] - lift), 0.0, 1e-6);
    }
    const Resolved p = resolve_gpu(s);
    print("plate through cloth (GPU)", p);
    expect_clean(s, p);
    EXPECT_EQ(p.report.frozen_vertices, 0);
    EXPECT_EQ(p.report.carried_vertices, 0);
}

TEST(GpuImpactZones, SameBitsOnEveryRunAndNothingToDo) {
    WEFT_REQUIRE_GPU();
    const Scene s = rounded(test::crumpled_sheet(16, 11));
    GpuImpactZones zones;  // reused: buffers kept between calls must not leak state
    const Resolved a = resolve_gpu(s, 32, zones);
    const Resolved b = resolve_gpu(s, 32, zones);
    const Resolved c = resolve_gpu(s, 2);
    const Resolved d = resolve_gpu(s, 2, zones);
    ASSERT_EQ(a.x1.size(), b.x1.size());
    std::size_t differ = 0, differ_fallback = 0;
    for (std::size_t v = 0; v < a.x1.size(); ++v) {
        differ += same_bits(a.x1[v], b.x1[v]) ? 0 : 1;
        differ_fallback += same_bits(c.x1[v], d.x1[v]) ? 0 : 1;
    }
    EXPECT_EQ(differ, 0U);
    EXPECT_EQ(differ_fallback, 0U);
    EXPECT_EQ(a.outcome, b.outcome);
    EXPECT_EQ(a.zone, b.zone);
    // A motion without collisions: nothing changes, nothing is counted.
    Scene still = s;
    still.x1 = still.x0;
    const Resolved n = resolve_gpu(still, 32, zones);
    EXPECT_TRUE(n.report.resolved);
    EXPECT_EQ(n.report.constraints, 0);
    for (std::size_t v = 0; v < still.x0.size(); ++v) EXPECT_TRUE(same_bits(n.x1[v], still.x0[v]));
}

TEST(GpuImpactZones, TheConstraintsOfACrumpleAreGivenBackAfterATrimWindow) {
    // The constraint arrays grown for a crumple are cut back once a trim window of calls needed
    // none (weft/backend/buffer_trim.h), and the crumple resolved again gives the same bits.
    WEFT_REQUIRE_GPU();
    const Scene s = rounded(test::crumpled_sheet(22, 7));  // 2,780 constraints
    Scene still = s;
    still.x1 = still.x0;
    GpuImpactZones zones;
    const Resolved first = resolve_gpu(s, 32, zones);
    const std::size_t grown = zones.constraint_capacity();
    std::printf("[ trim     ] crumple: %d constraints, capacity %zu (%.1f MB)\n", first.report.constraints, grown,
                static_cast<double>(grown * GpuImpactZones::kBytesPerConstraint) / 1e6);
    ASSERT_GT(grown * GpuImpactZones::kBytesPerConstraint, kTrimFloorBytes) << "the crumple is too small to trim";
    // The window that holds the crumple keeps its capacity (the peak is the crumple's); the next
    // window, with no constraint at all, gives it back.
    for (std::size_t call = 0; call < 2 * kTrimPeriod; ++call) (void)resolve_gpu(still, 32, zones);
    std::printf("[ trim     ] after %zu calls without a collision: capacity %zu, %d trims\n", 2 * kTrimPeriod,
                zones.constraint_capacity(), zones.trims());
    EXPECT_LT(zones.constraint_capacity(), grown);
    EXPECT_EQ(zones.trims(), 1);
    const Resolved again = resolve_gpu(s, 32, zones);
    std::size_t differ = 0;
    for (std::size_t v = 0; v < first.x1.size(); ++v) differ += same_bits(first.x1[v], again.x1[v]) ? 0 : 1;
    EXPECT_EQ(differ, 0U) << "the reallocated arrays changed the result";
    EXPECT_EQ(first.outcome, again.outcome);
}

TEST(GpuImpactZones, RejectsBadInput) {
    WEFT_REQUIRE_GPU();
    GpuImpactZones zones;
    GpuImpactZoneInput in;
    EXPECT_THROW((void)zones.resolve(in, nullptr), Error);  // no arrays
    const Scene s = test::two_sheets(2, 1);
    Scene bad = s;
    bad.thickness = -1.0;
    EXPECT_THROW((void)resolve_gpu(bad), Error);
    bad.thickness = std::nan("");
    EXPECT_THROW((void)resolve_gpu(bad), Error);
    EXPECT_THROW((void)resolve_gpu(s, -1), Error);
}

}  // namespace
}  // namespace weft::collision
