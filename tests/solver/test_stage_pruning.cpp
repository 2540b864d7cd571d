// A scene pays only for what it models, on the CPU backend: `hanging` (no self-contact, no collider,
// no wind) runs none of the collision stages and holds no collision memory; the same sheet with
// self-collision on runs them and holds it (the assertions can fail). The CUDA backend's proof counts
// kernel launches (tests/gpu/test_cuda_stage_pruning.cpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "weft/backend/backend.h"
#include "weft/scene.h"
#include "weft/world.h"

namespace weft {
namespace {

std::unique_ptr<World> hanging(const std::vector<std::string>& overrides) {
    const auto file = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / "hanging.toml";
    return build_world(load_scene(file, overrides), "cpu");
}

constexpr Stage kCollisionStages[] = {Stage::BroadPhase, Stage::Culling, Stage::NarrowPhase, Stage::Ccd, Stage::ImpactZones};

std::size_t collision_bytes(const World& world) {
    std::size_t bytes = 0;
    for (const auto& [what, b] : world.backend().memory_breakdown())
        if (what.find("collision") != std::string::npos) bytes += b;
    return bytes;
}

TEST(StagePruning, HangingRunsNoCollisionStageOnTheCpu) {
    auto plain = hanging({"cloth.sheet.mesh.grid.cells=[12,12]"});
    for (int k = 0; k < 3; ++k) {
        const StepStats& s = plain->step();
        for (const Stage stage : kCollisionStages)
            EXPECT_EQ(s.ms(stage), 0.0) << kStageNames[static_cast<int>(stage)] << " ran in step " << k;
        EXPECT_EQ(s.collision.candidate_pairs, 0);
        EXPECT_EQ(s.collision.contacts, 0);
    }
    EXPECT_EQ(collision_bytes(*plain), 0U);

    auto colliding = hanging({"cloth.sheet.mesh.grid.cells=[12,12]", "collision.self=true"});
    double detection = 0.0;
    for (int k = 0; k < 3; ++k) detection += colliding->step().ms(Stage::BroadPhase);
    EXPECT_GT(detection, 0.0) << "self-collision runs the broad phase";
    EXPECT_GT(collision_bytes(*colliding), 0U);
}

}  // namespace
}  // namespace weft
