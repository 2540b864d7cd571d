// A scene pays only for what it models: the CUDA backend builds and launches the collision stages
// only for a scene with cloth collisions or colliders. The launch record (cuda_check.h) counts every
// checked kernel launch by file and name; with graphs off every launch goes through it.
// - `hanging` (no self-contact, no collider, no wind) launches no kernel of the collision stages,
//   the contact solve or the collider sweep, and allocates no collision buffers;
// - the same sheet with self-collision switched on launches them (the record sees them: the first
//   assertion can fail).
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "cuda_check.h"
#include "gpu_test_util.h"

namespace weft {
namespace {

/// Launches by file and name over `steps` steps of `world` (built and stepped once before), graphs off.
std::map<std::string, long long> launches(World& world, int steps) {
    cuda::CudaBackendApi* api = cuda::as_cuda(world.backend());
    EXPECT_NE(api, nullptr);
    if (api != nullptr) api->set_use_graph(false);
    (void)world.step();
    cuda::start_launch_record();
    for (int k = 0; k < steps; ++k) (void)world.step();
    return cuda::stop_launch_record();
}

/// Whether a launch belongs to the contact or collision stages (their files) or the collider sweep.
bool collision_stage(const std::string& key) {
    return key.starts_with("collision/") || key.starts_with("contact_kernels.cu") ||
           key.starts_with("collision_state_kernels.cu") || key.find("sweep_colliders") != std::string::npos ||
           key.find("contact") != std::string::npos;
}

long long count_collision_launches(const std::map<std::string, long long>& counts, bool print) {
    long long n = 0;
    for (const auto& [key, count] : counts) {
        if (print) std::printf("[ launches ] %6lld  %s\n", count, key.c_str());
        if (collision_stage(key)) n += count;
    }
    return n;
}

TEST(CudaStagePruning, HangingLaunchesNoCollisionOrContactKernel) {
    WEFT_REQUIRE_GPU();
    auto plain = test::make_world("hanging", "cuda");
    const auto counts = launches(*plain, 3);
    ASSERT_FALSE(counts.empty()) << "the record saw no launch at all";
    long long total = 0;
    for (const auto& [key, count] : counts) total += count;
    std::printf("[ launches ] hanging: %lld kernel launches in 3 steps (%zu kernels)\n", total, counts.size());
    EXPECT_EQ(count_collision_launches(counts, true), 0);
    for (const auto& [what, bytes] : plain->backend().memory_breakdown())
        EXPECT_EQ(what.find("collision"), std::string::npos) << what << ": " << bytes << " bytes";

    auto colliding = test::make_world("hanging", "cuda", {"collision.self=true"});
    const auto with_contact = launches(*colliding, 3);
    const long long n = count_collision_launches(with_contact, false);
    std::printf("[ launches ] hanging with self-collision: %lld launches of the collision stages in 3 steps\n", n);
    EXPECT_GT(n, 0) << "the record must see the collision stages where the scene has them";
}

/// StepStats::kernels_launched over `steps` steps after one warm-up step (graphs as `graphs`).
std::vector<long long> kernels_per_step(World& world, int steps, bool graphs) {
    cuda::CudaBackendApi* api = cuda::as_cuda(world.backend());
    EXPECT_NE(api, nullptr);
    if (api != nullptr) api->set_use_graph(graphs);
    (void)world.step();
    std::vector<long long> out;
    for (int k = 0; k < steps; ++k) out.push_back(world.step().kernels_launched);
    return out;
}

// The stats' kernels per step: with graphs off, the launch record's count exactly; with the graph
// (hanging's CG is the one-launch kernel, so the graph holds every kernel of the substep once), the
// same count from the graph's nodes, the capture not counted as launches; and more with the
// collision stages switched on.
TEST(CudaStagePruning, TheStatsCountTheKernelsOfEachStep) {
    WEFT_REQUIRE_GPU();
    auto direct = test::make_world("hanging", "cuda");
    cuda::CudaBackendApi* api = cuda::as_cuda(direct->backend());
    ASSERT_NE(api, nullptr);
    api->set_use_graph(false);
    (void)direct->step();
    cuda::start_launch_record();
    const long long counted = direct->step().kernels_launched;
    long long recorded = 0;
    for (const auto& [key, count] : cuda::stop_launch_record()) recorded += count;
    std::printf("[ kernels  ] hanging, graphs off: %lld kernels in the step's stats, %lld in the launch record\n", counted,
                recorded);
    EXPECT_GT(counted, 0);
    EXPECT_EQ(counted, recorded);

    auto graphed = test::make_world("hanging", "cuda");
    const std::vector<long long> with_graph = kernels_per_step(*graphed, 4, true);
    const std::vector<long long> without = kernels_per_step(*direct, 4, false);
    ASSERT_TRUE(cuda::as_cuda(graphed->backend())->graph_active()) << "the graph did not run: the test compares nothing";
    for (std::size_t k = 0; k < with_graph.size(); ++k) {
        std::printf("[ kernels  ] hanging step %zu: %lld with the graph, %lld without\n", k, with_graph[k], without[k]);
        EXPECT_EQ(with_graph[k], without[k]) << "step " << k;
    }

    auto colliding = test::make_world("hanging", "cuda", {"collision.self=true"});
    const std::vector<long long> with_contact = kernels_per_step(*colliding, 2, false);
    std::printf("[ kernels  ] hanging with self-collision: %lld kernels a step\n", with_contact.back());
    EXPECT_GT(with_contact.back(), without.back());
}

}  // namespace
}  // namespace weft
