// The frame pipeline's ClothFeed on a machine without a shared GPU (label `render`; lavapipe and
// llvmpipe in CI, the CPU backend): the fallback is taken with its reason, frames drawn overlapped
// with the next frame's steps show exactly their own state, and the stamps tell a torn read from a
// whole one. The zero-copy path is tests/gpu/test_render_interop.cpp.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>

#include "render_checks.h"
#include "weft/backend/backend.h"
#include "weft/error.h"
#include "weft/frame_loop.h"
#include "weft/render/cloth_feed.h"
#include "weft/render/renderer.h"
#include "weft/scene.h"

namespace weft::render {
namespace {

// The renderer, or (skip) why this machine has none.
std::unique_ptr<Renderer> try_renderer(const std::string& name, std::string& why) {
    RendererOptions o;
    o.width = 160;
    o.height = 120;
    o.validation = true;
    test::Created c = test::create(name, o, [](const Error& e) { return std::string(e.what()); });
    why = c.skip;
    return std::move(c.renderer);
}

std::unique_ptr<World> small_flag(SceneDesc& desc) {
    const auto file = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / "flag.toml";
    const std::vector<std::string> overrides{"cloth.flag.mesh.grid.cells=[12,8]"};
    desc = load_scene(file, overrides);
    return build_world(desc, "cpu");
}

TEST(ClothFeed, TheCpuBackendFallsBackToTheHostUploadAndSaysWhy) {
    SceneDesc desc;
    auto world = small_flag(desc);
    std::string why;
    // The CPU backend imports nothing: its reason, and the fds it was given are closed (not leaked).
    const std::unique_ptr<SharedOutput> none = world->backend().share_output({}, DeviceUuid{}, why);
    EXPECT_EQ(none, nullptr);
    EXPECT_NE(why.find("host memory"), std::string::npos) << why;

    for (const std::string& name : renderer_names()) {
        auto renderer = try_renderer(name, why);
        if (!renderer) {
            std::printf("[  SKIPPED ] renderer %s: %s\n", name.c_str(), why.c_str());
            continue;
        }
        const RenderScene scene = make_render_scene(*world, desc.camera);
        renderer->load(scene);
        ClothFeed feed(*world, *renderer, scene);
        EXPECT_FALSE(feed.zero_copy()) << name;
        EXPECT_FALSE(feed.fallback_reason().empty()) << name;
        EXPECT_EQ(feed.describe().rfind("host upload (", 0), 0U) << feed.describe();
        std::printf("[ feed     ] %s: %s\n", name.c_str(), feed.describe().c_str());
    }
}

// A game's loop: submit(N), then the steps of N+1 while N draws, then collect(N). Each drawn frame
// holds exactly the state it was made from, and its stamps say so.
TEST(ClothFeed, OverlappedFramesDrawTheirOwnState) {
    for (const std::string& name : renderer_names()) {
        SCOPED_TRACE(name);
        std::string why;
        auto renderer = try_renderer(name, why);
        if (!renderer) {
            std::printf("[  SKIPPED ] renderer %s: %s\n", name.c_str(), why.c_str());
            continue;
        }
        SceneDesc desc;
        auto world = small_flag(desc);
        const RenderScene scene = make_render_scene(*world, desc.camera);
        renderer->load(scene);
        ClothFeed feed(*world, *renderer, scene);
        FrameLoop loop(*world);

        constexpr int kFrames = 24;
        std::optional<RenderFrame> drawing;
        std::vector<RenderVertex> drawing_state;
        for (int k = 1; k <= kFrames + 1; ++k) {
            std::optional<RenderFrame> next;
            if (k <= kFrames) next = feed.simulate([&] { (void)loop.advance(1.0 / 60.0); });
            if (drawing) {
                (void)renderer->collect();
                EXPECT_TRUE(feed.check(*drawing, renderer->transfer())) << "frame " << drawing->stamp;
                const std::vector<RenderVertex> drawn = renderer->read_cloth(drawing->cloth_slot);
                ASSERT_EQ(drawn.size(), drawing_state.size());
                EXPECT_EQ(std::memcmp(drawn.data(), drawing_state.data(), drawn.size() * sizeof(RenderVertex)), 0)
                    << "frame " << drawing->stamp << " drew another state than its own";
            }
            if (!next) break;
            EXPECT_EQ(next->stamp, static_cast<std::uint64_t>(k)) << "frames are numbered from 1";
            EXPECT_EQ(next->cloth.size(), scene.cloth_vertices) << "the host path carries the vertices";
            drawing_state.assign(next->cloth.begin(), next->cloth.end());
            renderer->submit(*next);
            EXPECT_EQ(renderer->transfer().bytes_uploaded, scene.cloth_vertices * sizeof(RenderVertex));
            drawing = std::move(next);
        }
        EXPECT_EQ(feed.frames(), kFrames);
        EXPECT_EQ(feed.checked_frames(), kFrames);
        EXPECT_EQ(feed.torn_frames(), 0);
        EXPECT_GT(loop.steps(), 0);
        EXPECT_EQ(renderer->validation_messages(), 0);
    }
}

// The tearing check is only worth something if it can fail: stamps that differ from each other (a
// read that began before the writer's last vertex) or from the frame's own are torn.
TEST(ClothFeed, StampsThatDisagreeAreATornFrame) {
    TransferStats t;
    t.stamp_first = 7;
    t.stamp_last = 7;
    EXPECT_TRUE(frame_intact(t, 7));
    EXPECT_FALSE(frame_intact(t, 5)) << "a whole state, but an older one";
    t.stamp_first = 9;
    EXPECT_FALSE(frame_intact(t, 7)) << "the writer of frame 9 began before the read ended";
    EXPECT_FALSE(frame_intact(t, 9));
}

}  // namespace
}  // namespace weft::render
