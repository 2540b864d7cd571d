// The CUDA backend across parts (cuda/src/multi/multi_solver.h): G parts on one GPU (the test
// mode, any GPU host; G = 2, 3, 4, 8) and G parts on G GPUs (2, 4, 8, as the host has them)
// against one GPU over up to 100 steps of shipped scenes;
// determinism for a fixed G; the parts' bits independent of where the parts run; clear errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cuda_check.h"
#include "gpu_test_util.h"
#include "backend_access.h"
#include "multi/multi_gpu_backend.h"
#include "multi/multi_solver.h"
#include "weft/backend/backend.h"
#include "weft/backend/energy_audit.h"
#include "weft/error.h"
#include "weft/cloth.h"
#include "weft/fabric.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

struct Trajectory {
    std::vector<std::vector<Vec3d>> x;  // per cloth
    StepStats last;
    int not_converged = 0;
    bool non_finite = false;
};

/// Sets or clears the test mode (every part on the first device) for the backends created after it.
void parts_on_one_device(bool on) {
    if (on)
        setenv(cuda::multi::kPartsOnOneDeviceEnv, "1", 1);
    else
        unsetenv(cuda::multi::kPartsOnOneDeviceEnv);
}

/// The world of shipped scene `scene` with `overrides` on `gpus` parts (all on one device, or one a device).
std::unique_ptr<World> make(const std::string& scene, const std::vector<std::string>& overrides, int gpus, bool one_device) {
    parts_on_one_device(one_device);
    BackendOptions options;
    options.gpus = gpus;
    auto world = build_world(load_scene(test::scene_file(scene), overrides), "cuda", options);
    parts_on_one_device(false);
    return world;
}

Trajectory run(const std::string& scene, const std::vector<std::string>& overrides, int gpus, int steps, bool one_device = true) {
    auto world = make(scene, overrides, gpus, one_device);
    Trajectory out;
    for (int s = 0; s < steps; ++s) {
        out.last = world->step();
        out.not_converged += out.last.cg_not_converged;
        out.non_finite = out.non_finite || out.last.non_finite;
    }
    for (std::size_t c = 0; c < world->cloth_count(); ++c) out.x.push_back(world->positions(c));
    return out;
}

/// Largest distance between the two runs' vertices, m.
double largest_difference(const Trajectory& a, const Trajectory& b) {
    double worst = 0.0;
    EXPECT_EQ(a.x.size(), b.x.size());
    for (std::size_t c = 0; c < std::min(a.x.size(), b.x.size()); ++c) {
        EXPECT_EQ(a.x[c].size(), b.x[c].size());
        for (std::size_t i = 0; i < std::min(a.x[c].size(), b.x[c].size()); ++i) {
            const Vec3d d = a.x[c][i] - b.x[c][i];
            const double dist = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
            worst = std::isfinite(dist) ? std::max(worst, dist) : 1e30;
        }
    }
    return worst;
}

bool same_bits(const Trajectory& a, const Trajectory& b) {
    if (a.x.size() != b.x.size()) return false;
    for (std::size_t c = 0; c < a.x.size(); ++c)
        if (a.x[c] != b.x[c]) return false;
    return true;
}

/// Block-Jacobi on both sides (the parts' preconditioner, for now), and a tight CG tolerance so
/// that the comparison measures the parts' logic rather than where two CG recurrences stop.
std::vector<std::string> with(std::vector<std::string> overrides) {
    overrides.insert(overrides.begin(), {"solver.preconditioner=\"jacobi\"", "solver.cg_tolerance=1e-6"});
    return overrides;
}


/// The worst, over `steps` steps, of the gap between one step on one GPU and the same step on
/// `gpus` parts from the same state, relative to how far the step moved the cloth. Both worlds
/// are set to the one-GPU world's state before each step (so both start their CG cold): the
/// flag flaps and the drape's folds choose a side, so whole trajectories part at any rounding
/// difference (measured: 1e-13 m after one step of drape, 0.1 m after 100), while one step's gap
/// is what the parts' logic owns.
struct StepGaps {
    double worst = 0.0;  ///< the largest step gap over the step's largest move
    long long iterations_one = 0, iterations_split = 0;  ///< CG iterations summed over the steps
    int recuts = 0;  ///< re-cuts of the split world's parts by contact load
    long long contacts_one = 0, contacts_split = 0;  ///< cloth contacts summed over the steps
};

StepGaps compare_steps(World& one_world, World& other_world, int steps, bool nudge_other = false);

StepGaps step_gaps(const std::string& scene, const std::vector<std::string>& overrides, int gpus, bool one_device, int steps) {
    auto one = make(scene, overrides, 1, false);
    auto split = make(scene, overrides, gpus, one_device);
    return compare_steps(*one, *split, steps);
}

/// `x` with every coordinate moved by one float ulp (up on even vertices, down on odd ones): a
/// start that a float solver cannot tell from `x` by more than rounding.
std::vector<Vec3d> nudged(const std::vector<Vec3d>& x) {
    std::vector<Vec3d> out = x;
    for (std::size_t i = 0; i < out.size(); ++i) {
        const float towards = (i % 2 == 0) ? 1e30F : -1e30F;
        out[i].x = std::nextafter(static_cast<float>(x[i].x), towards);
        out[i].y = std::nextafter(static_cast<float>(x[i].y), towards);
        out[i].z = std::nextafter(static_cast<float>(x[i].z), towards);
    }
    return out;
}

/// The worst step gap between two worlds stepped from the same states (one's), as step_gaps; with
/// `nudge_other`, the other world starts every step from one's state moved by one float ulp.
StepGaps compare_steps(World& one_world, World& other_world, int steps, bool nudge_other) {
    World* one = &one_world;
    World* split = &other_world;
    const std::string scene = "this scene";
    StepGaps out;
    for (int s = 0; s < steps; ++s) {
        double moved = 0.0, gap = 0.0;
        std::vector<std::vector<Vec3d>> start(one->cloth_count());
        for (std::size_t c = 0; c < one->cloth_count(); ++c) {
            start[c] = one->positions(c);
            const std::vector<Vec3d> v = one->velocities(c);
            one->set_state(c, start[c], v);
            split->set_state(c, nudge_other ? nudged(start[c]) : start[c], v);
        }
        const StepStats& a = one->step();
        const StepStats& b = split->step();
        out.iterations_one += a.cg_iterations;
        out.iterations_split += b.cg_iterations;
        out.recuts += b.collision.parts_recut;
        out.contacts_one += a.collision.contacts;
        out.contacts_split += b.collision.contacts;
        EXPECT_FALSE(a.non_finite || b.non_finite) << scene << ", step " << s;
        EXPECT_EQ(a.cg_not_converged, 0) << scene << ", step " << s;
        EXPECT_EQ(b.cg_not_converged, 0) << scene << ", step " << s;
        for (std::size_t c = 0; c < one->cloth_count(); ++c) {
            const std::vector<Vec3d> xa = one->positions(c), xb = split->positions(c);
            for (std::size_t i = 0; i < xa.size(); ++i) {
                moved = std::max(moved, length(xa[i] - start[c][i]));
                gap = std::max(gap, length(xa[i] - xb[i]));
            }
        }
        if (moved > 0.0) out.worst = std::max(out.worst, gap / moved);
    }
    return out;
}

/// One step's gap may be this share of the step's largest move. Both solves stop at a relative
/// residual of 1e-6 in the preconditioner's norm; on the flag's stiff system (about 500
/// block-Jacobi iterations) that leaves each Δv a few parts in 1e4 from the exact one, and the
/// gap is the sum of both errors. A wrong ghost or a missed element changes forces by their own
/// size: a gap of the order of the move.
constexpr double kStepTolerance = 2e-2;

TEST(MultiGpuSolver, PartsOnOneGpuFollowOneGpuStepByStepOver100Steps) {
    WEFT_REQUIRE_GPU();
    for (const char* scene : {"flag", "drape"}) {
        for (const int parts : {2, 3}) {
            const double worst = step_gaps(scene, with({}), parts, true, 100).worst;
            std::printf("[ multi    ] %s: %d parts on one GPU, 100 steps: worst step gap %.3g of the step's move\n", scene, parts,
                        worst);
            EXPECT_LT(worst, kStepTolerance) << scene << ", " << parts << " parts";
        }
    }
}

// Contacts at the triangles' centroids across parts: a triangle's centroid contact goes to its
// corners' rows on the parts that own them, and is counted once (by its first corner's owner).
TEST(MultiGpuSolver, FaceContactsAcrossPartsFollowOneGpu) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> faces{"solver.face_contacts=true", "cloth.cloth.mesh.grid.cells=[12,12]"};
    auto one = make("drape", faces, 1, false);
    auto split = make("drape", faces, 2, true);
    for (int f = 0; f < 14; ++f) (void)one->step();  // onto the ball (frame 13); compare_steps hands the state over
    const StepGaps g = compare_steps(*one, *split, 30);
    const StepStats& last = split->step();
    std::printf("[ multi    ] drape 13 × 13 with face contacts, 2 parts on one GPU, 30 steps on the ball: worst step gap %.3g "
                "of the move; %d collider contacts at the end\n",
                g.worst, last.collider_contacts);
    EXPECT_LT(g.worst, kStepTolerance);
    EXPECT_GT(last.collider_contacts, 0) << "the cloth left the ball: the test would prove nothing";
}

// A spinning collider that winds the cloth into folds (sphere): from the same states, the parts take
// the one GPU's steps and find its self-contacts (friction against a moving collider, contacts
// across the cut).
TEST(MultiGpuSolver, WindingOnASpinningBallFollowsOneGpu) {
    WEFT_REQUIRE_GPU();
    auto one = make("sphere", {}, 1, false);
    auto split = make("sphere", {}, 2, true);
    for (int f = 0; f < 60; ++f) (void)one->step();  // landed and winding; compare_steps hands the state over
    const StepGaps g = compare_steps(*one, *split, 30);
    std::printf("[ multi    ] sphere, 2 parts on one GPU, 30 steps from frame 60: worst step gap %.3g of the move; cloth "
                "contacts %lld (one GPU %lld)\n",
                g.worst, g.contacts_split, g.contacts_one);
    EXPECT_LT(g.worst, kStepTolerance);
    EXPECT_GT(g.contacts_one, 0) << "the sheet never folded onto itself: the test would prove nothing";
    EXPECT_NEAR(static_cast<double>(g.contacts_split), static_cast<double>(g.contacts_one), 0.1 * static_cast<double>(g.contacts_one));
}

// The multilevel Schwarz preconditioner across parts: level 1 gathered from every part, so it is the
// one-GPU preconditioner and the CG needs as many iterations (within 10%: the two CG recurrences
// round differently) and lands on the same step.
TEST(MultiGpuSolver, SchwarzAcrossPartsKeepsTheOneGpuIterationCount) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> mas{"solver.preconditioner=\"mas\"", "solver.cg_tolerance=1e-6",
                                       "cloth.flag.mesh.grid.cells=[90,54]"};
    for (const int parts : {2, 3}) {
        const StepGaps g = step_gaps("flag", mas, parts, true, 30);
        std::printf("[ multi    ] flag 91 × 55 with MAS, %d parts on one GPU, 30 steps: worst step gap %.3g of the move, "
                    "CG iterations %lld (one GPU %lld)\n",
                    parts, g.worst, g.iterations_split, g.iterations_one);
        EXPECT_LT(g.worst, kStepTolerance) << parts << " parts";
        EXPECT_LE(static_cast<double>(g.iterations_split), 1.1 * static_cast<double>(g.iterations_one)) << parts << " parts";
        EXPECT_GE(static_cast<double>(g.iterations_split), 0.9 * static_cast<double>(g.iterations_one)) << parts << " parts";
    }
}

// The CG's energy test across parts (multi/part_pcg_terms.cuh): behind a loose residual test, the
// parts go on as far as one GPU does, and the steps still follow one GPU's.
TEST(MultiGpuSolver, TheEnergyStopAcrossPartsGoesAsFarAsOnOneGpu) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> off{"solver.preconditioner=\"jacobi\"", "solver.cg_tolerance=1e-2",
                                       "solver.cg_velocity_tolerance=0"};
    const std::vector<std::string> on{"solver.preconditioner=\"jacobi\"", "solver.cg_tolerance=1e-2",
                                      "solver.cg_velocity_tolerance=1e-4"};
    const StepGaps without = step_gaps("flag", off, 2, true, 20);
    const StepGaps with_test = step_gaps("flag", on, 2, true, 20);
    std::printf("[ multi    ] flag, CG to 1e-2, 2 parts on one GPU, 20 steps: CG iterations %lld (one GPU %lld); with the "
                "energy test at 1e-4 m/s %lld (one GPU %lld), worst step gap %.3g of the move\n",
                without.iterations_split, without.iterations_one, with_test.iterations_split, with_test.iterations_one,
                with_test.worst);
    EXPECT_GT(with_test.iterations_one, without.iterations_one);
    EXPECT_GT(with_test.iterations_split, without.iterations_split);
    EXPECT_NEAR(static_cast<double>(with_test.iterations_split), static_cast<double>(with_test.iterations_one),
                0.1 * static_cast<double>(with_test.iterations_one));
    EXPECT_LT(with_test.worst, kStepTolerance);
}

TEST(MultiGpuSolver, PartsOnOneGpuFollowOneGpuOverTwistsWholeTrajectory) {
    WEFT_REQUIRE_GPU();
    // Twist's first 100 steps (its edges turn; self-contact off: its contact steps are compared below) do
    // not amplify differences: the whole trajectories stay within float rounding of the solves.
    const std::vector<std::string> o = with({"collision.self=false"});
    const Trajectory one = run("twist", o, 1, 100);
    ASSERT_FALSE(one.non_finite);
    for (const int parts : {2, 3}) {
        const Trajectory split = run("twist", o, parts, 100);
        const double gap = largest_difference(one, split);
        std::printf("[ multi    ] twist: %d parts on one GPU, 100 steps: largest gap from one GPU %.3g m\n", parts, gap);
        EXPECT_FALSE(split.non_finite);
        EXPECT_EQ(split.not_converged, one.not_converged);
        EXPECT_LT(gap, 1e-4) << parts << " parts";  // 0.4 m sheet; measured ~3e-6 m
    }
}

TEST(MultiGpuSolver, AFixedPartCountGivesTheSameBitsOnEveryRun) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> o{"solver.preconditioner=\"jacobi\""};
    const Trajectory a = run("flag", o, 3, 30), b = run("flag", o, 3, 30);
    EXPECT_TRUE(same_bits(a, b));
}

TEST(MultiGpuSolver, TwoGpusGiveTheBitsOfTheSamePartsOnOneGpu) {
    WEFT_REQUIRE_GPU();
    if (cuda::devices().size() < 2) GTEST_SKIP() << "one CUDA device: the two-GPU run needs two";
    // The parts run the same kernels on the same data wherever they are, and add the parts' sums
    // in part order: the device count must not change a bit.
    for (const char* scene : {"flag", "drape", "twist"}) {
        const std::vector<std::string> o = with({"collision.self=false"});
        const Trajectory one_device = run(scene, o, 2, 100, true);
        const Trajectory two_devices = run(scene, o, 2, 100, false);
        EXPECT_TRUE(same_bits(one_device, two_devices)) << scene;
        EXPECT_FALSE(two_devices.non_finite) << scene;
    }
    const std::vector<std::string> mas{"solver.preconditioner=\"mas\"", "cloth.flag.mesh.grid.cells=[90,54]"};
    EXPECT_TRUE(same_bits(run("flag", mas, 2, 30, true), run("flag", mas, 2, 30, false))) << "flag with MAS";
    for (const char* scene : {"flag", "drape"}) {
        const double worst = step_gaps(scene, with({}), 2, false, 100).worst;
        std::printf("[ multi    ] %s: 2 parts on 2 GPUs, 100 steps: worst step gap %.3g of the step's move\n", scene, worst);
        EXPECT_LT(worst, kStepTolerance) << scene;
    }
}

// Four and eight parts: the partitions of a 4- and an 8-GPU host. On one GPU (any host) each step
// must land where one GPU's does, with and without contacts; on a host with that many GPUs the
// parts must give the bits of the same parts on one GPU, so the one-GPU run proves the many-GPU one.
TEST(MultiGpuSolver, FourAndEightPartsFollowOneGpu) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> contacts = with({"collision.continuous=false", "solver.substeps=1",
                                                    "cloth.sheets.material.friction=0", "collider.ball.friction=0"});
    for (const int parts : {4, 8}) {
        const double flag = step_gaps("flag", with({}), parts, true, 60).worst;
        const double layers = step_gaps("layers", contacts, parts, true, 40).worst;
        std::printf("[ multi    ] %d parts on one GPU: flag 60 steps worst step gap %.3g, layers with contacts 40 steps %.3g "
                    "of the move\n",
                    parts, flag, layers);
        EXPECT_LT(flag, kStepTolerance) << parts << " parts";
        EXPECT_LT(layers, kStepTolerance) << parts << " parts";
    }
}

TEST(MultiGpuSolver, EveryGpuOfTheHostGivesTheBitsOfTheSamePartsOnOneGpu) {
    WEFT_REQUIRE_GPU();
    const int devices = static_cast<int>(cuda::devices().size());
    if (devices < 4) GTEST_SKIP() << devices << " CUDA device(s): this test needs 4 or 8 (the 2-GPU test covers two)";
    const std::vector<std::string> contacts = with({"collision.continuous=false", "solver.substeps=1",
                                                    "cloth.sheets.material.friction=0", "collider.ball.friction=0"});
    for (const int gpus : {4, 8}) {
        if (gpus > devices) continue;
        const std::vector<std::string> o = with({"collision.self=false"});
        for (const char* scene : {"flag", "twist"}) {
            const Trajectory on_one = run(scene, o, gpus, 60, true), across = run(scene, o, gpus, 60, false);
            EXPECT_TRUE(same_bits(on_one, across)) << scene << " on " << gpus << " GPUs";
            EXPECT_FALSE(across.non_finite) << scene << " on " << gpus << " GPUs";
        }
        EXPECT_TRUE(same_bits(run("layers", contacts, gpus, 40, true), run("layers", contacts, gpus, 40, false)))
            << "layers with contacts on " << gpus << " GPUs";
        const std::vector<std::string> checked = {"collision.check=true"};
        auto world = make("layers", checked, gpus, false);
        std::int64_t intersecting = 0;
        for (int f = 0; f < 45; ++f) intersecting += world->step().collision.remaining_intersections;
        EXPECT_EQ(intersecting, 0) << "layers on " << gpus << " GPUs";
        std::printf("[ multi    ] %d GPUs: flag, twist, layers give the bits of %d parts on one GPU; layers 45 frames, %lld "
                    "intersecting pairs left\n",
                    gpus, gpus, static_cast<long long>(intersecting));
    }
}

TEST(MultiGpuSolver, ReadsAndWritesStateThroughTheOwners) {
    WEFT_REQUIRE_GPU();
    parts_on_one_device(true);
    BackendOptions options;
    options.gpus = 2;
    const std::vector<std::string> jacobi{"solver.preconditioner=\"jacobi\""};
    auto world = build_world(load_scene(test::scene_file("flag"), jacobi), "cuda", options);
    parts_on_one_device(false);
    for (int s = 0; s < 5; ++s) (void)world->step();
    std::vector<Vec3d> x = world->positions(0);
    const std::vector<Vec3d> v(x.size(), Vec3d{});
    // Values a float holds exactly, so that what comes back must be what went in.
    for (std::size_t i = 0; i < x.size(); ++i)
        x[i] = Vec3d{static_cast<float>(x[i].x), static_cast<float>(x[i].y), static_cast<float>(x[i].z + 0.001 * static_cast<double>(i % 7))};
    world->set_state(0, x, v);
    EXPECT_EQ(world->positions(0), x);  // every vertex back from its owner, as written
}

// The energy guard's audit summed over the parts on their devices against the host's audit of
// the same state (read back through the owners): every vertex and element counted once.
TEST(MultiGpuSolver, EnergyAuditCountsEveryVertexAndElementOnce) {
    WEFT_REQUIRE_GPU();
    for (const std::string scene : {"hanging", "drape", "drape with face contacts", "flag"}) {
        const bool faces = scene == "drape with face contacts";
        auto world = faces ? make("drape", {"solver.face_contacts=true", "cloth.cloth.mesh.grid.cells=[12,12]"}, 3, true)
                           : make(scene, {}, 3, true);
        for (int f = 0; f < 15; ++f) (void)world->step();
        if (scene == "flag") test::grab_last_vertex_and_step(*world);  // the grab's power in the audit
        const auto [device, host, scale] = test::audit_device_and_host(*world);
        std::printf("[ multi    ] %s audit on 3 parts: K %.6e G %.6e U %.6e C %.3e P %.3e | host K %.6e G %.6e U %.6e C %.3e P %.3e\n",
                    scene.c_str(), device.kinetic, device.gravity, device.elastic, device.contact, device.external_power, host.kinetic,
                    host.gravity, host.elastic, host.contact, host.external_power);
        // Float terms summed in double: a part counted twice or missed is off by far more.
        EXPECT_NEAR(device.kinetic, host.kinetic, 1e-5 * scale) << scene;
        EXPECT_NEAR(device.gravity, host.gravity, 1e-5 * scale) << scene;
        EXPECT_NEAR(device.elastic, host.elastic, 1e-5 * scale) << scene;
        EXPECT_NEAR(device.contact, host.contact, 1e-5 * scale) << scene;
        EXPECT_NEAR(device.external_power, host.external_power, 1e-3 * host.external_power + 1e-6) << scene;
        EXPECT_EQ(device.bounded, host.bounded) << scene;
    }
}

// The output for rendering: every part writes its owned vertices' positions and normals into one
// buffer on the first GPU (peer writes from the others), no copy through the host; with the CG's
// batches launched directly as well (WEFT_CUDA_GRAPHS=0's path), the same state.
TEST(MultiGpuSolver, EveryPartWritesItsSliceOfTheOutputBuffer) {
    WEFT_REQUIRE_GPU();
    for (const bool one_device : {true, false}) {
        if (!one_device && cuda::devices().size() < 2) continue;
        const int parts = one_device ? 3 : 2;
        auto world = make("flag", with({}), parts, one_device);
        auto graphless = make("flag", with({}), parts, one_device);
        cuda::CudaBackendApi* api = cuda::as_cuda(world->backend());
        ASSERT_NE(api, nullptr);
        cuda::as_cuda(graphless->backend())->set_use_graph(false);
        (void)world->step();  // builds
        (void)graphless->step();
        const std::size_t n = api->vertex_count();
        WEFT_CUDA_CHECK(cudaSetDevice(0));
        void* buffer = nullptr;
        WEFT_CUDA_CHECK(cudaMalloc(&buffer, n * sizeof(cuda::OutputVertex)));
        WEFT_CUDA_CHECK(cudaMemset(buffer, 0xFF, n * sizeof(cuda::OutputVertex)));  // NaN until written
        api->set_output(buffer, sizeof(cuda::OutputVertex));
        for (int s = 0; s < 3; ++s) {
            (void)world->step();
            (void)graphless->step();
        }
        std::vector<cuda::OutputVertex> out(n);
        WEFT_CUDA_CHECK(cudaMemcpy(out.data(), buffer, n * sizeof(cuda::OutputVertex), cudaMemcpyDeviceToHost));
        api->set_output(nullptr, sizeof(cuda::OutputVertex));
        WEFT_CUDA_CHECK(cudaFree(buffer));
        const std::vector<Vec3d> x = world->positions(0);
        ASSERT_EQ(x.size(), n);
        for (std::size_t i = 0; i < n; ++i) {
            EXPECT_EQ(out[i].position[0], static_cast<float>(x[i].x)) << i;
            EXPECT_EQ(out[i].position[1], static_cast<float>(x[i].y)) << i;
            EXPECT_EQ(out[i].position[2], static_cast<float>(x[i].z)) << i;
            const Vec3d normal{out[i].normal[0], out[i].normal[1], out[i].normal[2]};
            const double norm = math::length(normal);
            EXPECT_NEAR(norm, 1.0, 1e-5) << i;
        }
        EXPECT_EQ(graphless->positions(0), x) << "graphs or not: the same kernels, the same bits";
        EXPECT_FALSE(cuda::as_cuda(graphless->backend())->graph_active());
    }
}

// Cloth collisions across parts: the collision stages run on the first GPU over the whole state and
// the contacts enter every part's rows. The exact check after every step of the shipped collision
// scenes (the sizes of the one-GPU collision test) finds no intersection, as on one GPU.
TEST(MultiGpuSolver, CollisionScenesStayIntersectionFreeAcrossParts) {
    WEFT_REQUIRE_GPU();
    struct Case {
        const char* scene;
        std::vector<std::string> overrides;
        int frames;
        int handover = 0;  ///< frames stepped on one GPU first, whose state the parts start from
    };
    const Case cases[] = {
        {"twist", {"cloth.sheet.mesh.grid.cells=[24,24]", "cloth.sheet.mesh.grid.width=0.24", "cloth.sheet.mesh.grid.height=0.24"}, 600},
        {"falling", {}, 45},
        {"layers", {}, 45},
        {"garment", {}, 45},
        // The sheet folds onto itself from about frame 60, but a whole trajectory on parts parts from
        // one GPU's at rounding and may fold much later (measured: no contact in 130 frames on 2 parts
        // where one GPU had 20 a frame; from the same states the parts find the same contacts,
        // WindingOnASpinningBallFollowsOneGpu): the parts start from one GPU's frame 60.
        {"sphere", {}, 60, 60},
    };
    for (const Case& c : cases) {
        std::vector<std::string> o = c.overrides;
        o.push_back("collision.check=true");
        std::unique_ptr<World> world;
        try {
            world = make(c.scene, o, 2, true);
            if (c.handover > 0) {
                auto one = make(c.scene, o, 1, false);
                for (int f = 0; f < c.handover; ++f) (void)one->step();
                for (std::size_t k = 0; k < one->cloth_count(); ++k) world->set_state(k, one->positions(k), one->velocities(k));
            }
        } catch (const Error& e) {
            std::printf("[ multi    ] %s skipped: %s\n", c.scene, e.what());  // an asset this build cannot load
            continue;
        }
        std::int64_t intersecting = 0;
        long long contacts = 0;
        bool non_finite = false;
        for (int f = 0; f < c.frames; ++f) {
            const StepStats& s = world->step();
            intersecting += s.collision.remaining_intersections;
            contacts += s.collision.contacts;
            non_finite = non_finite || s.non_finite;
        }
        std::printf("[ multi    ] %s on 2 parts, %d frames: %lld contacts in all, %lld intersecting pairs left\n", c.scene,
                    c.frames, contacts, static_cast<long long>(intersecting));
        EXPECT_EQ(intersecting, 0) << c.scene;
        EXPECT_FALSE(non_finite) << c.scene;
        EXPECT_GT(contacts, 0) << c.scene << ": the scene never touched (the test would prove nothing)";
    }
}

// With contacts, one step from the same state on parts lands where one GPU's does (the same contact
// list: the same detection over the same state), and two GPUs give the same parts' bits. Proximity
// forces only (collision.continuous = false): the impact zones after the solve are a discontinuous
// rule (a solve a rounding away from one GPU's may or may not cross a CCD threshold), which the
// intersection test above covers instead. One substep a step and no friction: there the step is a
// smooth function of the state and the parts must match one GPU as closely as without contacts.
TEST(MultiGpuSolver, ContactStepsFollowOneGpu) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> o = with({"collision.continuous=false", "solver.substeps=1",
                                             "cloth.sheets.material.friction=0", "collider.ball.friction=0"});
    for (const int parts : {2, 3}) {
        const StepGaps g = step_gaps("layers", o, parts, true, 40);
        std::printf("[ multi    ] layers with contacts, %d parts on one GPU, 40 steps: worst step gap %.3g of the move\n", parts,
                    g.worst);
        EXPECT_LT(g.worst, kStepTolerance) << parts << " parts";
    }
    if (cuda::devices().size() >= 2) {
        EXPECT_TRUE(same_bits(run("layers", o, 2, 40, true), run("layers", o, 2, 40, false))) << "layers on two GPUs";
    }
}

// Re-cutting the parts by contact load (solver.gpu_rebalance; weft/backend/recut_policy.h). A bar
// of 1 re-cuts as soon as the policy allows (three detections in): after the re-cut each step still
// lands where one GPU's does. Stepped freely, a world that re-cuts stays within rounding of one that
// does not (the state and the warm start carry over; a lost ghost or a stale contact row would move
// the cloth by the step's size), stays intersection-free, and its renderer output still holds every
// vertex.
TEST(MultiGpuSolver, ARecutByContactLoadKeepsTheStateAndTheSteps) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> contacts = with({"collision.continuous=false", "solver.substeps=1",
                                                    "cloth.sheets.material.friction=0", "collider.ball.friction=0"});
    std::vector<std::string> eager = contacts, never = contacts;
    eager.push_back("solver.gpu_rebalance=1");
    never.push_back("solver.gpu_rebalance=0");
    for (const int parts : {2, 3}) {
        const StepGaps g = step_gaps("layers", eager, parts, true, 40);
        std::printf("[ multi    ] layers, %d parts on one GPU re-cut %d times in 40 steps: worst step gap %.3g of the move\n",
                    parts, g.recuts, g.worst);
        EXPECT_GE(g.recuts, 1) << parts << " parts: the bar of 1 never re-cut";
        EXPECT_LT(g.worst, kStepTolerance) << parts << " parts";
    }
    for (const bool one_device : {true, false}) {
        if (!one_device && cuda::devices().size() < 2) continue;
        auto recut = make("layers", eager, 2, one_device);
        auto kept = make("layers", never, 2, one_device);
        (void)recut->step();
        const std::size_t n = cuda::as_cuda(recut->backend())->vertex_count();
        WEFT_CUDA_CHECK(cudaSetDevice(0));
        void* buffer = nullptr;
        WEFT_CUDA_CHECK(cudaMalloc(&buffer, n * sizeof(cuda::OutputVertex)));
        cuda::as_cuda(recut->backend())->set_output(buffer, sizeof(cuda::OutputVertex));
        (void)kept->step();
        // The same cut gives the same bits, so the two worlds agree to the bit until the re-cut; the
        // step of the re-cut may differ by rounding (other parts sum in another order).
        int recuts = 0;
        double gap_after_recut = -1.0, move = 0.0;
        for (int s = 1; s < 40 && recuts == 0; ++s) {
            std::vector<std::vector<Vec3d>> before;
            for (std::size_t c = 0; c < kept->cloth_count(); ++c) before.push_back(kept->positions(c));
            const StepStats& a = recut->step();
            (void)kept->step();
            recuts += a.collision.parts_recut;
            if (a.collision.parts_recut > 0) {
                gap_after_recut = 0.0;
                for (std::size_t c = 0; c < recut->cloth_count(); ++c) {
                    const std::vector<Vec3d> xa = recut->positions(c), xb = kept->positions(c);
                    for (std::size_t i = 0; i < xa.size(); ++i) {
                        gap_after_recut = std::max(gap_after_recut, length(xa[i] - xb[i]));
                        move = std::max(move, length(xb[i] - before[c][i]));
                    }
                }
            }
        }
        for (int s = 0; s < 3; ++s) recuts += recut->step().collision.parts_recut;  // the cooldown holds
        std::vector<cuda::OutputVertex> out(n);
        WEFT_CUDA_CHECK(cudaMemcpy(out.data(), buffer, n * sizeof(cuda::OutputVertex), cudaMemcpyDeviceToHost));
        cuda::as_cuda(recut->backend())->set_output(nullptr, sizeof(cuda::OutputVertex));
        WEFT_CUDA_CHECK(cudaFree(buffer));
        std::printf("[ multi    ] layers on 2 %s: %d re-cut; the step of the re-cut %.3g m from the world without it, "
                    "the step moved %.3g m\n",
                    one_device ? "parts on one GPU" : "GPUs", recuts, gap_after_recut, move);
        ASSERT_EQ(recuts, 1) << "a bar of 1: one re-cut three detections into the contacts, then the cooldown";
        EXPECT_LT(gap_after_recut, kStepTolerance * move) << "the re-cut moved the cloth";
        std::size_t first = 0;
        for (std::size_t c = 0; c < recut->cloth_count(); ++c) {
            const std::vector<Vec3d> x = recut->positions(c);
            for (std::size_t i = 0; i < x.size(); ++i) {
                EXPECT_EQ(out[first + i].position[0], static_cast<float>(x[i].x)) << "cloth " << c << " vertex " << i;
                EXPECT_EQ(out[first + i].position[2], static_cast<float>(x[i].z)) << "cloth " << c << " vertex " << i;
            }
            first += x.size();
        }
    }
    std::vector<std::string> checked = eager;
    checked.push_back("collision.check=true");
    checked.push_back("collision.continuous=true");
    auto world = make("layers", checked, 2, true);
    std::int64_t intersecting = 0;
    int recuts = 0;
    for (int f = 0; f < 45; ++f) {
        const StepStats& s = world->step();
        intersecting += s.collision.remaining_intersections;
        recuts += s.collision.parts_recut;
    }
    EXPECT_GE(recuts, 1);
    EXPECT_EQ(intersecting, 0);
}

// With Coulomb friction and several substeps a step, the step is not a smooth function of the
// state: a contact on the edge of sticking sticks or slips on a rounding, and the substeps after it
// carry the difference on. The scale of that is one GPU against itself from a start one float ulp
// away; the parts' step gap must stay within a few times it (a wrong contact row would show as a gap
// of the order of the move at every step, with or without friction).
TEST(MultiGpuSolver, FrictionalContactStepsStayWithinOneGpusRoundingSensitivity) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> o = with({"collision.continuous=false"});
    auto one = make("layers", o, 1, false);
    auto again = make("layers", o, 1, false);
    const double sensitivity = compare_steps(*one, *again, 40, true).worst;
    const StepGaps g = step_gaps("layers", o, 2, true, 40);
    std::printf("[ multi    ] layers with friction: one GPU against a one-ulp start %.3g of the move, 2 parts %.3g\n",
                sensitivity, g.worst);
    EXPECT_LT(g.worst, std::max(kStepTolerance, 4.0 * sensitivity));
}

// One substep (with friction) of both from the same state with thousands of contacts: each owned
// row's right-hand side b (contacts gathered in) agrees with the one-GPU solver's to float rounding,
// and Δv to the CG tolerance's scale (measured on H100: 4e-8 and 1.5e-4 of the largest entry).
TEST(MultiGpuSolver, ContactSystemRowsMatchOneGpu) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> o = with({"collision.continuous=false", "solver.substeps=1"});
    auto one = make("layers", o, 1, false);
    auto split = make("layers", o, 2, true);
    for (int f = 0; f < 30; ++f) (void)one->step();  // the sheets lie on each other: many contacts
    for (std::size_t c = 0; c < one->cloth_count(); ++c) {
        const auto x = one->positions(c);
        const auto v = one->velocities(c);
        one->set_state(c, x, v);
        split->set_state(c, x, v);
    }
    const StepStats a = one->step();
    const StepStats b = split->step();
    std::printf("[ multi    ] contacts %lld / %lld, CG iterations %d / %d\n", static_cast<long long>(a.collision.contacts),
                static_cast<long long>(b.collision.contacts), a.cg_iterations, b.cg_iterations);
    cuda::DeviceSolver* ds = cuda::device_solver(one->backend());
    cuda::multi::MultiSolver* ms = cuda::multi::multi_solver(split->backend());
    ASSERT_NE(ds, nullptr);
    ASSERT_NE(ms, nullptr);
    const auto read = [](const float* device, std::size_t count) {
        std::vector<float> host(count);
        WEFT_CUDA_CHECK(cudaDeviceSynchronize());
        WEFT_CUDA_CHECK(cudaMemcpy(host.data(), device, count * sizeof(float), cudaMemcpyDeviceToHost));
        return host;
    };
    const std::uint32_t n = ds->view().n;
    const std::vector<float> b1 = read(ds->view().b, 3 * n), dv1 = read(ds->view().dv, 3 * n);
    double b_scale = 0.0, dv_scale = 0.0;
    for (std::size_t k = 0; k < b1.size(); ++k) {
        b_scale = std::max(b_scale, std::abs(double(b1[k])));
        dv_scale = std::max(dv_scale, std::abs(double(dv1[k])));
    }
    double b_gap = 0.0, dv_gap = 0.0;
    std::size_t worst_row = 0;
    for (std::size_t p = 0; p < ms->parts(); ++p) {
        const cuda::DeviceSolver& part = ms->part(p);
        const std::uint32_t local = part.view().n, owned = part.view().rows;
        std::vector<std::uint32_t> global(local);
        WEFT_CUDA_CHECK(cudaMemcpy(global.data(), part.part_global_ids(), local * sizeof(std::uint32_t), cudaMemcpyDeviceToHost));
        const std::vector<float> b2 = read(part.view().b, 3 * local), dv2 = read(part.view().dv, 3 * local);
        for (std::uint32_t i = 0; i < owned; ++i)
            for (std::uint32_t c = 0; c < 3; ++c) {
                const double db = std::abs(double(b2[c * local + i]) - double(b1[c * n + global[i]]));
                if (db > b_gap) {
                    b_gap = db;
                    worst_row = global[i];
                }
                dv_gap = std::max(dv_gap, std::abs(double(dv2[c * local + i]) - double(dv1[c * n + global[i]])));
            }
    }
    std::printf("[ multi    ] b: largest difference %.3g of its largest entry %.3g (vertex %zu); dv: %.3g of %.3g\n", b_gap / b_scale,
                b_scale, worst_row, dv_gap / dv_scale, dv_scale);
    EXPECT_LT(b_gap, 1e-4 * b_scale);
    EXPECT_LT(dv_gap, 1e-2 * dv_scale);
}

// The bending model per triangle across parts (extract_part: each part holds the faces and hinges
// its rows' bending reads, the partition their far corners as ghosts): one step from the same state
// as on one GPU, on the flag (pins, wind, flapping folds) and the drape (a fall onto the ball), and
// the energy audit of the hanging sheet counting every triangle once. (Not the hanging sheet's steps:
// it is at rest within a few frames, where a step moves 1e-9 m and float rounding alone is of that
// size, with either bending model.)
TEST(MultiGpuSolver, ShellBendingAcrossPartsFollowsOneGpu) {
    WEFT_REQUIRE_GPU();
    for (const char* scene : {"flag", "drape"}) {
        for (const int parts : {2, 3}) {
            const double worst = step_gaps(scene, with({"solver.bending=\"shell\""}), parts, true, 30).worst;
            std::printf("[ multi    ] %s with shell bending: %d parts on one GPU, 30 steps: worst step gap %.3g of the step's move\n",
                        scene, parts, worst);
            EXPECT_LT(worst, kStepTolerance) << scene << ", " << parts << " parts";
        }
    }
    auto world = make("hanging", {"solver.bending=\"shell\""}, 3, true);
    for (int f = 0; f < 15; ++f) (void)world->step();
    const auto [device, host, scale] = test::audit_device_and_host(*world);
    std::printf("[ multi    ] hanging with shell bending, audit on 3 parts: U %.9e | host U %.9e\n", device.elastic, host.elastic);
    EXPECT_GT(host.elastic, 0.0);
    EXPECT_NEAR(device.elastic, host.elastic, 1e-5 * scale);
    EXPECT_NEAR(device.external_power, host.external_power, 1e-3 * std::abs(host.external_power) + 1e-6);
}

// The editor's contact marks with several GPUs (World::contact_vertices, collider_contact_vertices):
// each part reports its owned rows in a contact, and together they are one GPU's vertices. Two
// sheets laid 2 mm apart, a large ball just behind the back one's middle, one step from the same
// start on one GPU and on two parts.
TEST(MultiGpuSolver, ReportsTheVerticesInClothContactsLikeOneGpu) {
    WEFT_REQUIRE_GPU();
    const auto contacts = [](int gpus) {
        WorldDesc desc;
        desc.collision.self_collision = true;
        BackendOptions options;
        options.gpus = gpus;
        parts_on_one_device(gpus > 1);
        World world(desc, "cuda", options);
        world.add_cloth({.name = "back", .fabric = Fabric::cook(make_grid(0.4, 0.4, 16, 16))});
        ClothDesc front{.name = "front", .fabric = Fabric::cook(make_grid(0.4, 0.4, 16, 16))};
        front.transform.translation = {0.0, 0.0, 0.002};
        world.add_cloth(front);
        const double thickness = world.model().cloths[0].material.contact_thickness;
        ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
        ball.radius = 1.0;
        ball.motion.origin = world.positions(0)[144] + Vec3d{0.0, 0.0, -1.0 - 0.5 * thickness};  // the middle vertex
        world.add_collider(ball);
        (void)world.step();
        parts_on_one_device(false);
        std::vector<std::vector<std::uint32_t>> out;  // cloth contacts of each sheet, then the back sheet's with the ball
        for (std::size_t c = 0; c < 2; ++c) {
            const std::optional<std::vector<std::uint32_t>> v = world.contact_vertices(c);
            EXPECT_TRUE(v.has_value()) << gpus << " GPUs: the backend does not report its contacts";
            out.push_back(v.value_or(std::vector<std::uint32_t>{}));
        }
        const std::optional<std::vector<std::uint32_t>> on_ball = world.collider_contact_vertices(0);
        EXPECT_TRUE(on_ball.has_value()) << gpus << " GPUs: the backend does not report its collider contacts";
        out.push_back(on_ball.value_or(std::vector<std::uint32_t>{}));
        return out;
    };
    const auto one = contacts(1), split = contacts(2);
    for (std::size_t c = 0; c < 2; ++c) {
        std::vector<std::uint32_t> only;
        std::set_symmetric_difference(split[c].begin(), split[c].end(), one[c].begin(), one[c].end(), std::back_inserter(only));
        std::printf("[ contacts ] cloth %zu: %zu vertices in a contact on two parts, %zu on one GPU, %zu on one only\n", c,
                    split[c].size(), one[c].size(), only.size());
        EXPECT_GT(one[c].size(), 100U) << "most of each sheet touches the other";
        EXPECT_TRUE(std::is_sorted(split[c].begin(), split[c].end()));
        EXPECT_TRUE(std::adjacent_find(split[c].begin(), split[c].end()) == split[c].end()) << "each vertex once";
        for (const std::uint32_t v : split[c]) EXPECT_LT(v, 289U) << "cloth-local ids";
        EXPECT_LE(only.size(), one[c].size() / 20) << "cloth " << c;
    }
    std::vector<std::uint32_t> only;
    std::set_symmetric_difference(split[2].begin(), split[2].end(), one[2].begin(), one[2].end(), std::back_inserter(only));
    std::printf("[ contacts ] with the ball: %zu vertices on two parts, %zu on one GPU, %zu on one only\n", split[2].size(),
                one[2].size(), only.size());
    EXPECT_GT(one[2].size(), 4U) << "the ball touches the back sheet round its middle";
    EXPECT_LT(one[2].size(), 100U) << "not the whole sheet";
    EXPECT_TRUE(std::binary_search(split[2].begin(), split[2].end(), 144U)) << "the middle vertex";
    EXPECT_LE(only.size(), 2U);
}

// The profiling override of the re-cut's contact weight: a number in [0, 100], anything else an
// error naming the value (host code: runs without a GPU).
TEST(MultiGpuSolver, TheContactWeightOverrideTakesANumberAndNamesABadOne) {
    const auto weight_with = [](const char* value) {
        if (value == nullptr)
            unsetenv("WEFT_GPU_CONTACT_WORK");
        else
            setenv("WEFT_GPU_CONTACT_WORK", value, 1);
        return cuda::multi::contact_work_per_vertex();
    };
    EXPECT_EQ(weight_with(nullptr), kContactWorkPerVertex);
    EXPECT_EQ(weight_with("0.75"), 0.75);
    for (const char* bad : {"abc", "0.3x", "-1", "1e9"}) {
        try {
            (void)weight_with(bad);
            ADD_FAILURE() << "WEFT_GPU_CONTACT_WORK=" << bad << " was taken";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
        }
    }
    unsetenv("WEFT_GPU_CONTACT_WORK");
}

TEST(MultiGpuSolver, BadRequestsAreClearErrors) {
    WEFT_REQUIRE_GPU();
    // The mid-edge model is one GPU's so far.
    try {
        auto world = make("cantilever", {"solver.bending=\"midedge\""}, 2, true);
        (void)world->step();
        ADD_FAILURE() << "solver.bending = \"midedge\" ran on two parts";
    } catch (const Error& e) {
        parts_on_one_device(false);  // make() may have thrown before clearing it
        EXPECT_NE(std::string(e.what()).find("\"midedge\""), std::string::npos) << e.what();
    }
    // The parts are cut for the bending model they were built with: switching between the hinge and
    // the per-triangle model without a new world is refused by name.
    for (const auto& [from, to] : {std::pair{BendingModel::Hinge, BendingModel::Shell}, std::pair{BendingModel::Shell, BendingModel::Hinge}}) {
        auto world = make("hanging", {from == BendingModel::Shell ? "solver.bending=\"shell\"" : "solver.bending=\"hinge\""}, 2, true);
        EXPECT_TRUE(world->step().ok());
        world->settings().solver.bending = to;
        try {
            (void)world->step();
            ADD_FAILURE() << "solver.bending switched on two parts without a new world";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("solver.bending"), std::string::npos) << e.what();
        }
    }
    BackendOptions options;
    options.gpus = static_cast<int>(cuda::devices().size()) + 1;
    try {
        (void)build_world(load_scene(test::scene_file("flag")), "cuda", options);
        ADD_FAILURE() << "more GPUs than the host has were accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("this host has"), std::string::npos) << e.what();
    }
}

// The runaway guard across parts (weft/backend/runaway.h): a small sheet thrown down at 9,990 m/s
// beside a large one at rest, under 1000 m/s² for one 0.1 s step. The thrown sheet passes
// kRunawaySpeed within the substep, so the solve is dropped: every free vertex moves on at its
// start velocity (the thrown sheet 999 m down, the resting one not at all), as on one GPU. The
// sheets share no element and the small one's nine vertices lie in one part's run of the order, so
// the other part holds resting cloth only; if it kept its solve, its vertices would fall 10 m.
TEST(MultiGpuSolver, ARunawayOnOnePartDropsEveryPartsSolve) {
    WEFT_REQUIRE_GPU();
    constexpr double kThrown = 9'990.0, kDt = 0.1;  // m/s, s
    for (const bool one_device : {true, false}) {
        if (!one_device && cuda::devices().size() < 2) continue;
        SCOPED_TRACE(one_device ? "two parts on one GPU" : "two GPUs");
        WorldDesc desc;
        desc.solver.dt = kDt;
        desc.gravity = {0.0, -1000.0, 0.0};
        BackendOptions options;
        options.gpus = 2;
        parts_on_one_device(one_device);
        World world(desc, "cuda", options);
        ClothDesc thrown{.name = "thrown", .fabric = Fabric::cook(make_grid(0.2, 0.2, 2, 2))};
        thrown.initial_velocity = {0.0, -kThrown, 0.0};
        world.add_cloth(thrown);
        ClothDesc resting{.name = "resting", .fabric = Fabric::cook(make_grid(1.0, 1.0, 16, 16))};
        resting.transform.translation = {2.0, 0.0, 0.0};
        world.add_cloth(resting);
        const std::vector<Vec3d> thrown_before = world.positions(0), resting_before = world.positions(1);
        const StepStats stats = world.step();
        parts_on_one_device(false);
        EXPECT_GT(stats.runaway_solves, 0);
        EXPECT_FALSE(stats.non_finite);
        const std::vector<Vec3d> thrown_after = world.positions(0), resting_after = world.positions(1);
        for (std::size_t i = 0; i < thrown_after.size(); ++i)
            EXPECT_NEAR(thrown_after[i].y, thrown_before[i].y - kThrown * kDt, 1e-5 * kThrown) << "thrown vertex " << i;
        double fell = 0.0;
        for (std::size_t i = 0; i < resting_after.size(); ++i)
            fell = std::max(fell, std::abs(resting_after[i].y - resting_before[i].y));
        EXPECT_LT(fell, 1e-6) << "the resting sheet moved " << fell << " m: a part kept its solve";
    }
}

// Offset contact across parts (docs/multi-gpu.md, "Collisions"): every GPU measures its share of the
// bound pairs and the truncation's pair limits; the per-vertex minimum over the shares is the one-GPU
// array, so from the same state the parts find the same contacts and the same bounds, and one step
// lands where one GPU's does (friction off, one substep: a smooth step, as ContactStepsFollowOneGpu).
// Stepped freely with the exact check after every step, the offset scenes stay intersection-free on
// 2 and 3 parts, and two GPUs give the bits of two parts on one.
TEST(MultiGpuSolver, OffsetContactAcrossPartsFollowsOneGpuAndStaysIntersectionFree) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> smooth = with({"collision.mode=\"offset\"", "solver.substeps=1",
                                                  "cloth.sheets.material.friction=0", "collider.ball.friction=0"});
    for (const int parts : {2, 3}) {
        const StepGaps g = step_gaps("layers", smooth, parts, true, 40);
        std::printf("[ multi    ] offset layers, %d parts on one GPU, 40 steps: worst step gap %.3g of the move\n", parts, g.worst);
        EXPECT_LT(g.worst, kStepTolerance) << parts << " parts";
    }
    struct Case {
        const char* scene;
        std::vector<std::string> overrides;
        int frames;
    };
    const Case cases[] = {
        {"twist", {"cloth.sheet.mesh.grid.cells=[24,24]", "cloth.sheet.mesh.grid.width=0.24", "cloth.sheet.mesh.grid.height=0.24"}, 600},
        {"layers", {}, 45},
        {"falling", {}, 45},
    };
    for (const Case& c : cases) {
        for (const int parts : {2, 3}) {
            std::vector<std::string> o = c.overrides;
            o.push_back("collision.mode=\"offset\"");
            o.push_back("collision.check=true");
            auto world = make(c.scene, o, parts, true);
            std::int64_t intersecting = 0, truncated = 0;
            long long contacts = 0;
            int redetections = 0;
            bool non_finite = false;
            for (int f = 0; f < c.frames; ++f) {
                const StepStats& s = world->step();
                intersecting += s.collision.remaining_intersections;
                contacts += s.collision.contacts;
                truncated += s.collision.truncated_vertices;
                redetections += s.collision.redetections;
                non_finite = non_finite || s.non_finite;
            }
            std::printf("[ multi    ] offset %s on %d parts, %d frames: %lld contacts, %lld truncated moves, %d reruns, %lld "
                        "intersecting pairs left\n",
                        c.scene, parts, c.frames, contacts, static_cast<long long>(truncated), redetections,
                        static_cast<long long>(intersecting));
            EXPECT_EQ(intersecting, 0) << c.scene << " on " << parts << " parts";
            EXPECT_FALSE(non_finite) << c.scene;
            EXPECT_GT(contacts, 0) << c.scene << ": the scene never touched (the test would prove nothing)";
        }
    }
    // The energy audit counts every offset contact once across the parts (on the owner of its first
    // cloth corner, from the whole positions): after one step from the same state, with both worlds
    // then set to one state, the parts' offset contact energy is one GPU's (a contact counted twice
    // or lost would be off by its share). No reruns, so both lists are the one detection's.
    {
        std::vector<std::string> o = smooth;
        o.push_back("collision.max_redetections=0");
        auto one = make("layers", o, 1, false);
        auto split = make("layers", o, 2, true);
        for (int f = 0; f < 30; ++f) (void)one->step();
        for (std::size_t c = 0; c < one->cloth_count(); ++c) split->set_state(c, one->positions(c), one->velocities(c));
        (void)one->step();
        (void)split->step();
        for (std::size_t c = 0; c < one->cloth_count(); ++c) split->set_state(c, one->positions(c), one->velocities(c));
        const Model& model = one->model();
        const double t = one->time(), h = model.settings.solver.dt / model.settings.solver.substeps;
        const auto offset_energy = [&](World& w) {
            Backend& b = w.backend();
            return b.energy_audit(model, t, h, false).contact - b.Backend::energy_audit(model, t, h, false).contact;
        };
        const double e_one = offset_energy(*one), e_split = offset_energy(*split);
        std::printf("[ multi    ] offset contact energy in the audit: one GPU %.6e J, 2 parts %.6e J\n", e_one, e_split);
        EXPECT_GT(e_one, 0.0) << "no offset contact energy: the test would prove nothing";
        EXPECT_NEAR(e_split, e_one, 1e-2 * e_one);
    }
    const std::vector<std::string> layers{"collision.mode=\"offset\""};
    EXPECT_TRUE(same_bits(run("layers", layers, 2, 20, true), run("layers", layers, 2, 20, true))) << "offset layers, 2 parts, twice";
    if (cuda::devices().size() >= 2) {
        EXPECT_TRUE(same_bits(run("layers", layers, 2, 20, true), run("layers", layers, 2, 20, false))) << "offset layers on two GPUs";
    }
}

}  // namespace
}  // namespace weft


