// The frame loop: a fixed simulation rate under any display rate, the cap on steps per frame,
// pause, single step and time scale, the stats of every step of a frame.
#include <gtest/gtest.h>

#include <limits>
#include <memory>

#include "weft/error.h"
#include "weft/frame_loop.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

std::unique_ptr<World> small_world(double dt) {
    WorldDesc desc;
    desc.solver.dt = dt;
    auto world = std::make_unique<World>(desc);
    world->add_cloth(ClothDesc{.name = "sheet", .fabric = Fabric::cook(make_grid(0.2, 0.2, 2, 2), {})});
    return world;
}

TEST(FrameLoop, SimulatesRealTimeWhateverTheDisplayRate) {
    for (const double display_hz : {30.0, 60.0, 75.0, 144.0}) {
        auto world = small_world(1.0 / 60.0);
        FrameLoop loop(*world);
        const int frames = static_cast<int>(display_hz * 2.0);  // two seconds
        for (int f = 0; f < frames; ++f) (void)loop.advance(1.0 / display_hz);
        EXPECT_EQ(loop.steps(), 120) << display_hz << " Hz";
        EXPECT_NEAR(world->time(), 2.0, 1e-9) << display_hz << " Hz";
        EXPECT_EQ(loop.dropped_steps(), 0);
    }
}

TEST(FrameLoop, CarriesTheRemainderAndReportsIt) {
    auto world = small_world(0.01);
    FrameLoop loop(*world);
    EXPECT_EQ(loop.advance(0.025), 2);
    EXPECT_NEAR(loop.alpha(), 0.5, 1e-9);
    EXPECT_EQ(loop.advance(0.005), 1);  // 0.005 + 0.005 owed
    EXPECT_NEAR(loop.alpha(), 0.0, 1e-9);
    EXPECT_EQ(loop.advance(0.0), 0);
}

TEST(FrameLoop, SlowFramesDropStepsInsteadOfSpiralling) {
    auto world = small_world(0.01);
    FrameLoop loop(*world, {.time_scale = 1.0, .max_steps_per_frame = 3});
    EXPECT_EQ(loop.advance(0.1), 3);  // 10 due
    EXPECT_EQ(loop.dropped_steps(), 7);
    EXPECT_LT(loop.alpha(), 1.0);
    EXPECT_EQ(loop.advance(0.01), 1) << "no backlog carried over";
}

TEST(FrameLoop, PauseSingleStepAndTimeScale) {
    auto world = small_world(0.01);
    FrameLoop loop(*world);
    loop.set_paused(true);
    EXPECT_EQ(loop.advance(1.0), 0);
    loop.request_single_step();
    EXPECT_EQ(loop.advance(1.0), 1);
    EXPECT_EQ(loop.advance(1.0), 0) << "one step per request";
    EXPECT_TRUE(loop.paused());
    loop.set_paused(false);
    loop.set_time_scale(0.5);
    EXPECT_EQ(loop.advance(0.06), 3);  // 0.03 s simulated
    EXPECT_NEAR(world->time(), 0.04, 1e-9);
    EXPECT_GT(loop.last_stats().substeps, 0);
}

// Each step of a frame has its own stats (the editor's per-step history), in order, the last one
// being last_stats(); a frame that ran none has none.
TEST(FrameLoop, EveryStepOfAFrameReportsItsStats) {
    auto world = small_world(0.01);
    FrameLoop loop(*world);
    EXPECT_EQ(loop.advance(0.035), 3);
    ASSERT_EQ(loop.frame_stats().size(), 3U);
    for (const StepStats& s : loop.frame_stats()) EXPECT_EQ(s.substeps, world->settings().solver.substeps);
    EXPECT_EQ(loop.frame_stats().back().step_ms, loop.last_stats().step_ms);
    EXPECT_EQ(loop.advance(0.001), 0);
    EXPECT_TRUE(loop.frame_stats().empty());
    loop.set_paused(true);
    loop.request_single_step();
    EXPECT_EQ(loop.advance(0.0), 1);
    EXPECT_EQ(loop.frame_stats().size(), 1U);
}

TEST(FrameLoop, BadValuesAreErrors) {
    auto world = small_world(0.01);
    EXPECT_THROW(FrameLoop(*world, {.time_scale = 0.0}), Error);
    EXPECT_THROW(FrameLoop(*world, {.time_scale = 1.0, .max_steps_per_frame = 0}), Error);
    FrameLoop loop(*world);
    EXPECT_THROW(loop.set_time_scale(1000.0), Error);
    EXPECT_THROW((void)loop.advance(-1.0), Error);
    EXPECT_THROW((void)loop.advance(std::numeric_limits<double>::quiet_NaN()), Error);
}

}  // namespace
}  // namespace weft
