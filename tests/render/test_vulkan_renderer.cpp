// The Vulkan offscreen renderer on whatever device the loader gives here (lavapipe in CI, the GPU on
// a GPU host), with the validation layer on: the picture is there and upright, cloth is two-sided,
// the ball's shadow falls where the light puts it, MSAA only touches edges, frames are reproducible
// and uploads are counted. The checks shared with the EGL renderer are in render_checks.h.
// Every test that needs a device skips, saying why, where there is none.
// With WEFT_TEST_IMAGES=<folder> in the environment the pictures are written there as PNG files.
#include <gtest/gtest.h>

#include <cstring>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "weft/error.h"
#include "weft/render/image.h"
#include "weft/render/renderer.h"

#include "render_checks.h"
#include "render_test_scenes.h"
#include "vulkan/vulkan_context.h"

namespace weft::render {
namespace {

/// The test size, with the validation layer on (every test counts its messages).
RendererOptions small_options(int samples = 4) { return test::small_options(samples, /*validation=*/true); }

/// Why `e` means this machine cannot run the renderer (no Vulkan device, no validation layer), or
/// "" when it is the renderer's own error.
std::string machine_lacks(const Error& e) {
    const std::string what = e.what();
    if (what.find("no Vulkan device") != std::string::npos || what.find("is not installed") != std::string::npos ||
        what.find("older than Vulkan 1.1") != std::string::npos)
        return "Vulkan renderer unavailable: " + what;
    return {};
}

test::Created create(const RendererOptions& options) { return test::create("vulkan", options, machine_lacks); }

TEST(VulkanRenderer, RejectsBadOptions) {
    RendererOptions o = small_options();
    o.width = 0;
    EXPECT_THROW((void)create_renderer("vulkan", o), Error);
    o = small_options(3);
    EXPECT_THROW((void)create_renderer("vulkan", o), Error);
    o = small_options();
    o.shadow_map_size = 8;
    EXPECT_THROW((void)create_renderer("vulkan", o), Error);
}

TEST(VulkanRenderer, DrawsSheetOverBallWithoutValidationMessages) {
    const int before = detail::vulkan_validation_messages_total();
    test::Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    Renderer& r = *c.renderer;
    EXPECT_EQ(r.name(), "vulkan");
    const std::string device = r.device_description();
    EXPECT_NE(device.find(", Vulkan 1."), std::string::npos) << device;
    std::printf("vulkan renderer: %s\n", device.c_str());

    test::expect_draws_sheet_over_ball(r);

    // Destroying the device reports leaked objects; the process-wide count sees them.
    c.renderer.reset();
    EXPECT_EQ(detail::vulkan_validation_messages_total(), before) << "validation messages while destroying";
}

// The counter above could read 0 because nothing reaches it: break a rule on purpose and see it
// counted. (The layer prints the message below as "vulkan validation: ...": expected.)
TEST(VulkanRenderer, CountsValidationMessages) {
    try {
        const int before = detail::vulkan_validation_messages_total();
        detail::VulkanContext context(true);
        EXPECT_EQ(context.validation_messages(), 0);
        VkSamplerCreateInfo info{};
        info.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO;
        info.anisotropyEnable = VK_TRUE;  // without the samplerAnisotropy feature enabled: invalid
        info.maxAnisotropy = 4.0F;
        VkSampler sampler = VK_NULL_HANDLE;
        if (vkCreateSampler(context.device(), &info, nullptr, &sampler) == VK_SUCCESS)
            vkDestroySampler(context.device(), sampler, nullptr);
        EXPECT_GE(context.validation_messages(), 1);
        EXPECT_EQ(detail::vulkan_validation_messages_total() - before, context.validation_messages());
        const auto uuid = context.device_uuid();
        EXPECT_TRUE(std::any_of(uuid.begin(), uuid.end(), [](std::uint8_t b) { return b != 0; })) << "no device UUID";
    } catch (const Error& e) {
        const std::string why = machine_lacks(e);
        if (why.empty()) throw;
        GTEST_SKIP() << why;
    }
}

TEST(VulkanRenderer, ShowsTheSideOfTheClothThatFacesTheCamera) {
    const test::Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_shows_the_side_facing_the_camera(*c.renderer);
}

TEST(VulkanRenderer, BallShadowsTheGroundWhereTheLightPutsIt) {
    const test::Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_ball_shadow_where_the_light_puts_it(*c.renderer);
}

TEST(VulkanRenderer, DrawsAnAnimatedCharacterWhereEachFramePutsIt) {
    const test::Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_draws_deforming_colliders_where_the_frame_puts_them(*c.renderer);
}

TEST(VulkanRenderer, MultisamplingSmoothsEdgesOnly) {
    const test::Created c1 = create(small_options(1));
    if (!c1.renderer) GTEST_SKIP() << c1.skip;
    const test::Created c4 = create(small_options(4));
    ASSERT_TRUE(c4.renderer) << c4.skip;
    test::expect_multisampling_smooths_edges_only(*c1.renderer, *c4.renderer);
}

TEST(VulkanRenderer, RedrawsTheSameFrameBitForBitAndCountsUploads) {
    const test::Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_redraws_the_same_frame_bit_for_bit(*c.renderer);
}

// The zero-copy export: on a device that can export memory and timeline semaphores (an NVIDIA GPU)
// it hands out fds and draws "interop" frames ordered by the timeline; on one that cannot (lavapipe
// has no exportable semaphores) it says why, and the host upload keeps working. The GPU side (CUDA
// writing into the buffer) is tests/gpu/test_render_interop.cpp.
TEST(VulkanRenderer, ExportsTheClothBufferOrSaysWhyNot) {
    const test::Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    Renderer& r = *c.renderer;
    const test::TestScene t = test::sheet_over_ball();
    std::string why;
    EXPECT_THROW((void)r.export_cloth(why), Error) << "export before load()";
    r.load(t.scene);
    const auto link = r.export_cloth(why);
    RenderFrame timed;
    timed.collider_models = t.frame.collider_models;
    timed.signal_value = 1;
    if (!link) {
        std::printf("[ interop  ] %s\n", why.c_str());
        EXPECT_FALSE(why.empty());
        EXPECT_THROW((void)r.draw(timed), Error) << "timeline values without an exported buffer";
        (void)r.draw(t.frame);
        EXPECT_EQ(r.transfer().path, "host upload");
        EXPECT_TRUE(frame_intact(r.transfer(), t.frame.stamp)) << "the upload carries the frame's stamps";
        const std::vector<RenderVertex> back = r.read_cloth();
        ASSERT_EQ(back.size(), t.vertices.size());
        EXPECT_EQ(std::memcmp(back.data(), t.vertices.data(), back.size() * sizeof(RenderVertex)), 0)
            << "the buffer holds what was uploaded";
        return;
    }
    ASSERT_EQ(link->slots.size(), 2U) << "two slots: one written while the other is drawn";
    ASSERT_EQ(link->timeline_values.size(), 2U);
    for (const SharedSlotHandle& slot : link->slots) {
        EXPECT_GE(slot.memory.fd, 0);
        EXPECT_GE(slot.timeline.fd, 0);
        EXPECT_EQ(slot.memory.size, std::uint64_t{t.scene.cloth_vertices} * sizeof(RenderVertex) + kSlotStampBytes);
        EXPECT_GE(slot.memory.allocation_size, slot.memory.size);
    }
    timed.cloth_slot = 1;
    (void)r.draw(timed);  // nothing waits: value 1 is signalled after the frame
    EXPECT_EQ(r.transfer().path, "interop");
    EXPECT_EQ(r.transfer().bytes_uploaded, 0U);
    EXPECT_THROW((void)r.draw(timed), Error) << "timeline values must increase";
    timed.cloth_slot = 0;
    (void)r.draw(timed);  // each slot has its own timeline
    timed.cloth_slot = 2;
    EXPECT_THROW((void)r.draw(timed), Error) << "there is no slot 2";
    for (const SharedSlotHandle& slot : link->slots) {
        ::close(slot.memory.fd);
        ::close(slot.timeline.fd);
    }
    EXPECT_EQ(r.validation_messages(), 0);
}

// Not a check of speed (lavapipe's depends on the machine): the draw time per frame, median of 11,
// for the record, at the test size and at 720p with the default options.
TEST(VulkanRenderer, ReportsDrawTime) {
    for (const auto& [w, h] : {std::pair{320, 240}, std::pair{1280, 720}}) {
        RendererOptions o;
        o.width = w;
        o.height = h;
        const test::Created c = create(o);
        if (!c.renderer) GTEST_SKIP() << c.skip;
        const test::TestScene t = test::sheet_over_ball();
        c.renderer->load(t.scene);
        std::vector<double> ms;
        Image first, last;
        for (int k = 0; k < 11; ++k) {
            const auto start = std::chrono::steady_clock::now();
            last = c.renderer->draw(t.frame);
            ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
            if (k == 0) first = last;
        }
        EXPECT_EQ(first.rgba, last.rgba);
        std::sort(ms.begin(), ms.end());
        std::printf("%s, %d×%d, %d samples, shadow map %d²: draw median %.1f ms (min %.1f, max %.1f)\n",
                    c.renderer->device_description().c_str(), w, h, o.samples, o.shadow_map_size, ms[5], ms[0], ms[10]);
        test::save(c.renderer->name(), "sheet_over_ball_" + std::to_string(w) + "x" + std::to_string(h), last);
    }
}

TEST(VulkanRenderer, DrawsOverlayLinesFromTheClothBufferHiddenBehindWhatIsInFront) {
    const test::Created c = create(test::small_options(4, /*validation=*/true));
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_overlay_lines_over_the_cloth_only_where_seen(*c.renderer);
}

TEST(VulkanRenderer, DrawsOverlayPointsAtTheListedVerticesHiddenBehindWhatIsInFront) {
    const test::Created c = create(test::small_options(4, /*validation=*/true));
    if (!c.renderer) GTEST_SKIP() << c.skip;
    test::expect_overlay_points_at_the_listed_vertices_where_seen(*c.renderer);
}

}  // namespace

}  // namespace weft::render
