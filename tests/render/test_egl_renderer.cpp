// The EGL + OpenGL 4.5 capture renderer on whatever EGL gives here (llvmpipe in CI, the GPU on a
// GPU host): the picture is there and upright, cloth is two-sided, the ball casts its shadow where
// the light puts it, MSAA only touches edges, frames are reproducible, and renderers coexist.
// The checks shared with the Vulkan renderer are in render_checks.h.
// Every test skips, saying why, where no EGL display gives an OpenGL 4.5 core context.
// With WEFT_TEST_IMAGES=<folder> in the environment the pictures are written there as PNG files.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "weft/error.h"
#include "weft/render/image.h"
#include "weft/render/renderer.h"

#include "render_checks.h"
#include "render_test_scenes.h"

namespace weft::render {
namespace {

/// Why `e` means this machine has no EGL renderer (no EGL display, no OpenGL 4.5 context or debug
/// context), or "" when it is the renderer's own error.
std::string machine_lacks(const Error& e) {
    const std::string what = e.what();
    if (what.find("no EGL display") != std::string::npos || what.find("no debug context") != std::string::npos)
        return "EGL renderer unavailable: " + what;
    return {};
}

test::Created create(const RendererOptions& options) { return test::create("egl", options, machine_lacks); }

TEST(EglRenderer, DrawsSheetOverBallWithoutDebugMessages) {
    const test::Created c = create(test::small_options(4, /*validation=*/true));
    if (!c.renderer) GTEST_SKIP() << c.skip;
    Renderer& r = *c.renderer;
    EXPECT_EQ(r.name(), "egl");
    const std::string device = r.device_description();
    EXPECT_NE(device.find(", OpenGL "), std::string::npos) << device;
    EXPECT_NE(device.find("(EGL "), std::string::npos) << device;
    std::printf("egl renderer: %s\n", device.c_str());
    test::expect_draws_sheet_over_ball(r);
}

TEST(EglRenderer, ShowsTheSideOfTheClothThatFacesTheCamera) {
    const test::Created c = create(test::small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_shows_the_side_facing_the_camera(*c.renderer);
}

TEST(EglRenderer, BallShadowsTheGroundWhereTheLightPutsIt) {
    const test::Created c = create(test::small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_ball_shadow_where_the_light_puts_it(*c.renderer);
}

TEST(EglRenderer, MultisamplingSmoothsEdgesOnly) {
    const test::Created c1 = create(test::small_options(1));
    if (!c1.renderer) GTEST_SKIP() << c1.skip;
    const test::Created c4 = create(test::small_options(4));
    ASSERT_TRUE(c4.renderer) << c4.skip;
    test::expect_multisampling_smooths_edges_only(*c1.renderer, *c4.renderer);
}

TEST(EglRenderer, RedrawsTheSameFrameBitForBit) {
    const test::Created c = create(test::small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_redraws_the_same_frame_bit_for_bit(*c.renderer);
}

TEST(EglRenderer, SeveralRenderersLiveSideBySide) {
    test::Created first = create(test::small_options());
    if (!first.renderer) GTEST_SKIP() << first.skip;
    test::Created second = create(test::small_options());
    ASSERT_TRUE(second.renderer) << second.skip;
    const test::TestScene t = test::sheet_over_ball();
    const test::TestScene back = test::sheet_over_ball(true);
    first.renderer->load(t.scene);
    second.renderer->load(back.scene);
    const Image a = first.renderer->draw(t.frame);
    const Image b = second.renderer->draw(back.frame);
    EXPECT_GT(luminance_spread(a), 10.0);
    EXPECT_GT(luminance_spread(b), 10.0);
    EXPECT_GT(compare(a, b).fraction_over, 0.01) << "the two renderers drew the same scene";
    // Each keeps its own context, objects and state.
    EXPECT_EQ(first.renderer->draw(t.frame).rgba, a.rgba);
    EXPECT_EQ(second.renderer->draw(back.frame).rgba, b.rgba);

    // Dropping one leaves the other working (the shared EGL display stays up), and a new one can
    // start once both are gone.
    first.renderer.reset();
    EXPECT_EQ(second.renderer->draw(back.frame).rgba, b.rgba);
    second.renderer.reset();
    const test::Created third = create(test::small_options());
    ASSERT_TRUE(third.renderer) << third.skip;
    third.renderer->load(t.scene);
    EXPECT_EQ(third.renderer->draw(t.frame).rgba, a.rgba);
}

}  // namespace
}  // namespace weft::render
