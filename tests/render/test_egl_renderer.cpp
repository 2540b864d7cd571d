// The EGL + OpenGL 4.5 capture renderer on whatever EGL gives here (llvmpipe in CI, the GPU on a
// GPU host): the picture is there and upright, cloth is two-sided, the ball casts its shadow where
// the light puts it, MSAA only touches edges, frames are reproducible, and renderers coexist.
// The checks shared with the Vulkan renderer are in render_checks.h.
// Every test skips, saying why, where no EGL display gives an OpenGL 4.5 core context.
// With WEFT_TEST_IMAGES=<folder> in the environment the pictures are written there as PNG files.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <optional>
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

TEST(EglRenderer, DrawsAnAnimatedCharacterWhereEachFramePutsIt) {
    const test::Created c = create(test::small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_draws_deforming_colliders_where_the_frame_puts_them(*c.renderer);
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

// The slots the EGL renderer shares with CUDA (SlotApi::opengl_buffer): two buffer objects sized
// for the vertices and the stamps. Without CUDA here, a host frame fills slot 1 (an uploaded frame
// goes into its slot once slots exist); a frame with no vertices then draws from that slot without
// an upload, gives the same picture, and reads the slot's stamps (zeros: no writer stamped it).
TEST(EglRenderer, DrawsFromAnExportedSlotWithoutAnUpload) {
    const test::Created c = create(test::small_options(4, /*validation=*/true));
    if (!c.renderer) GTEST_SKIP() << c.skip;
    Renderer& r = *c.renderer;
    const test::TestScene t = test::sheet_over_ball();
    r.load(t.scene);
    std::string why;
    const std::optional<ClothInterop> link = r.export_cloth(why);
    ASSERT_TRUE(link) << why;
    ASSERT_EQ(link->slots.size(), 2U);
    const std::uint64_t bytes = t.scene.cloth_vertices * sizeof(RenderVertex) + kSlotStampBytes;
    for (const SharedSlotHandle& s : link->slots) {
        EXPECT_EQ(s.api, SlotApi::opengl_buffer);
        EXPECT_NE(s.gl_buffer.name, 0U);
        EXPECT_EQ(slot_bytes(s), bytes);
        EXPECT_EQ(s.memory.fd, -1) << "nothing to close: GL shares names, not fds";
    }
    EXPECT_NE(link->slots[0].gl_buffer.name, link->slots[1].gl_buffer.name);
    for (const RenderVertex& v : r.read_cloth(0)) ASSERT_EQ(v.position[0], 0.0F) << "a slot starts zeroed";

    RenderFrame upload = t.frame;
    upload.cloth_slot = 1;
    upload.stamp = 5;
    const Image uploaded = r.draw(upload);
    EXPECT_EQ(r.transfer().path, "host upload");
    EXPECT_TRUE(frame_intact(r.transfer(), 5));
    const std::vector<RenderVertex> slot1 = r.read_cloth(1);
    ASSERT_EQ(slot1.size(), t.vertices.size());
    EXPECT_EQ(std::memcmp(slot1.data(), t.vertices.data(), slot1.size() * sizeof(RenderVertex)), 0);
    EXPECT_EQ(r.read_cloth(0)[0].position[0], 0.0F) << "slot 0 untouched";

    RenderFrame shared = t.frame;
    shared.cloth = {};
    shared.cloth_slot = 1;
    shared.stamp = 6;
    r.submit(shared);
    EXPECT_EQ(r.transfer().path, "interop");
    EXPECT_EQ(r.transfer().bytes_uploaded, 0U);
    const Image drawn = r.collect();
    EXPECT_EQ(drawn.rgba, uploaded.rgba) << "the slot's vertices, drawn as uploaded";
    EXPECT_EQ(r.transfer().stamp_first, 0U);
    EXPECT_EQ(r.transfer().stamp_last, 0U);
    EXPECT_FALSE(frame_intact(r.transfer(), 6)) << "no writer stamped the slot: not this frame's state";

    shared.cloth_slot = 2;
    EXPECT_THROW(r.submit(shared), Error);
    EXPECT_THROW(r.read_cloth(2), Error);
    EXPECT_EQ(r.validation_messages(), 0);
}

// submit() only queues (the picture lands in a pixel buffer behind a fence); collect() returns the
// same picture draw() does, once: a second collect() has nothing to wait for.
TEST(EglRenderer, SubmitQueuesAndCollectReturnsThePictureOnce) {
    const test::Created c = create(test::small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    Renderer& r = *c.renderer;
    const test::TestScene t = test::sheet_over_ball();
    r.load(t.scene);
    const Image expected = r.draw(t.frame);
    r.submit(t.frame);
    r.submit(t.frame);  // the first is collected and dropped
    EXPECT_EQ(r.collect().rgba, expected.rgba);
    EXPECT_THROW((void)r.collect(), Error);
}

TEST(EglRenderer, DrawsOverlayLinesFromTheClothBufferHiddenBehindWhatIsInFront) {
    const test::Created c = create(test::small_options(4, /*validation=*/true));
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_overlay_lines_over_the_cloth_only_where_seen(*c.renderer);
}

TEST(EglRenderer, DrawsOverlayPointsAtTheListedVerticesHiddenBehindWhatIsInFront) {
    const test::Created c = create(test::small_options(4, /*validation=*/true));
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_overlay_points_at_the_listed_vertices_where_seen(*c.renderer);
}

}  // namespace

}  // namespace weft::render
