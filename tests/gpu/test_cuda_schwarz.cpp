// The multilevel additive Schwarz preconditioner on the cuda backend (schwarz_kernels.cu): the same
// levels as the CPU backend's, far fewer CG iterations than block-Jacobi, the same bits on every run
// and in both CG loops, a live switch between preconditioners, and proximity contacts in the solve.
// (Parity with the CPU backend, MAS on both, is in test_cuda_backend.cpp.)
#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "backend_access.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/model.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/error.h"

#include "gpu_test_util.h"

namespace weft {
namespace {

using test::make_world;

const std::vector<std::string> kMasFlag{"cloth.flag.mesh.grid.cells=[120, 72]", "solver.preconditioner=mas"};
const std::vector<std::string> kJacobiFlag{"cloth.flag.mesh.grid.cells=[120, 72]", "solver.preconditioner=jacobi"};

cuda::DeviceSolver& device_solver_of(World& world) {
    cuda::DeviceSolver* solver = cuda::device_solver(world.backend());
    if (solver == nullptr) throw Error("not a cuda world");
    return *solver;
}

bool same_bits(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3d)) == 0;
}

struct Totals {
    long iterations = 0;
    int not_converged = 0, pivot_failures = 0, non_finite = 0;
    double precondition_ms = 0.0;
    void add(const StepStats& s) {
        iterations += s.cg_iterations;
        not_converged += s.cg_not_converged;
        pivot_failures += s.preconditioner_pivot_failures;
        non_finite += s.non_finite ? 1 : 0;
        precondition_ms += s.ms(Stage::Precondition);
    }
};

TEST(CudaSchwarz, LevelsAreTheCpuBackends) {
    WEFT_REQUIRE_GPU();
    const auto world = make_world("flag", "cuda", kMasFlag);
    (void)world->step();
    const cuda::DeviceSolver& solver = device_solver_of(*world);
    ASSERT_TRUE(solver.schwarz_active());
    const SchwarzHierarchy& gpu = solver.schwarz().hierarchy();
    // The CPU backend builds its levels from the same flattened model with the same function.
    const FlatModel flat = flatten(world->model());
    const SchwarzHierarchy cpu = build_schwarz_hierarchy(flat.initial_positions, flat.pattern, cuda::kSchwarzMaxLevels);
    ASSERT_EQ(gpu.levels(), cpu.levels());
    EXPECT_EQ(gpu.order, cpu.order);
    for (int l = 0; l < cpu.levels(); ++l) {
        const SchwarzLevel &a = gpu.level[static_cast<std::size_t>(l)], &b = cpu.level[static_cast<std::size_t>(l)];
        EXPECT_EQ(a.nodes, b.nodes) << "level " << l;
        EXPECT_EQ(a.parent, b.parent) << "level " << l;
        EXPECT_EQ(a.source, b.source) << "level " << l;
        EXPECT_EQ(a.dense_block, b.dense_block) << "level " << l;
        EXPECT_EQ(solver.view().mas.level[l].domains, b.domains()) << "level " << l;
    }
    std::printf("[ levels   ] %d levels, nodes", cpu.levels());
    for (int l = 0; l < cpu.levels(); ++l) std::printf(" %u", cpu.nodes(l));
    std::printf("\n");
}

TEST(CudaSchwarz, ConvergesInFarFewerIterationsThanJacobi) {
    WEFT_REQUIRE_GPU();
    Totals totals[2];
    for (const bool mas : {false, true}) {
        const auto world = make_world("flag", "cuda", mas ? kMasFlag : kJacobiFlag);
        for (int f = 0; f < 20; ++f) totals[mas ? 1 : 0].add(world->step());
    }
    std::printf("[ flag 8.8K] 20 frames: jacobi %ld CG iterations, mas %ld (precondition %.2f ms in all)\n",
                totals[0].iterations, totals[1].iterations, totals[1].precondition_ms);
    for (const Totals& t : totals) {
        EXPECT_EQ(t.not_converged, 0);
        EXPECT_EQ(t.non_finite, 0);
    }
    EXPECT_EQ(totals[1].pivot_failures, 0);
    EXPECT_LT(2 * totals[1].iterations, totals[0].iterations);
    EXPECT_GT(totals[1].precondition_ms, 0.0);
}

TEST(CudaSchwarz, SameBitsOnEveryRunAndInBothLoops) {
    WEFT_REQUIRE_GPU();
    const auto a = make_world("flag", "cuda", kMasFlag);
    const auto b = make_world("flag", "cuda", kMasFlag);
    const auto host_loop = make_world("flag", "cuda", kMasFlag);
    cuda::as_cuda(host_loop->backend())->set_use_graph(false);
    for (int f = 0; f < 10; ++f) {
        (void)a->step();
        (void)b->step();
        (void)host_loop->step();
    }
    EXPECT_TRUE(cuda::as_cuda(a->backend())->graph_active());
    EXPECT_FALSE(cuda::as_cuda(host_loop->backend())->graph_active());
    EXPECT_TRUE(same_bits(a->positions(0), b->positions(0)));
    EXPECT_TRUE(same_bits(a->positions(0), host_loop->positions(0)));
}

TEST(CudaSchwarz, OneLaunchAndPerKernelLoopsAgree) {
    // The same iteration with the dots summed in another order: float rounding only (compared after
    // one frame of the fluttering flag and five of the drape, as for block-Jacobi in
    // test_cuda_backend.cpp).
    WEFT_REQUIRE_GPU();
    for (const std::string scene : {"flag", "drape"}) {
        const int frames = scene == "flag" ? 1 : 5;
        const std::vector<std::string> overrides{"solver.preconditioner=mas"};
        const auto one = make_world(scene, "cuda", overrides);
        const auto per = make_world(scene, "cuda", overrides);
        cuda::as_cuda(one->backend())->set_pcg_loop(cuda::PcgLoop::OneLaunch);
        cuda::as_cuda(per->backend())->set_pcg_loop(cuda::PcgLoop::PerKernel);
        long iterations_one = 0, iterations_per = 0;
        for (int f = 0; f < frames; ++f) {
            iterations_one += one->step().cg_iterations;
            iterations_per += per->step().cg_iterations;
        }
        // At least one block an SM, so that the warp-per-domain phases spread over the device.
        int sms = 0;
        ASSERT_EQ(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, 0), cudaSuccess);
        EXPECT_GE(device_solver_of(*one).persistent_grid(), sms) << scene;
        EXPECT_EQ(device_solver_of(*per).persistent_grid(), 0) << scene;
        const auto xo = one->positions(0), xp = per->positions(0);
        double d = 0.0, lo = 1e30, hi = -1e30;
        for (std::size_t i = 0; i < xo.size(); ++i) {
            d = std::max(d, math::length(xo[i] - xp[i]));
            lo = std::min(lo, xo[i][1]);
            hi = std::max(hi, xo[i][1]);
        }
        std::printf("[ loops    ] %s: one-launch against per-kernel MAS after %d frames: %.3e m, %ld against %ld "
                    "iterations\n",
                    scene.c_str(), frames, d, iterations_one, iterations_per);
        EXPECT_LT(d, 1e-4 * std::max(1.0, hi - lo)) << scene;
        EXPECT_NEAR(double(iterations_one), double(iterations_per), 0.05 * double(iterations_per) + 4) << scene;
    }
}

TEST(CudaSchwarz, SwitchesPreconditionerLive) {
    WEFT_REQUIRE_GPU();
    const auto world = make_world("flag", "cuda", kJacobiFlag);
    cuda::DeviceSolver& solver = device_solver_of(*world);
    Totals totals;
    for (const Preconditioner p : {Preconditioner::Jacobi, Preconditioner::Schwarz, Preconditioner::Jacobi,
                                   Preconditioner::Schwarz}) {
        world->settings().solver.preconditioner = p;
        for (int f = 0; f < 4; ++f) totals.add(world->step());
        EXPECT_EQ(solver.schwarz_active(), p == Preconditioner::Schwarz);
    }
    EXPECT_EQ(totals.not_converged, 0);
    EXPECT_EQ(totals.non_finite, 0);
}

TEST(CudaSchwarz, AutoPicksMasFromTheMeasuredSize) {
    WEFT_REQUIRE_GPU();
    // The shipped flag (1.2K vertices) stays on block-Jacobi; at 400 × 250 cells (100,651 vertices)
    // `auto` takes the Schwarz preconditioner.
    const auto small = make_world("flag", "cuda", {"solver.preconditioner=auto"});
    const auto large = make_world("flag", "cuda", {"solver.preconditioner=auto", "cloth.flag.mesh.grid.cells=[400, 250]"});
    (void)small->step();
    (void)large->step();
    ASSERT_LT(small->model().cloths[0].fabric->vertex_count(), kAutoSchwarzMinVertices);
    ASSERT_GE(large->model().cloths[0].fabric->vertex_count(), kAutoSchwarzMinVertices);
    EXPECT_FALSE(device_solver_of(*small).schwarz_active());
    EXPECT_TRUE(device_solver_of(*large).schwarz_active());
    EXPECT_NE(large->device_description().find("MAS"), std::string::npos) << large->device_description();
}

TEST(CudaSchwarz, ReusedFactorsStillConverge) {
    // The hanging sheet settles slowly, so factors a few substeps old still fit (on the fluttering flag
    // they do not: docs/results.md measures how the iterations grow there).
    WEFT_REQUIRE_GPU();
    std::vector<Vec3d> x[2];
    long iterations[2] = {0, 0};
    for (const int refresh : {1, 4}) {
        const std::vector<std::string> overrides{"solver.preconditioner=mas",
                                                 "solver.preconditioner_refresh=" + std::to_string(refresh)};
        const auto world = make_world("hanging", "cuda", overrides);
        Totals totals;
        for (int f = 0; f < 30; ++f) totals.add(world->step());
        EXPECT_EQ(totals.not_converged, 0) << "refresh " << refresh;
        EXPECT_EQ(totals.non_finite, 0) << "refresh " << refresh;
        iterations[refresh == 4 ? 1 : 0] = totals.iterations;
        x[refresh == 4 ? 1 : 0] = world->positions(0);
    }
    double largest = 0.0, lo = 1e30, hi = -1e30;
    for (std::size_t i = 0; i < x[0].size(); ++i) {
        largest = std::max(largest, math::length(x[1][i] - x[0][i]));
        lo = std::min(lo, x[0][i][1]);
        hi = std::max(hi, x[0][i][1]);
    }
    std::printf("[ refresh  ] 30 frames of the hanging sheet: %ld CG iterations refactoring every substep, %ld every "
                "4th; states %.2e m apart\n",
                iterations[0], iterations[1], largest);
    EXPECT_FALSE(same_bits(x[0], x[1]));  // the factors really were reused
    EXPECT_LT(largest, 1e-4 * (hi - lo));  // two CG stopping points of a settling sheet
}

TEST(CudaSchwarz, SolvesWithProximityContacts) {
    WEFT_REQUIRE_GPU();
    // Four sheets dropped on a ball: every layer touches the next, so each solve carries contacts.
    const std::vector<std::string> overrides{"solver.preconditioner=mas", "cloth.sheets.repeat.count=4"};
    const auto world = make_world("layers", "cuda", overrides);
    Totals totals;
    int contacts = 0;
    for (int f = 0; f < 60; ++f) {
        const StepStats& s = world->step();
        totals.add(s);
        contacts = std::max(contacts, s.collision.contacts);
    }
    std::printf("[ layers   ] 60 frames with mas: %ld CG iterations, up to %d contacts\n", totals.iterations, contacts);
    EXPECT_GT(contacts, 0);
    EXPECT_EQ(totals.not_converged, 0);
    EXPECT_EQ(totals.non_finite, 0);
    EXPECT_EQ(totals.pivot_failures, 0);
}

}  // namespace
}  // namespace weft
