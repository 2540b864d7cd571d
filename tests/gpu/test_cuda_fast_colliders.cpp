// Fast analytic colliders on the cuda backend (docs/collisions.md, step 4): after the solve of each
// substep the device runs the swept test of weft/physics/swept_collider.h on every free vertex, as
// CpuSolver::sweep_fast_colliders does, in substeps where some vertex's motion relative to a
// collider may exceed a quarter of the collider's width (DeviceSolver::sweep_colliders). Checked
// here: the 50 m/s ball of the `projectile` scene does not tunnel through the sheet; one substep
// sweeps the same vertices to the same places as the CPU backend in float and as the swept test
// evaluated on the host; a static collider met by fast cloth is swept too (the test measures the
// relative motion, as on the CPU); a slow collider launches nothing; the substep's CUDA graph is
// captured once and gives the same bits as the host-driven loop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "backend_access.h"
#include "weft/backend/collider_shape.h"
#include "weft/backend/model.h"
#include "weft/collider.h"
#include "weft/mesh.h"
#include "weft/physics/swept_collider.h"
#include "weft/scene.h"
#include "weft/world.h"

#include "gpu_test_util.h"

namespace weft {
namespace {

using test::make_world;

cuda::DeviceSolver& device_solver_of(World& world) {
    cuda::DeviceSolver* solver = cuda::device_solver(world.backend());
    if (solver == nullptr) throw Error("not a cuda world");
    return *solver;
}

bool same_bits(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3d)) == 0;
}

/// Vertices that end more than 1 cm from where their own motion took them: the ones a collider
/// carried (in the one-substep cases below the others miss it by under 1e-5 m, the carried ones by
/// more than 5 cm).
std::vector<std::size_t> carried_vertices(const std::vector<Vec3d>& free_end, const std::vector<Vec3d>& end) {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < free_end.size(); ++i)
        if (physics::length(end[i] - free_end[i]) > 0.01) out.push_back(i);
    return out;
}

// ---- one substep against the host evaluation and the CPU ------------------------------------------

/// The swept test of the whole sheet on the host, in float, as CpuSolver<float> runs it: each vertex
/// from `x0` to `x1` against `ball` over [0, h]. Hit vertices and their corrected end positions.
struct HostSweep {
    std::vector<std::size_t> hit;
    std::vector<Vec3d> position;  ///< corrected end position of every vertex (x1 where not hit)
};

HostSweep host_sweep(const ColliderDesc& ball, double h, float thickness, const std::vector<Vec3d>& x0,
                     const std::vector<Vec3d>& x1) {
    const physics::Shape<float> s0 = shape_at<float>(ball, 0.0), s1 = shape_at<float>(ball, 0.0 + h);
    HostSweep out;
    out.position = x1;
    for (std::size_t i = 0; i < x0.size(); ++i) {
        const physics::SweptContact<float> c = physics::swept_shape_contact(
            s0, s1, static_cast<float>(h), x0[i].cast<float>(), x1[i].cast<float>(), thickness);
        if (!c.hit) continue;
        out.hit.push_back(i);
        out.position[i] = c.position.cast<double>();
    }
    return out;
}

/// One substep of `h` s of the same world on the cuda backend and on the CPU backend in float,
/// compared with each other and with `host_sweep` of the start state moving at its start velocity.
///
/// Tolerance. The swept test itself is some thirty float operations on coordinates below 1.2 m
/// (an ulp of 1.2e-7 m), so host, CPU and GPU agree to about 1e-6 m (nvcc may fuse multiply-adds,
/// which changes the rounding, not its size). What else differs is the solve: the vertex's end of
/// the substep before the sweep, x1, which the host takes as x0 + h·v0 (no force acts: no gravity,
/// a sheet at rest or in uniform motion, no contact at either end of the substep). The hit point
/// depends on x1 only through the sample point x0 + τ(x1 − x0), with a factor (r + thickness)/|p − c|
/// ≤ 0.054/0.035 < 2 where the nearest hit sits; so twice the largest deviation of the unswept
/// vertices from x0 + h·v0 (measured on each backend, and asserted small) is added to 1e-5 m.
void expect_one_substep_matches(World& gpu, World& cpu, int expected_hits) {
    const Model& model = gpu.model();
    ASSERT_EQ(model.colliders.size(), 1u);
    const ColliderDesc& ball = model.colliders[0];
    const double h = model.settings.solver.dt / model.settings.solver.substeps;
    ASSERT_EQ(model.settings.solver.substeps, 1);
    const float thickness = static_cast<float>(model.cloths[0].material.contact_thickness);
    const std::vector<Vec3d> x0 = gpu.positions(0), v0 = gpu.velocities(0);
    ASSERT_TRUE(same_bits(x0, cpu.positions(0))) << "both backends must start from the same float state";
    std::vector<Vec3d> x1_free(x0.size());
    for (std::size_t i = 0; i < x0.size(); ++i) x1_free[i] = x0[i] + h * v0[i];

    const StepStats gs = gpu.step();
    const StepStats cs = cpu.step();
    ASSERT_FALSE(gs.non_finite);
    ASSERT_FALSE(cs.non_finite);
    const std::vector<Vec3d> xg = gpu.positions(0), vg = gpu.velocities(0);
    const std::vector<Vec3d> xc = cpu.positions(0), vc = cpu.velocities(0);

    const HostSweep expected = host_sweep(ball, h, thickness, x0, x1_free);
    ASSERT_EQ(static_cast<int>(expected.hit.size()), expected_hits) << "the geometry of the test changed";
    // x1 = x0 + h·v0 is only an approximation of the solve's x1 if the unswept vertices show it is.
    double drift_g = 0.0, drift_c = 0.0;
    for (std::size_t i = 0; i < x0.size(); ++i) {
        if (std::find(expected.hit.begin(), expected.hit.end(), i) != expected.hit.end()) continue;
        drift_g = std::max(drift_g, physics::length(xg[i] - x1_free[i]));
        drift_c = std::max(drift_c, physics::length(xc[i] - x1_free[i]));
    }
    ASSERT_LT(drift_g, 1e-5) << "the free sheet should move as it started";
    ASSERT_LT(drift_c, 1e-5) << "the free sheet should move as it started";
    const double tolerance = 1e-5 + 2.0 * std::max(drift_g, drift_c);

    // The same vertices, each caught once, by the one collider.
    EXPECT_EQ(carried_vertices(x1_free, xg), expected.hit);
    EXPECT_EQ(carried_vertices(x1_free, xc), expected.hit);
    EXPECT_EQ(gs.collision.swept_collider_hits, expected_hits);
    EXPECT_EQ(cs.collision.swept_collider_hits, expected_hits);

    const physics::Shape<double> end = shape_at<double>(ball, h);
    double worst_host = 0.0, worst_cpu = 0.0, worst_v = 0.0;
    for (std::size_t i : expected.hit) {
        worst_host = std::max(worst_host, physics::length(xg[i] - expected.position[i]));
        worst_cpu = std::max(worst_cpu, physics::length(xg[i] - xc[i]));
        worst_v = std::max(worst_v, physics::length(vg[i] - vc[i]));
        // Carried on the ball's surface, pushed out to the contact thickness, with v = (x − x0)/h.
        EXPECT_NEAR(physics::length(xg[i] - end.origin), ball.radius + static_cast<double>(thickness), tolerance) << "vertex " << i;
        EXPECT_LE(physics::length(vg[i] - (xg[i] - x0[i]) / h), 1e-3 * physics::length(vg[i]) + tolerance / h);
    }
    for (std::size_t i = 0; i < x0.size(); ++i)
        EXPECT_GE(physics::length(xg[i] - end.origin), ball.radius) << "vertex " << i << " ends inside the ball";
    std::printf("[ swept    ] %d vertices carried; |x_cuda - x_host| <= %.2e m, |x_cuda - x_cpu| <= %.2e m, "
                "|v_cuda - v_cpu| <= %.2e m/s (tolerance %.2e m; unswept drift %.1e m cuda, %.1e m cpu)\n",
                gs.collision.swept_collider_hits, worst_host, worst_cpu, worst_v, tolerance, drift_g, drift_c);
    EXPECT_LE(worst_host, tolerance);
    EXPECT_LE(worst_cpu, tolerance);
    EXPECT_LE(worst_v, tolerance / h);  // v = (x − x0)/h on both
    EXPECT_EQ(device_solver_of(gpu).sweep_launches(), 1);
}

// The projectile's sheet, at rest in zero gravity, and its ball 8 mm in front of it, passing right
// through in one substep of 2.3 ms (11.5 cm at 50 m/s): the penalty sees the ball at neither end
// (8 mm and 7 mm from the sheet), so without the sweep nothing at all would stop it. The ball is fast
// by the collider's own motion (more than a quarter of its width). The grid spacing is 1/32 m, so the
// 3 × 3 vertices around the centre lie within its 5 cm radius of its path (at most 4.4 cm off) and
// the next ones 6.25 cm off; 5 samples at τ = 0.2, 0.4, … find each of the nine inside by 4 mm or more.
const std::vector<std::string> kThroughInOneSubstep = {
    "solver.substeps=1", "solver.dt=0.0023", "world.gravity=[0, 0, 0]", "collision.self=false",
    "motion.shot.origin=[0, 1, 0.058]"};

TEST(CudaFastColliders, BallThroughTheSheetInOneSubstepIsSweptAsOnTheCpu) {
    WEFT_REQUIRE_GPU();
    const auto gpu = make_world("projectile", "cuda", kThroughInOneSubstep);
    std::vector<std::string> cpu_overrides = kThroughInOneSubstep;
    cpu_overrides.emplace_back("solver.precision=float");
    const auto cpu = make_world("projectile", "cpu", cpu_overrides);
    const Model& model = gpu->model();
    ASSERT_TRUE(is_fast_collider(model.colliders.at(0), 0.0, model.settings.solver.dt));
    expect_one_substep_matches(*gpu, *cpu, 9);
}

// The same relative motion the other way round: the sheet flies at 50 m/s into a ball that does not
// move. The ball is not fast (it does not move at all) but the vertices are: the swept test measures
// the motion of the vertex relative to the collider, so the CPU sweeps these vertices, and the cuda
// backend must launch the test from the vertices' motion as well.
WorldDesc flying_sheet_settings() {
    WorldDesc desc;
    desc.gravity = {0.0, 0.0, 0.0};
    desc.solver.dt = 0.0023;
    desc.solver.substeps = 1;
    desc.solver.precision = Precision::Float;  // the CPU backend's scalar; the cuda backend is float anyway
    return desc;
}

void add_flying_sheet_and_still_ball(World& world) {
    const auto fabric = Fabric::cook(make_grid(1.0, 1.0, 32, 32), {.density = 0.2});
    ClothDesc sheet{.name = "sheet", .fabric = fabric};
    sheet.transform.translation = {0.0, 1.0, 0.0};
    sheet.material.contact_thickness = 0.004;
    sheet.initial_velocity = {0.0, 0.0, -50.0};
    world.add_cloth(sheet);
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
    ball.radius = 0.05;
    ball.motion.origin = {0.0, 1.0, -0.057};  // the sheet reaches it after 7 mm and is 8 mm past it at the end
    ball.friction = 0.0;
    world.add_collider(ball);
}

TEST(CudaFastColliders, StillBallMetByAFastSheetIsSweptAsOnTheCpu) {
    WEFT_REQUIRE_GPU();
    World gpu(flying_sheet_settings(), "cuda");
    World cpu(flying_sheet_settings(), "cpu");
    add_flying_sheet_and_still_ball(gpu);
    add_flying_sheet_and_still_ball(cpu);
    ASSERT_FALSE(is_fast_collider(gpu.model().colliders.at(0), 0.0, gpu.settings().solver.dt));
    expect_one_substep_matches(gpu, cpu, 9);
}

// ---- the projectile scene: no tunnelling ----------------------------------------------------------

/// What a run did to the cloth around a ball that moves in a straight line.
struct PathCheck {
    int tunnelled = 0;     ///< vertices the ball passed through within a frame
    int inside = 0;        ///< vertices deeper than the tolerance inside the ball at a frame's end
    double deepest = 0.0;  ///< largest depth inside the ball at a frame's end (m)
    int swept = 0;         ///< swept collider hits over the run
    int first_swept_frame = -1;
};

/// A vertex tunnelled during a frame when it lay within the ball's cross-section (closer than r to the
/// line of its path) ahead of the ball at the frame's start and within it behind the ball at the
/// end: the ball went through where it was. Cloth that the ball carries stays ahead of it; cloth
/// that slides off leaves the cross-section on the way (frames are too short for it to slide round
/// and back in behind).
void check_frame(const std::vector<Vec3d>& before, const std::vector<Vec3d>& after, const physics::Shape<double>& b0,
                 const physics::Shape<double>& b1, double radius, double tolerance, PathCheck& check) {
    const Vec3d dir = physics::normalized(b1.origin - b0.origin);
    auto axial = [&](Vec3d p, const Vec3d& c) { return physics::dot(p - c, dir); };
    auto lateral = [&](Vec3d p, const Vec3d& c) { return physics::length((p - c) - axial(p, c) * dir); };
    for (std::size_t i = 0; i < after.size(); ++i) {
        const double depth = radius - physics::length(after[i] - b1.origin);
        check.deepest = std::max(check.deepest, depth);
        if (depth > tolerance) ++check.inside;
        if (lateral(before[i], b0.origin) < radius && axial(before[i], b0.origin) > 0.0 &&
            lateral(after[i], b1.origin) < radius && axial(after[i], b1.origin) < 0.0)
            ++check.tunnelled;
    }
}

PathCheck run_projectile(World& world, int frames) {
    const ColliderDesc ball = world.model().colliders.at(0);
    PathCheck check;
    std::vector<Vec3d> before = world.positions(0);
    for (int f = 0; f < frames; ++f) {
        const double t0 = world.time();
        const StepStats& s = world.step();
        EXPECT_FALSE(s.non_finite) << "frame " << f;
        EXPECT_EQ(s.collision.remaining_intersections, 0) << "frame " << f;
        EXPECT_EQ(s.collision.unresolved_substeps, 0) << "frame " << f;
        if (s.collision.swept_collider_hits > 0 && check.first_swept_frame < 0) check.first_swept_frame = f;
        check.swept += s.collision.swept_collider_hits;
        const std::vector<Vec3d> after = world.positions(0);
        // A fifth of the 4 mm contact thickness: the penalty keeps cloth it holds outside the ball
        // (it pushes out to the thickness), while a vertex that the ball runs over ends centimetres
        // deep or behind it.
        check_frame(before, after, shape_at<double>(ball, t0), shape_at<double>(ball, world.time()), ball.radius, 8e-4,
                    check);
        before = after;
    }
    return check;
}

struct ProjectileCase {
    const char* name;
    std::vector<std::string> overrides;
};

// The scene as shipped (4 substeps: the ball moves 2.1 cm a substep, under a quarter of its width,
// but the cloth it carries moves as fast, so the relative motion is sampled) and at one substep
// (8.3 cm: the ball alone is fast). Self-collision on, the exact check after every frame. The ball
// reaches the sheet at frame 12; 45 frames carry it 2.75 m past the sheet's plane. The check has
// teeth: with the CPU backend's sweep switched off (a local experiment), 3 vertices tunnel and one
// ends 1.4 cm deep at 4 substeps, 7 and 2.8 cm at one; with it, none and none, in float and double.
const ProjectileCase kProjectileCases[] = {
    {"FourSubsteps", {"collision.check=true"}},
    {"OneSubstep", {"collision.check=true", "solver.substeps=1"}},
};

void PrintTo(const ProjectileCase& c, std::ostream* os) { *os << c.name; }

class CudaProjectile : public testing::TestWithParam<ProjectileCase> {};

TEST_P(CudaProjectile, BallAt50MetresPerSecondDoesNotTunnelThroughTheSheet) {
    WEFT_REQUIRE_GPU();
    const auto gpu = make_world("projectile", "cuda", GetParam().overrides);
    const auto cpu = make_world("projectile", "cpu", GetParam().overrides);
    constexpr int kFrames = 45;
    const PathCheck g = run_projectile(*gpu, kFrames);
    const PathCheck c = run_projectile(*cpu, kFrames);
    std::printf("[ projectl ] %s: cuda %d swept hits from frame %d, %d tunnelled, deepest %.2e m; "
                "cpu %d swept hits from frame %d, %d tunnelled, deepest %.2e m; sweep launched in %d substeps\n",
                GetParam().name, g.swept, g.first_swept_frame, g.tunnelled, g.deepest, c.swept, c.first_swept_frame,
                c.tunnelled, c.deepest, device_solver_of(*gpu).sweep_launches());
    EXPECT_EQ(g.tunnelled, 0);
    EXPECT_EQ(g.inside, 0);
    // The reference passes the same check (else the check, not the port, would be wrong).
    EXPECT_EQ(c.tunnelled, 0);
    EXPECT_EQ(c.inside, 0);
    // The cloth in the ball's path was carried, on both backends, from the frame the ball reaches
    // the sheet in (the CPU in float and in double: frame 14 at 4 substeps, 11 at one). After that
    // the trajectories part as any two solves of a contact do, so only the start is compared, to a
    // frame: at 4 substeps the first hit is a carried vertex whose solved end lands just inside the
    // ball, which rounding-sized differences of the solves may move by a substep.
    EXPECT_GT(g.swept, 0);
    EXPECT_GT(c.swept, 0);
    EXPECT_LE(std::abs(g.first_swept_frame - c.first_swept_frame), 1);
}

INSTANTIATE_TEST_SUITE_P(Substeps, CudaProjectile, testing::ValuesIn(kProjectileCases),
                         [](const testing::TestParamInfo<ProjectileCase>& p) { return std::string(p.param.name); });

// ---- the graph and the cost -----------------------------------------------------------------------

// The sweep runs after the graph, on the same stream: the graph is captured once and the graph and
// host-driven loops give the same bits while the ball is carrying cloth.
TEST(CudaFastColliders, SweepLeavesTheGraphAsCapturedAndGivesTheSameBitsWithout) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> overrides = {"solver.substeps=1", "collision.self=false"};
    const auto graph = make_world("projectile", "cuda", overrides);
    const auto loop = make_world("projectile", "cuda", overrides);
    cuda::as_cuda(loop->backend())->set_use_graph(false);
    constexpr int kFrames = 20;  // the ball reaches the sheet at frame 12
    int hits = 0;
    for (int f = 0; f < kFrames; ++f) {
        hits += graph->step().collision.swept_collider_hits;
        (void)loop->step();
    }
    const cuda::DeviceSolver& solver = device_solver_of(*graph);
    EXPECT_GT(hits, 0);
    EXPECT_TRUE(solver.graph_active());
    EXPECT_EQ(solver.graph_captures(), 1);
    EXPECT_EQ(solver.sweep_launches(), kFrames) << "the ball is fast in every substep";
    EXPECT_FALSE(device_solver_of(*loop).graph_active());
    EXPECT_TRUE(same_bits(graph->positions(0), loop->positions(0)));
    EXPECT_TRUE(same_bits(graph->velocities(0), loop->velocities(0)));
}

// A ball pushed slowly (0.5 m/s) into a hanging sheet: neither it nor the cloth moves anywhere near a
// quarter of its width in a substep, so the sweep is never launched and nothing is swept, on either
// backend, while the penalty holds the cloth off the ball.
TEST(CudaFastColliders, SlowColliderLaunchesNothing) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> overrides = {"motion.shot.origin=[0, 1, 0.06]", "motion.shot.linear_velocity=[0, 0, -0.5]",
                                                "collision.self=false"};
    const auto gpu = make_world("projectile", "cuda", overrides);
    const auto cpu = make_world("projectile", "cpu", overrides);
    int gpu_swept = 0, cpu_swept = 0, contacts = 0;
    for (int f = 0; f < 60; ++f) {  // 0.1 s: the ball pushes the sheet 4 cm
        const StepStats& s = gpu->step();
        ASSERT_FALSE(s.non_finite);
        gpu_swept += s.collision.swept_collider_hits;
        contacts = std::max(contacts, s.collider_contacts);
        cpu_swept += cpu->step().collision.swept_collider_hits;
    }
    const cuda::DeviceSolver& solver = device_solver_of(*gpu);
    EXPECT_GT(contacts, 0) << "the ball never touched the sheet: the test tests nothing";
    EXPECT_EQ(gpu_swept, 0);
    EXPECT_EQ(cpu_swept, 0);
    EXPECT_EQ(solver.sweep_launches(), 0);
    EXPECT_TRUE(solver.graph_active());
    EXPECT_EQ(solver.graph_captures(), 1);
}

}  // namespace
}  // namespace weft
