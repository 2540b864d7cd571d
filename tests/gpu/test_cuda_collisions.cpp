// Cloth collisions on the cuda backend (cuda/src/device_collisions.h): every shipped collision scene,
// at the CI sizes of tests/cli/CMakeLists.txt, ends every frame with zero intersections (the exact
// check) and no unresolved substep; and the GPU's proximity contacts for one state match the CPU's.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/scene.h"
#include "weft/world.h"

#include "gpu_test_util.h"
#include "rest_exclusion_scene.h"

namespace weft {
namespace {

using test::make_world;

struct SceneCase {
    const char* scene;
    std::vector<std::string> overrides;
    int frames;
};

// The CLI collision tests' sizes; the twist runs 1 s (600 frames) of the CLI's 2 s to keep the test
// short, past the first folds.
const SceneCase kScenes[] = {
    {"twist", {"cloth.sheet.mesh.grid.cells=[24,24]", "cloth.sheet.mesh.grid.width=0.24", "cloth.sheet.mesh.grid.height=0.24"}, 600},
    {"falling", {}, 45},
    {"projectile", {}, 45},
    {"layers", {}, 45},
    {"garment", {}, 45},
    {"sphere", {}, 45},
};

// The projectile at one substep per frame (its 50 m/s ball then moves 8 cm a substep, most of its
// 10 cm width) needs the swept collider test, which the exact check cannot judge (it looks at
// triangles, not at analytic colliders): test_cuda_fast_colliders.cpp runs it against the CPU.

// Both contact modes: CCD with impact zones, and offset contact (truncation to the displacement
// bounds, the impact zones only as the fallback).
class CudaCollisionModes : public ::testing::TestWithParam<const char*> {};

TEST_P(CudaCollisionModes, EveryCollisionSceneEndsEveryFrameWithoutIntersections) {
    WEFT_REQUIRE_GPU();
    for (const SceneCase& c : kScenes) {
        SCOPED_TRACE(c.scene);
        std::vector<std::string> overrides = c.overrides;
        overrides.emplace_back("collision.check=true");
        overrides.emplace_back(std::string("collision.mode=") + GetParam());
        std::unique_ptr<World> world;
        try {
            world = make_world(c.scene, "cuda", overrides);
        } catch (const Error& e) {
            // The garment's skirt and mannequin are OBJ files: without mesh import (WEFT_ASSETS off)
            // the scene cannot load in this build; the `weft` CLI runs it where it can.
            if (std::string(e.what()).find("mesh import not built") == std::string::npos) throw;
            std::printf("[ collide  ] %-10s skipped: %s\n", c.scene, e.what());
            continue;
        }
        int intersecting = 0, unresolved = 0, non_finite = 0, zones = 0, contacts_max = 0, redetections = 0, fallbacks = 0;
        std::int64_t ccd_hits = 0, truncated = 0;
        const auto start = std::chrono::steady_clock::now();
        for (int f = 0; f < c.frames; ++f) {
            const StepStats& s = world->step();
            if (s.collision.remaining_intersections != 0) ++intersecting;
            unresolved += s.collision.unresolved_substeps;
            non_finite += s.non_finite ? 1 : 0;
            zones += s.collision.impact_zones;
            ccd_hits += s.collision.ccd_hits;
            contacts_max = std::max(contacts_max, s.collision.contacts);
            truncated += s.collision.truncated_vertices;
            redetections += s.collision.redetections;
            fallbacks += s.collision.bound_fallbacks;
        }
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        std::printf("[ collide  ] %-9s %-10s %4d frames: %d intersecting, %d unresolved substeps, %d impact zones, "
                    "%lld CCD hits, up to %d contacts, %lld truncated, %d reruns, %d fallbacks, %.2f ms/frame (check "
                    "included)\n",
                    GetParam(), c.scene, c.frames, intersecting, unresolved, zones, static_cast<long long>(ccd_hits),
                    contacts_max, static_cast<long long>(truncated), redetections, fallbacks, ms / c.frames);
        EXPECT_EQ(intersecting, 0);
        EXPECT_EQ(unresolved, 0);
        EXPECT_EQ(non_finite, 0);
    }
}

INSTANTIATE_TEST_SUITE_P(BothModes, CudaCollisionModes, ::testing::Values("ccd_zones", "offset"),
                         [](const auto& mode) { return std::string(mode.param); });

TEST(CudaCollisions, ContactCountOfOneStateMatchesTheCpu) {
    WEFT_REQUIRE_GPU();
    // The layers at frame 30 (the sheets have landed on the ball and on each other: thousands of
    // cloth-cloth contacts; at frame 5 there are none yet). Both backends are given the CPU's state,
    // then take one step of one substep, whose contacts both find from that state (the GPU from its
    // float rounding). The GPU broad phase's boxes contain the CPU's (broad_phase_gpu.h), and the
    // proximity decision in float differs from the double one only for pairs within float rounding of
    // the thickness: 1 % is a wide margin for that.
    const auto cpu = make_world("layers", "cpu");
    const auto gpu = make_world("layers", "cuda");
    for (int f = 0; f < 30; ++f) {
        (void)cpu->step();
        (void)gpu->step();
    }
    for (std::size_t c = 0; c < cpu->model().cloths.size(); ++c) {
        const auto x = cpu->positions(c), v = cpu->velocities(c);
        gpu->set_state(c, x, v);
    }
    cpu->settings().solver.substeps = 1;
    gpu->settings().solver.substeps = 1;
    const int cpu_contacts = cpu->step().collision.contacts;
    const int gpu_contacts = gpu->step().collision.contacts;
    std::printf("[ contacts ] layers, one state: CPU %d, GPU %d\n", cpu_contacts, gpu_contacts);
    EXPECT_GT(cpu_contacts, 0);
    EXPECT_LE(std::abs(gpu_contacts - cpu_contacts), std::max(2, cpu_contacts / 100));
}

// The CPU test's promise (test_cloth_collisions.cpp) on the GPU narrow phase, and the same counts.
TEST(CudaCollisions, RestNeighboursGetNoSpringsButOtherClothsDo) {
    WEFT_REQUIRE_GPU();
    const int excluded = test::rest_exclusion_contacts("cuda", 1.0, false);
    const int kept = test::rest_exclusion_contacts("cuda", 0.0, false);
    const int two_sheets = test::rest_exclusion_contacts("cuda", 1.0, true);
    std::printf("[ contacts ] rest exclusion on the GPU: %d excluded, %d kept, %d with two sheets\n", excluded, kept,
                two_sheets);
    EXPECT_EQ(excluded, 0);
    // As in ContactCountOfOneStateMatchesTheCpu: float and double differ only on pairs within
    // rounding of the thickness.
    const int cpu_kept = test::rest_exclusion_contacts("cpu", 0.0, false);
    const int cpu_two_sheets = test::rest_exclusion_contacts("cpu", 1.0, true);
    EXPECT_LE(std::abs(kept - cpu_kept), std::max(2, cpu_kept / 100));
    EXPECT_LE(std::abs(two_sheets - cpu_two_sheets), std::max(2, cpu_two_sheets / 100));
}

// collision.ccd_time_tolerance reaches the GPU's impact zones (their float CCD): the stacked layers
// stay intersection-free with a coarse tolerance, and the run differs from the default's.
TEST(CudaCollisions, ACoarseCcdTimeToleranceStaysIntersectionFree) {
    WEFT_REQUIRE_GPU();
    const auto run = [](const char* tolerance) {
        const auto world = make_world("layers", "cuda",
                                      {"collision.check=true", "collision.mode=\"ccd_zones\"",
                                       std::string("collision.ccd_time_tolerance=") + tolerance});
        std::int64_t hits = 0;
        for (int frame = 0; frame < 45; ++frame) {
            const StepStats& s = world->step();
            EXPECT_FALSE(s.non_finite) << "frame " << frame;
            EXPECT_EQ(s.collision.remaining_intersections, 0) << "tolerance " << tolerance << ", frame " << frame;
            EXPECT_EQ(s.collision.unresolved_substeps, 0) << "tolerance " << tolerance << ", frame " << frame;
            hits += s.collision.ccd_hits;
        }
        return std::make_pair(hits, world->positions(0));
    };
    const auto [default_hits, default_x] = run("0");
    const auto [coarse_hits, coarse_x] = run("1e-2");
    std::printf("[ ccd      ] layers, 45 frames: %lld CCD hits at the default time tolerance, %lld at 1e-2\n",
                static_cast<long long>(default_hits), static_cast<long long>(coarse_hits));
    EXPECT_GT(default_hits, 0) << "no CCD hit: the scene does not test the tolerance";
    EXPECT_NE(coarse_x, default_x) << "the tolerance did not reach the GPU's CCD";
}

// The vertices in a cloth contact (World::contact_vertices, the editor's magenta marks) on the
// device: two sheets 2 mm apart, inside their contact thickness, give the CPU's vertices after one
// step from the same state (a borderline pair or two may differ in float).
TEST(CudaCollisions, ReportsTheVerticesInClothContactsLikeTheCpu) {
    WEFT_REQUIRE_GPU();
    const auto contacts = [](const char* backend) {
        WorldDesc desc;
        desc.collision.self_collision = true;
        World world(desc, backend);
        world.add_cloth({.name = "back", .fabric = Fabric::cook(make_grid(0.4, 0.4, 4, 4))});
        ClothDesc front{.name = "front", .fabric = Fabric::cook(make_grid(0.4, 0.4, 4, 4))};
        front.transform.translation = {0.0, 0.0, 0.002};
        world.add_cloth(front);
        (void)world.step();
        std::vector<std::vector<std::uint32_t>> out;
        for (std::size_t c = 0; c < 2; ++c) {
            const std::optional<std::vector<std::uint32_t>> v = world.contact_vertices(c);
            EXPECT_TRUE(v.has_value()) << backend << " does not report its contacts";
            out.push_back(v.value_or(std::vector<std::uint32_t>{}));
        }
        return out;
    };
    const auto gpu = contacts("cuda"), cpu = contacts("cpu");
    for (std::size_t c = 0; c < 2; ++c) {
        std::vector<std::uint32_t> only;
        std::set_symmetric_difference(gpu[c].begin(), gpu[c].end(), cpu[c].begin(), cpu[c].end(), std::back_inserter(only));
        std::printf("[ contacts ] cloth %zu: %zu vertices in a contact on the GPU, %zu on the CPU, %zu on one only\n", c,
                    gpu[c].size(), cpu[c].size(), only.size());
        EXPECT_GT(gpu[c].size(), 10U) << "most of each sheet touches the other";
        EXPECT_TRUE(std::is_sorted(gpu[c].begin(), gpu[c].end()));
        EXPECT_TRUE(std::adjacent_find(gpu[c].begin(), gpu[c].end()) == gpu[c].end()) << "each vertex once";
        for (const std::uint32_t v : gpu[c]) EXPECT_LT(v, 25U) << "cloth-local ids";
        EXPECT_LE(only.size(), cpu[c].size() / 10) << "cloth " << c;
    }
}

}  // namespace
}  // namespace weft
