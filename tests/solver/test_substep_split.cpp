// Splitting the substeps that tear the cloth (SolverSettings::split_stretch; docs/methods.md §1c): a
// body running through a banner at one step a frame tears it open unless the substeps in which it
// drags the banner are redone as halves; a scene that never overstretches steps to the same bits
// with the splitting on as off; and a world resumed from a checkpoint taken while the substeps run
// split steps on to the same bits.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "banner_runner.h"
#include "weft/backend/backend.h"
#include "weft/backend/energy_audit.h"
#include "weft/backend/model.h"
#include "weft/mesh.h"
#include "weft/scene.h"
#include "weft/world.h"
#include "world_snapshot.h"

namespace weft {
namespace {

using test::BannerRun;
using test::kBannerFrames;
using test::run_frames;

// A backend whose only physics is the stretch a substep leaves, scripted by its length: in the
// first frame (of length kFrame) a whole substep stretches to 3, a half to 4 and a quarter to 3.5;
// later substeps to 1. So a split into halves is kept by neither rule at once: each half's own split
// into quarters helps it (3.5 < 4), but the halves end worse than the whole (3.5 > 3), and the whole
// is kept. The stretch is state (the first position's x), so that World's saved states restore it.
constexpr double kFrame = 0.01;
class ScriptedStretch final : public Backend {
public:
    std::string_view name() const override { return "scripted_stretch"; }
    std::string device_description() const override { return "a script"; }
    void build(const Model& model) override {
        x_.assign(model.cloths.at(0).fabric->vertex_count(), Vec3d{1.0, 0.0, 0.0});
        v_.assign(x_.size(), Vec3d{});
    }
    void substep(const Model&, double t, double h, StepStats&) override {
        const auto near = [](double a, double b) { return std::abs(a - b) < 1e-9; };
        double stretch = 1.0;
        if (t < kFrame - 1e-12) stretch = near(h, kFrame) ? 3.0 : near(h, 0.5 * kFrame) ? 4.0 : 3.5;
        x_[0].x = stretch;
    }
    void read_state(std::size_t, std::span<Vec3d> x, std::span<Vec3d> v) const override {
        std::copy(x_.begin(), x_.end(), x.begin());
        std::copy(v_.begin(), v_.end(), v.begin());
    }
    void write_state(std::size_t, std::span<const Vec3d> x, std::span<const Vec3d> v) override {
        x_.assign(x.begin(), x.end());
        v_.assign(v.begin(), v.end());
    }
    EnergyAudit energy_audit(const Model&, double, double, bool) const override {
        EnergyAudit a;
        a.max_stretch = x_.empty() ? 1.0 : x_[0].x;
        return a;
    }
    std::size_t memory_bytes() const override { return 0; }

private:
    std::vector<Vec3d> x_, v_;
};

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

// A split whose halves end worse than the whole is undone with everything in it: the halves' own
// splits, which helped the halves, must not set the level later substeps start at (they did: the
// next frame then ran in quarters for nothing).
TEST(SubstepSplit, ASplitThatIsUndoneSetsNoLevelForLaterSubsteps) {
    register_backend("scripted_stretch", "tests: a stretch scripted by the substep's length",
                     [](const BackendOptions&) { return std::make_unique<ScriptedStretch>(); });
    WorldDesc desc;
    desc.solver.dt = kFrame;
    desc.solver.substeps = 1;
    desc.solver.split_stretch = 2.0;
    desc.solver.max_substep_splits = 2;
    desc.solver.energy_guard = EnergyGuard::Off;
    World world(desc, "scripted_stretch");
    world.add_cloth({.name = "patch", .fabric = Fabric::cook(make_grid(0.1, 0.1, 1, 1))});
    const StepStats first = world.step();
    EXPECT_EQ(first.substeps, 1) << "the whole substep is kept";
    EXPECT_EQ(first.split_substeps, 3) << "the whole, and each half, were split";
    EXPECT_DOUBLE_EQ(first.max_stretch, 3.0);
    const StepStats second = world.step();
    EXPECT_EQ(second.substeps, 1) << "the next frame starts unsplit: nothing that was kept split";
    EXPECT_EQ(second.split_substeps, 0);
}

}  // namespace
}  // namespace weft
