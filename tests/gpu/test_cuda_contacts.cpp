// Proximity contacts in the CUDA implicit solve (cuda/src/contact_kernels.cu, device_contacts.h)
// against the CPU float solve with the same contacts (runtime/src/cpu/contact_terms.h), and against
// itself: the same bits on every run, in the graph and host-driven loops, both CG loops agreeing,
// a changing contact count replaying one graph, and no contacts giving today's bits exactly.
//
// The scene: two sheets stacked 3 mm apart (the upper one falling onto the lower), the lower one 3 mm
// above a ball and pinned at a corner, and a kinematic paddle (4 vertices of a "mesh collider") 3 mm
// above the upper sheet pressing down. Its contacts come from the CPU reference broad and narrow
// phases on the float state both solvers start from; the GPU takes them through set_contacts, the
// CPU through its test hook.
#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "collision/broad_phase.h"
#include "collision/proximity_contacts.h"
#include "cpu/cpu_solver.h"
#include "device_solver.h"
#include "gpu_test_util.h"
#include "weft/backend/flat_model.h"
#include "weft/mesh.h"

namespace weft {
namespace {

using collision::ProximityContact;

constexpr double kH = 1.0 / 120.0;  // substep, s
/// CG tolerance of the comparisons with the CPU. The default scene's springs (12 a vertex) make a stiff
/// system: at 1e-4 the CPU's float solve is 6e-3 of the velocity change from the converged one, at
/// 1e-5 6e-4 (measured with the CPU backend), which makes the comparison ten times sharper. Float CG
/// reaches 1e-5 here (785 iterations on the CPU).
constexpr double kParityTolerance = 1e-5;

/// Sizes of the scene: cells per sheet side (0.5 m), the contact thickness, the gap between the
/// sheets, between the ball and the lower sheet, and between the paddle and the upper sheet, and the
/// speed at which the upper sheet falls onto the lower one, and how far it is shifted along x and z
/// (0: it covers the lower sheet; 0.25 m: a quarter of each overlaps). Where two sheets lie within the
/// thickness every crossing pair of edges is a contact: 12 contacts per vertex in the default scene.
struct SceneSize {
    int cells = 30;
    double thickness = 0.004;
    double gap = 0.003;
    double approach = 0.5;  // m/s
    double shift = 0.0;     // m
};

/// The scene, the contacts at its start and everything both solvers need to take them.
struct ContactScene {
    Model model;
    FlatModel flat;
    std::vector<Vec3d> x0, v0;            // the cloth's float start state, widened
    std::vector<Vec3d> kinematic_x1, kinematic_v;
    std::vector<ProximityContact> contacts;
};

Model make_model(SceneSize size, double tolerance) {
    const int cells = size.cells;
    const double gap = size.gap;
    Model m;
    m.settings.solver.newton_iterations = 2;  // the second linearises at x0 + h·w_1 ≠ x0
    m.settings.solver.cg_tolerance = tolerance;
    m.settings.solver.cg_max_iterations = 4000;
    const auto fabric = Fabric::cook(make_grid(0.5, 0.5, cells, cells, GridPlane::XZ), {.density = 0.2});
    ClothDesc low{.name = "low", .fabric = fabric};
    low.transform.translation = {0.0, 0.2, 0.0};
    low.initial_velocity = {0.0, -0.1, 0.0};
    low.pins.push_back({0, -1});
    ClothDesc high{.name = "high", .fabric = fabric};
    // Offset sideways by a fraction of a cell, so that the vertex–face weights are generic.
    high.transform.translation = {size.shift + 0.37 * 0.5 / cells, 0.2 + gap, size.shift + 0.21 * 0.5 / cells};
    high.initial_velocity = {0.3 * size.approach, -size.approach, 0.1 * size.approach};  // and sliding (friction)
    for (ClothDesc* c : {&low, &high}) {
        c->material.stretch_stiffness = 2e3;
        c->material.contact_thickness = size.thickness;
        c->material.friction = 0.3;
    }
    m.cloths = {low, high};
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
    ball.radius = 0.15;
    ball.motion.origin = {0.0, 0.2 - gap - 0.15, 0.0};
    m.colliders = {ball};
    return m;
}

std::vector<Vec3d> widened_float(const std::vector<Vec3d>& a) {
    std::vector<Vec3d> out(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) out[i] = a[i].cast<float>().cast<double>();
    return out;
}

ContactScene make_scene(SceneSize size = {}, double tolerance = 1e-4) {
    ContactScene s;
    s.model = make_model(size, tolerance);
    s.flat = flatten(s.model);
    const std::size_t n = s.flat.vertex_count;
    s.x0 = widened_float(s.flat.initial_positions);
    s.v0 = widened_float(s.flat.initial_velocities);

    // The paddle: a 0.12 m square over a corner region of the upper sheet, moving down at 0.3 m/s.
    const double top = 0.2 + 2 * size.gap;
    const std::vector<Vec3d> paddle = {{0.05, top, 0.05}, {0.17, top, 0.05}, {0.17, top, 0.17}, {0.05, top, 0.17}};
    const Vec3d paddle_v{0.0, -0.3, 0.0};
    const auto k0 = static_cast<std::uint32_t>(n);
    std::vector<Triangle> triangles = s.flat.triangles;
    std::vector<std::uint32_t> group = s.flat.triangle_cloth;
    triangles.push_back({{k0, k0 + 1, k0 + 2}});
    triangles.push_back({{k0, k0 + 2, k0 + 3}});
    group.insert(group.end(), 2, 2u);

    std::vector<Vec3d> x0 = s.x0, x1(n);
    for (std::size_t i = 0; i < n; ++i) x1[i] = (s.x0[i].cast<float>() + static_cast<float>(kH) * s.v0[i].cast<float>()).cast<double>();
    for (const Vec3d& p : paddle) {
        x0.push_back(p);
        x1.push_back(p + kH * paddle_v);
        s.kinematic_x1.push_back(p + kH * paddle_v);
        s.kinematic_v.push_back(paddle_v);
    }
    const std::vector<collision::Edge> edges = collision::build_edges(triangles);
    collision::BroadPhaseInput in;
    in.x0 = x0;
    in.x1 = x1;
    in.triangles = triangles;
    in.edges = edges;
    in.triangle_cloth = group;
    in.thickness = size.thickness;
    in.self_pairs = false;  // sheet–sheet and sheet–paddle pairs
    collision::BroadPhase broad;
    collision::BroadPhaseResult pairs;
    broad.find(in, pairs);

    std::vector<double> inverse_mass(x0.size(), 0.0), thickness(x0.size(), 0.0), friction(x0.size(), 0.5);
    for (std::size_t i = 0; i < n; ++i) {
        inverse_mass[i] = s.flat.vertex_pin[i] >= 0 ? 0.0 : 1.0 / s.flat.mass[i];
        thickness[i] = size.thickness;
        friction[i] = 0.3;
    }
    collision::ProximityInput p;
    p.x0 = x0;
    p.x1 = x1;
    p.inverse_mass = inverse_mass;
    p.thickness = thickness;
    p.friction = friction;
    p.triangles = triangles;
    p.edges = edges;
    p.vf = pairs.vf;
    p.ee = pairs.ee;
    p.h = kH;
    collision::find_proximity_contacts(p, s.contacts);
    return s;
}

struct State {
    std::vector<Vec3d> x, v;
    StepStats stats;
};

/// `steps` substeps of CpuSolver<T> from the scene's float state, with `contacts` (none when empty).
template <typename T>
State cpu_substeps(const ContactScene& s, std::span<const ProximityContact> contacts, double tolerance, int steps = 1) {
    Model model = s.model;
    model.settings.solver.cg_tolerance = tolerance;
    cpu::CpuSolver<T> solver;
    solver.build(s.flat, model);
    const std::size_t n = s.flat.vertex_count;
    solver.write_state(0, n, s.x0.data(), s.v0.data());
    if (!contacts.empty()) {
        std::vector<physics::Vec3<T>> x1, v;
        for (std::size_t k = 0; k < s.kinematic_x1.size(); ++k) {
            x1.push_back(s.kinematic_x1[k].template cast<T>());
            v.push_back(s.kinematic_v[k].template cast<T>());
        }
        solver.set_contacts_for_test(contacts, x1, v);
    }
    State out;
    for (int step = 0; step < steps; ++step) solver.substep(model, step * kH, kH, out.stats);
    out.x.resize(n);
    out.v.resize(n);
    solver.read_state(0, n, out.x.data(), out.v.data());
    return out;
}

/// A device solver for the scene, with the given CG loop and graph setting.
std::unique_ptr<cuda::DeviceSolver> gpu_solver(const ContactScene& s, cuda::PcgLoop loop, bool graph = true) {
    auto solver = std::make_unique<cuda::DeviceSolver>(0);
    solver->build(s.flat, s.model);
    solver->set_pcg_loop(loop);
    solver->set_use_graph(graph);
    return solver;
}

State gpu_read(const cuda::DeviceSolver& solver, std::size_t n) {
    State out;
    out.x.resize(n);
    out.v.resize(n);
    solver.read_state(0, n, out.x.data(), out.v.data());
    return out;
}

double max_distance(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
    double m = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, physics::length(a[i] - b[i]));
    return m;
}

bool same_bits(const State& a, const State& b) {
    return a.x.size() == b.x.size() && std::memcmp(a.x.data(), b.x.data(), a.x.size() * sizeof(Vec3d)) == 0 &&
           std::memcmp(a.v.data(), b.v.data(), a.v.size() * sizeof(Vec3d)) == 0;
}

const char* name(cuda::PcgLoop loop) { return loop == cuda::PcgLoop::OneLaunch ? "one-launch" : "per-kernel"; }

std::span<const ProximityContact> prefix(const std::vector<ProximityContact>& c, std::size_t count) {
    return std::span<const ProximityContact>(c).first(std::min(count, c.size()));
}

TEST(CudaContacts, SceneHasContactsOfEveryKind) {
    // Guard of the other tests: the reference phases found sheet–sheet, sheet–paddle (kinematic) and
    // pinned-vertex pairs, vertex–face and edge–edge.
    const ContactScene s = make_scene();
    const std::size_t n = s.flat.vertex_count;
    std::size_t kinematic = 0, pinned = 0, edge_edge = 0;
    for (const ProximityContact& c : s.contacts) {
        bool k = false, p = false;
        for (std::uint32_t v : c.vertex) {
            k = k || v >= n;
            p = p || (v < n && s.flat.vertex_pin[v] >= 0);
        }
        kinematic += k ? 1 : 0;
        pinned += p ? 1 : 0;
        edge_edge += c.weight[0] != 1.0 ? 1 : 0;
    }
    std::printf("[ contacts ] %zu cloth vertices, %zu contacts: %zu with the paddle, %zu with a pinned vertex, %zu "
                "edge-edge\n",
                n, s.contacts.size(), kinematic, pinned, edge_edge);
    EXPECT_GT(s.contacts.size(), 1000u);
    EXPECT_GT(kinematic, 0u);
    EXPECT_GT(pinned, 0u);
    EXPECT_GT(edge_edge, 0u);
}

// One substep with the contacts on the GPU against the CPU in float with the same contacts. Two CG
// solves of one system that stop at the same relative residual differ by up to about what each
// differs from the exact solution; so both are measured against the converged solve in double (same
// start state, same contacts) and the GPU must be as close to it as the CPU float solve is (3×, for
// a different rounding order and stopping point), and closer to the CPU than the contacts' own effect
// by far.
TEST(CudaContacts, OneSubstepMatchesTheCpuFloatSolve) {
    WEFT_REQUIRE_GPU();
    const ContactScene s = make_scene({}, kParityTolerance);
    const std::size_t n = s.flat.vertex_count;
    const double tolerance = s.model.settings.solver.cg_tolerance;
    const State cpu = cpu_substeps<float>(s, s.contacts, tolerance);
    const State exact = cpu_substeps<double>(s, s.contacts, 1e-10);
    const State no_contacts = cpu_substeps<float>(s, {}, tolerance);
    ASSERT_EQ(cpu.stats.cg_not_converged, 0);
    ASSERT_EQ(exact.stats.cg_not_converged, 0);
    double dv_max = 0.0;
    for (std::size_t i = 0; i < n; ++i) dv_max = std::max(dv_max, physics::length(exact.v[i] - s.v0[i]));
    const double cpu_error = max_distance(cpu.v, exact.v);
    const double effect = max_distance(cpu.v, no_contacts.v);
    for (const cuda::PcgLoop loop : {cuda::PcgLoop::OneLaunch, cuda::PcgLoop::PerKernel}) {
        SCOPED_TRACE(name(loop));
        auto gpu = gpu_solver(s, loop);
        gpu->set_contacts(s.contacts, s.kinematic_x1, s.kinematic_v);
        StepStats stats;
        gpu->substep(s.model, 0.0, kH, stats);
        const State g = gpu_read(*gpu, n);
        const double gpu_error = max_distance(g.v, exact.v);
        const double diff = max_distance(g.v, cpu.v);
        const double bound = 3.0 * cpu_error + tolerance * dv_max;
        std::printf("[ parity   ] %s: %d contacts; max |dv| %.3e m/s; |v_gpu - v_cpu| %.3e, |v_cpu - v_exact| %.3e, "
                    "|v_gpu - v_exact| %.3e (bound %.3e); contacts change v by %.3e; CG %d (gpu) / %d (cpu) iterations\n",
                    name(loop), stats.collision.contacts, dv_max, diff, cpu_error, gpu_error, bound, effect,
                    stats.cg_iterations, cpu.stats.cg_iterations);
        EXPECT_EQ(stats.collision.contacts, static_cast<int>(s.contacts.size()));
        EXPECT_EQ(stats.cg_not_converged, 0);
        EXPECT_FALSE(stats.non_finite);
        EXPECT_LE(gpu_error, bound);
        EXPECT_LE(diff, bound + cpu_error);
        EXPECT_GT(effect, 20.0 * (bound + cpu_error)) << "the contacts barely matter: the comparison proves little";
        // Positions follow from velocities (x = x0 + h·v); checked so a wrong commit cannot hide.
        EXPECT_LE(max_distance(g.x, cpu.x), kH * (bound + cpu_error) + 1e-6);
    }
}

TEST(CudaContacts, BothCgLoopsAgree) {
    // Same system, dot products summed in another order: they differ as two stopping points of CG do.
    WEFT_REQUIRE_GPU();
    const ContactScene s = make_scene({}, kParityTolerance);
    const std::size_t n = s.flat.vertex_count;
    const double tolerance = s.model.settings.solver.cg_tolerance;
    const State cpu = cpu_substeps<float>(s, s.contacts, tolerance, 3);
    const State exact = cpu_substeps<double>(s, s.contacts, 1e-10, 3);
    ASSERT_EQ(cpu.stats.cg_not_converged, 0);
    ASSERT_EQ(exact.stats.cg_not_converged, 0);
    double dv_max = 0.0;
    for (std::size_t i = 0; i < n; ++i) dv_max = std::max(dv_max, physics::length(exact.v[i] - s.v0[i]));
    const double cpu_error = max_distance(cpu.v, exact.v);
    const double bound = 2.0 * (3.0 * cpu_error + tolerance * dv_max);  // each within the parity test's bound
    State result[2];
    int iterations[2] = {0, 0};
    const cuda::PcgLoop loops[2] = {cuda::PcgLoop::OneLaunch, cuda::PcgLoop::PerKernel};
    for (int k = 0; k < 2; ++k) {
        auto gpu = gpu_solver(s, loops[k]);
        gpu->set_contacts(s.contacts, s.kinematic_x1, s.kinematic_v);
        ASSERT_EQ(gpu->persistent_grid() > 0, k == 0);
        for (int step = 0; step < 3; ++step) {
            StepStats stats;
            gpu->substep(s.model, step * kH, kH, stats);
            iterations[k] += stats.cg_iterations;
        }
        result[k] = gpu_read(*gpu, n);
    }
    const double d = max_distance(result[0].v, result[1].v);
    std::printf("[ loops    ] one-launch against per-kernel after 3 substeps: |dv| %.3e m/s (bound %.3e; CPU float "
                "against double %.3e); %d against %d CG iterations\n",
                d, bound, cpu_error, iterations[0], iterations[1]);
    EXPECT_LE(d, bound);
    // The stopping rule is the same; rounding moves the exit, by more than on the fabric alone because
    // the residual of this stiff system creeps along near the tolerance for a while.
    EXPECT_NEAR(iterations[0], iterations[1], 0.1 * iterations[1] + 10);
}

TEST(CudaContacts, SameBitsOnEveryRunAndWithOrWithoutTheGraph) {
    // Five substeps whose contact count changes every time (a prefix of the list, none at all, then
    // more than the capacity held): one run with the graph, one without, and the graph run again.
    // Everything must agree bit for bit; the count changes must replay one graph, and only the growth
    // may capture a new one.
    WEFT_REQUIRE_GPU();
    const ContactScene s = make_scene();
    const std::size_t n = s.flat.vertex_count, m = s.contacts.size();
    std::vector<ProximityContact> doubled = s.contacts;  // every spring twice: past the capacity
    doubled.insert(doubled.end(), s.contacts.begin(), s.contacts.end());
    const std::size_t counts[] = {m / 2, m, m / 4, 0, 2 * m};
    for (const cuda::PcgLoop loop : {cuda::PcgLoop::OneLaunch, cuda::PcgLoop::PerKernel}) {
        SCOPED_TRACE(name(loop));
        auto graph = gpu_solver(s, loop, true);
        auto graph_again = gpu_solver(s, loop, true);
        auto host = gpu_solver(s, loop, false);
        for (auto* g : {graph.get(), graph_again.get(), host.get()}) g->reserve_contacts(m, s.kinematic_x1.size());
        const std::size_t capacity = graph->contact_capacity();
        ASSERT_GE(capacity, m);
        ASSERT_LT(capacity, 2 * m) << "the last substep must grow the list";
        int captures_before_growth = 0;
        for (int step = 0; step < 5; ++step) {
            SCOPED_TRACE(step);
            for (auto* g : {graph.get(), graph_again.get(), host.get()}) {
                g->set_contacts(prefix(doubled, counts[step]), s.kinematic_x1, s.kinematic_v);
                StepStats stats;
                g->substep(s.model, step * kH, kH, stats);
                EXPECT_EQ(stats.collision.contacts, static_cast<int>(counts[step]));
                EXPECT_FALSE(stats.non_finite);
            }
            const State a = gpu_read(*graph, n), b = gpu_read(*graph_again, n), c = gpu_read(*host, n);
            EXPECT_TRUE(same_bits(a, b)) << "two graph runs differ by " << max_distance(a.v, b.v) << " m/s";
            EXPECT_TRUE(same_bits(a, c)) << "graph and host-driven runs differ by " << max_distance(a.v, c.v) << " m/s";
            EXPECT_FALSE(host->graph_active());
            if (step >= 1) {
                EXPECT_TRUE(graph->graph_active()) << "the graph is not running";
            }
            if (step == 1) captures_before_growth = graph->graph_captures();
            if (step >= 2 && step < 4) {
                EXPECT_EQ(graph->graph_captures(), captures_before_growth) << "re-captured for a count";
            }
        }
        EXPECT_GT(graph->contact_capacity(), capacity);
        EXPECT_EQ(graph->graph_captures(), captures_before_growth + 1) << "growth must re-capture once";
        EXPECT_EQ(host->graph_captures(), 0);
    }
}

TEST(CudaContacts, AFloodOfContactsIsGivenBackAfterATrimWindow) {
    // A list grown for a flood (a fold's one frame) is cut back once a trim window of substeps
    // needed far less (weft/backend/buffer_trim.h), re-capturing the graph once; the steps before
    // and after are the bits of a solver that never held the flood.
    WEFT_REQUIRE_GPU();
    const ContactScene s = make_scene();
    const std::size_t n = s.flat.vertex_count, m = s.contacts.size();
    auto flooded = gpu_solver(s, cuda::PcgLoop::OneLaunch, true);
    auto steady = gpu_solver(s, cuda::PcgLoop::OneLaunch, true);
    flooded->reserve_contacts(200000, s.kinematic_x1.size());
    steady->reserve_contacts(m, s.kinematic_x1.size());
    const std::size_t flood = flooded->contact_capacity();
    ASSERT_GE(flood, 200000u);
    int captures = 0;
    for (std::size_t step = 0; step <= kTrimPeriod; ++step) {
        for (auto* g : {flooded.get(), steady.get()}) {
            g->reserve_contacts(m, s.kinematic_x1.size());  // as each substep's detection does
            g->set_contacts(s.contacts, s.kinematic_x1, s.kinematic_v);
            StepStats stats;
            g->substep(s.model, static_cast<double>(step) * kH, kH, stats);
            ASSERT_FALSE(stats.non_finite) << "substep " << step;
        }
        if (step == 2) captures = flooded->graph_captures();
    }
    std::printf("[ trim     ] contact list: %zu pairs of capacity after the flood, %zu after %zu substeps of %zu\n", flood,
                flooded->contact_capacity(), kTrimPeriod + 1, m);
    // The cut keeps kTrimKeep × the window's peak (m), rounded up to a power of two: at most twice that.
    EXPECT_LT(flooded->contact_capacity(), flood) << "the flood's capacity was kept";
    EXPECT_LE(flooded->contact_capacity(), 2 * kTrimKeep * m);
    EXPECT_GE(flooded->contact_capacity(), kTrimKeep * m);
    EXPECT_EQ(flooded->graph_captures(), captures + 1) << "the cut re-captures the graph once";
    const State a = gpu_read(*flooded, n), b = gpu_read(*steady, n);
    EXPECT_TRUE(same_bits(a, b)) << "the capacity changed the results by " << max_distance(a.v, b.v) << " m/s";
}

TEST(CudaContacts, NoContactsGiveTodaysBitsExactly) {
    // A solver with room for contacts but none in the list runs the contact kernels (they return at
    // once) and the contact variants of the PCG kernels: it must step exactly as one without a list.
    WEFT_REQUIRE_GPU();
    const ContactScene s = make_scene();
    const std::size_t n = s.flat.vertex_count;
    for (const cuda::PcgLoop loop : {cuda::PcgLoop::OneLaunch, cuda::PcgLoop::PerKernel}) {
        SCOPED_TRACE(name(loop));
        auto plain = gpu_solver(s, loop);
        auto empty = gpu_solver(s, loop);
        empty->reserve_contacts(s.contacts.size(), s.kinematic_x1.size());
        empty->set_contacts({}, s.kinematic_x1, s.kinematic_v);
        ASSERT_EQ(plain->contact_capacity(), 0u);
        ASSERT_GT(empty->contact_capacity(), 0u);
        for (int step = 0; step < 4; ++step) {
            StepStats a, b;
            plain->substep(s.model, step * kH, kH, a);
            empty->substep(s.model, step * kH, kH, b);
            EXPECT_EQ(a.cg_iterations, b.cg_iterations);
            EXPECT_EQ(b.collision.contacts, 0);
        }
        EXPECT_TRUE(plain->graph_active());
        EXPECT_TRUE(empty->graph_active());
        const State a = gpu_read(*plain, n), b = gpu_read(*empty, n);
        EXPECT_TRUE(same_bits(a, b)) << "differ by " << max_distance(a.v, b.v) << " m/s";
    }
}

TEST(CudaContacts, UploadRejectsVerticesOutOfRange) {
    WEFT_REQUIRE_GPU();
    const ContactScene s = make_scene({.cells = 8});
    auto gpu = gpu_solver(s, cuda::PcgLoop::Auto);
    std::vector<ProximityContact> bad(1);
    bad[0].vertex[3] = static_cast<std::uint32_t>(s.flat.vertex_count + 4);  // 4 kinematic vertices: ids n..n+3
    EXPECT_THROW(gpu->set_contacts(bad, s.kinematic_x1, s.kinematic_v), Error);
    EXPECT_THROW(gpu->set_contacts(bad, s.kinematic_x1, {}), Error);
    EXPECT_EQ(gpu->contact_capacity(), 0u);
}

// ---- cost -----------------------------------------------------------------------------------------

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

// A measurement, not a test (timings do not belong in assertions, and it takes a minute): disabled
// in the suite, run with --gtest_also_run_disabled_tests --gtest_filter='*Cost*'. To move into
// bench/ with the wiring of the GPU narrow phase.
TEST(CudaContacts, DISABLED_CostOfTheContactPath) {
    // Substep times (wall clock, host to host, and the solve stage from the graph's events) of the same
    // scene without a contact list, with room for contacts but none in use, and with the contacts on;
    // per CG iteration too, since contacts change how many iterations a solve takes. Printed for
    // docs/results.md.
    WEFT_REQUIRE_GPU();
    // The default scene (two whole sheets in contact, 12 pairs a vertex, a stiff system), and two
    // larger ones with a quarter of each sheet in contact, the second past the 200K vertices where
    // the per-kernel loop becomes the default.
    for (const SceneSize size : {SceneSize{}, SceneSize{150, 0.0015, 0.001, 0.05, 0.25}, SceneSize{320, 0.0008, 0.0005, 0.02, 0.25}}) {
        const ContactScene s = make_scene(size);
        const int steps = size.cells > 100 ? 10 : 24;
        const std::size_t m = s.contacts.size();
        for (const cuda::PcgLoop loop : {cuda::PcgLoop::OneLaunch, cuda::PcgLoop::PerKernel}) {
            double wall_ms[3] = {}, solve_ms[3] = {}, per_iteration_us[3] = {}, start_ms[3] = {}, forces_ms[3] = {};
            for (int mode = 0; mode < 3; ++mode) {
                auto gpu = gpu_solver(s, loop);
                if (mode >= 1) gpu->reserve_contacts(m, s.kinematic_x1.size());
                if (mode == 2) gpu->set_contacts(s.contacts, s.kinematic_x1, s.kinematic_v);
                std::vector<double> wall, solve, iteration, begin, forces;
                for (int step = 0; step < steps; ++step) {
                    StepStats stats;
                    const auto start = std::chrono::steady_clock::now();
                    gpu->substep(s.model, step * kH, kH, stats);
                    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
                    if (step < 3) continue;  // warm-up and graph capture
                    wall.push_back(ms);
                    solve.push_back(stats.ms(Stage::Solve));
                    begin.push_back(stats.ms(Stage::Kinematics));  // with the incidence build
                    forces.push_back(stats.ms(Stage::Forces));     // with the pair evaluation
                    iteration.push_back(1e3 * stats.ms(Stage::Solve) / std::max(1, stats.cg_iterations));
                }
                wall_ms[mode] = median(wall);
                solve_ms[mode] = median(solve);
                per_iteration_us[mode] = median(iteration);
                start_ms[mode] = median(begin);
                forces_ms[mode] = median(forces);
            }
            std::printf("[ cost     ] %zu vertices, %s CG: substep %.3f ms without a list, %.3f ms with 0 contacts, "
                        "%.3f ms with %zu contacts; solve %.3f / %.3f / %.3f ms; per CG iteration %.2f / %.2f / %.2f us; "
                        "start (incidence) %.3f / %.3f / %.3f ms; forces (pair evaluation) %.3f / %.3f / %.3f ms\n",
                        s.flat.vertex_count, name(loop), wall_ms[0], wall_ms[1], wall_ms[2], m, solve_ms[0], solve_ms[1],
                        solve_ms[2], per_iteration_us[0], per_iteration_us[1], per_iteration_us[2], start_ms[0], start_ms[1],
                        start_ms[2], forces_ms[0], forces_ms[1], forces_ms[2]);
        }
    }
}

}  // namespace
}  // namespace weft
