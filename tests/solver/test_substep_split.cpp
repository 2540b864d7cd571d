// Splitting the substeps that tear the cloth (SolverSettings::split_stretch; docs/methods.md §1c): a
// body running through a banner at one step a frame tears it open unless the substeps in which it
// drags the banner are redone as halves; a scene that never overstretches steps to the same bits
// with the splitting on as off; and a world resumed from a checkpoint taken while the substeps run
// split steps on to the same bits.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "banner_runner.h"
#include "weft/scene.h"
#include "world_snapshot.h"

namespace weft {
namespace {

using test::BannerRun;
using test::kBannerFrames;
using test::run_frames;

TEST(SubstepSplit, ABodyRunningThroughABannerTearsItUnlessTheDraggingSubstepsSplit) {
    auto whole = test::banner_runner(0.0);
    const BannerRun torn = run_frames(*whole, kBannerFrames);
    auto split = test::banner_runner(2.0);
    const BannerRun kept = run_frames(*split, kBannerFrames);
    std::printf("[   info   ] one step a frame: stretch up to %.2fx; split at 2x: %.2fx, %d substeps redone, %d taken in %d frames\n",
                torn.max_stretch, kept.max_stretch, kept.split_substeps, kept.substeps, kBannerFrames);
    // The control: without splitting the head drags the banner open.
    EXPECT_GE(torn.max_stretch, kOverstretch);
    EXPECT_EQ(torn.split_substeps, 0);
    EXPECT_EQ(torn.substeps, kBannerFrames);
    // Split, it slides over the head: nothing past the overstretch mark, and it cost some substeps.
    EXPECT_LT(kept.max_stretch, kOverstretch);
    EXPECT_GT(kept.split_substeps, 0);
    EXPECT_GT(kept.substeps, kBannerFrames);
    // Both runs collision-free and sound.
    EXPECT_EQ(torn.intersecting_frames, 0);
    EXPECT_EQ(kept.intersecting_frames, 0);
    EXPECT_EQ(torn.failed, 0);
    EXPECT_EQ(kept.failed, 0);
}

TEST(SubstepSplit, AWorldThatNeverOverstretchesStepsToTheSameBitsWithTheSplittingOn) {
    const std::filesystem::path scene = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / "flag.toml";
    const std::vector<std::string> plain = {"cloth.flag.mesh.grid.cells=[24,14]"};
    const std::vector<std::string> splitting = {"cloth.flag.mesh.grid.cells=[24,14]", "solver.split_stretch=2"};
    auto off = build_world(load_scene(scene, plain), "cpu");
    auto on = build_world(load_scene(scene, splitting), "cpu");
    const BannerRun a = run_frames(*off, 30), b = run_frames(*on, 30);
    EXPECT_EQ(b.split_substeps, 0) << "the flag stretched to " << b.max_stretch;
    EXPECT_EQ(b.substeps, a.substeps);
    EXPECT_TRUE(test::snapshot(*on) == test::snapshot(*off)) << "splitting that never split changed the result";
}

TEST(SubstepSplit, AWorldResumedWhileItsSubstepsRunSplitStepsOnToTheSameBits) {
    const std::filesystem::path file = test::test_state_file("weft_test_substep_split_");
    auto saved = test::banner_runner(2.0);
    // Into the pass through the banner, until the substeps start split.
    int frame = 0, taken = 0;
    while (frame < kBannerFrames && taken <= 1) {
        taken = saved->step().substeps;
        ++frame;
    }
    ASSERT_GT(taken, 1) << "no substep split in " << kBannerFrames << " frames";
    saved->save_state(file);
    const BannerRun after_save = run_frames(*saved, 10);

    auto resumed = test::banner_runner(2.0);
    resumed->load_state(file);
    const BannerRun after_load = run_frames(*resumed, 10);
    EXPECT_EQ(after_load.substeps, after_save.substeps);
    EXPECT_TRUE(test::snapshot(*resumed) == test::snapshot(*saved)) << "the continuation differs";
    std::filesystem::remove(file);
}

}  // namespace
}  // namespace weft
