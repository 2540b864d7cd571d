// Zero-copy interop between the CUDA backend and each renderer (docs/rendering.md), on a GPU host,
// through the frame pipeline's ClothFeed: the renderer exports two cloth slots, the backend takes
// them, its output kernel writes positions and normals straight into one slot while the renderer
// draws the frame before from the other, with no host wait between them.
// - Vulkan: memory and a timeline semaphore per slot exported as fds, imported by CUDA; the
//   timelines order writer and reader on the GPU.
// - EGL + OpenGL: two buffer objects registered with CUDA (cudaGraphicsGLRegisterBuffer); the
//   writer's map and unmap order it against GL's draws.
// Each test runs once per renderer ("vulkan", "egl").
// - The slot the renderer draws from holds exactly the solver's state (positions bit for bit).
// - The picture equals the host-upload picture of the same state.
// - No cloth byte crosses the bus: the renderer uploads 0 bytes per frame on this path.
// - 1,000 frames of the frame loop with simulation and drawing overlapped: every frame drew one
//   whole state, its own (the frame stamps the writer puts before and after the vertices, read back
//   by the renderer after its draws), and the slot's contents equal the state of that frame.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>

#include "gpu_test_util.h"
#include "multi/multi_gpu_backend.h"
#include "weft/error.h"
#include "weft/frame_loop.h"
#include "weft/render/cloth_feed.h"
#include "weft/render/renderer.h"
#include "weft/scene.h"

namespace weft {
namespace {

std::unique_ptr<render::Renderer> make_renderer(const std::string& name, std::string& why) {
    render::RendererOptions o;
    o.width = 320;
    o.height = 240;
    // Validation where the layer (or a GL debug context) is there (the GPU host gets the Vulkan
    // layer from .gpu-deps), else without.
    for (const bool validation : {true, false}) {
        o.validation = validation;
        try {
            return render::create_renderer(name, o);
        } catch (const Error& e) {
            why = e.what();
        }
    }
    return nullptr;
}

struct Rig {
    SceneDesc desc;
    std::unique_ptr<World> world;
    std::unique_ptr<render::Renderer> renderer;
    render::RenderScene scene;
};

// The flag on the cuda backend (with `overrides`), drawn by renderer `name`; nullopt (with `why`)
// without one.
std::optional<Rig> make_rig(const std::string& name, std::string& why, const std::vector<std::string>& overrides = {}) {
    Rig r;
    r.renderer = make_renderer(name, why);
    if (!r.renderer) return std::nullopt;
    const auto file = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / "flag.toml";
    r.desc = load_scene(file, overrides);
    r.world = build_world(r.desc, "cuda");
    r.scene = render::make_render_scene(*r.world, r.desc.camera);
    r.renderer->load(r.scene);
    return r;
}

// Largest differences between a slot's contents and the host's vertices of the same state.
struct Difference {
    double position = 0.0, normal = 0.0;
    bool positions_identical = true;
};

Difference compare(const std::vector<render::RenderVertex>& slot, const std::vector<render::RenderVertex>& host) {
    Difference d;
    for (std::size_t i = 0; i < host.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            if (slot[i].position[c] != host[i].position[c]) d.positions_identical = false;
            d.position = std::max(d.position, static_cast<double>(std::abs(host[i].position[c] - slot[i].position[c])));
            d.normal = std::max(d.normal, static_cast<double>(std::abs(host[i].normal[c] - slot[i].normal[c])));
        }
    return d;
}

class RenderInterop : public ::testing::TestWithParam<std::string> {};

TEST_P(RenderInterop, CudaWritesTheSlotsTheRendererDrawsWithoutACopy) {
    WEFT_REQUIRE_GPU();
    std::string why;
    std::optional<Rig> rig = make_rig(GetParam(), why);
    if (!rig) GTEST_SKIP() << "no " << GetParam() << " renderer: " << why;
    render::ClothFeed feed(*rig->world, *rig->renderer, rig->scene);
    ASSERT_TRUE(feed.zero_copy()) << "an NVIDIA " << GetParam() << " device on the backend's GPU must share: "
                                  << feed.fallback_reason();
    std::printf("[ interop  ] %s on %s\n", feed.describe().c_str(), rig->renderer->device_description().c_str());

    constexpr int kFrames = 30;
    render::Image picture;
    render::RenderFrame last;
    for (int k = 1; k <= kFrames; ++k) {
        last = feed.simulate([&] { (void)rig->world->step(); });
        EXPECT_EQ(last.cloth_slot, (k - 1) % 2) << "frames alternate between the two slots";
        EXPECT_TRUE(last.cloth.empty()) << "no host vertices on the zero-copy path";
        picture = rig->renderer->draw(last);
        ASSERT_EQ(rig->renderer->transfer().path, "interop") << "frame " << k;
        ASSERT_EQ(rig->renderer->transfer().bytes_uploaded, 0U) << "frame " << k;
        ASSERT_TRUE(feed.check(last, rig->renderer->transfer()))
            << "frame " << k << " stamps " << rig->renderer->transfer().stamp_first << "/"
            << rig->renderer->transfer().stamp_last;
    }

    // What the renderer drew from is the solver's state after the last step: positions bit for bit (the
    // state is float on the device; the host reads it as double and rounds it back).
    const std::vector<render::RenderVertex> slot = rig->renderer->read_cloth(last.cloth_slot);
    std::vector<render::RenderVertex> host;
    render::cloth_vertices(*rig->world, rig->scene, host);
    ASSERT_EQ(slot.size(), host.size());
    const Difference d = compare(slot, host);
    std::printf("[ interop  ] %zu vertices after %d frames: positions within %.3g m, normals within %.3g of the host's\n",
                host.size(), kFrames, d.position, d.normal);
    EXPECT_TRUE(d.positions_identical) << "the slot must hold exactly the solver's positions";
    EXPECT_LT(d.normal, 1e-4);

    // The picture drawn from the shared slot equals the host-upload picture of the same state.
    auto reference = make_renderer(GetParam(), why);
    ASSERT_TRUE(reference) << why;
    reference->load(rig->scene);
    render::RenderFrame upload;
    upload.cloth = host;
    upload.collider_models = last.collider_models;
    const render::Image expected = reference->draw(upload);
    EXPECT_EQ(reference->transfer().bytes_uploaded, host.size() * sizeof(render::RenderVertex));
    const render::ImageDifference diff = render::compare(picture, expected, 16);
    std::printf("[ interop  ] picture against the host upload: mean %.4f, max %d, %.4f %% over 16\n", diff.mean, diff.max,
                100.0 * diff.fraction_over);
    EXPECT_LT(diff.mean, 0.5);
    EXPECT_LT(diff.fraction_over, 0.002);
    EXPECT_GT(render::luminance_spread(picture), 10.0);
    EXPECT_EQ(rig->renderer->validation_messages(), 0);
}

// The frame loop of a game: each display frame runs the steps due (FrameLoop, 60 Hz display), and
// they run while the GPU draws the frame before: submit(N) → simulate(N+1) → collect(N). 1,000
// frames; every frame must have drawn one whole state, its own.
TEST_P(RenderInterop, ThousandOverlappedFramesDrawWholeStatesOnly) {
    WEFT_REQUIRE_GPU();
    std::string why;
    std::optional<Rig> rig = make_rig(GetParam(), why);
    if (!rig) GTEST_SKIP() << "no " << GetParam() << " renderer: " << why;
    render::ClothFeed feed(*rig->world, *rig->renderer, rig->scene);
    ASSERT_TRUE(feed.zero_copy()) << feed.fallback_reason();
    FrameLoop loop(*rig->world);

    constexpr int kFrames = 1000;
    constexpr int kContentEvery = 50;  // the slot compared with the host's copy of the state
    std::optional<render::RenderFrame> drawing;
    std::vector<render::RenderVertex> state_of_drawing, state;
    int compared = 0;
    std::int64_t steps = 0;
    for (int k = 1; k <= kFrames + 1; ++k) {
        std::optional<render::RenderFrame> next;
        if (k <= kFrames) {
            // Overlaps the draw of frame k−1 (submitted below in the last iteration, not waited for).
            next = feed.simulate([&] { steps += loop.advance(1.0 / 60.0); });
            if (k % kContentEvery == 0) render::cloth_vertices(*rig->world, rig->scene, state);
        }
        if (drawing) {
            (void)rig->renderer->collect();
            const render::TransferStats t = rig->renderer->transfer();
            ASSERT_TRUE(feed.check(*drawing, t)) << "frame " << drawing->stamp << " drew stamps " << t.stamp_first
                                                 << "/" << t.stamp_last;
            ASSERT_EQ(t.bytes_uploaded, 0U);
            if (drawing->stamp % kContentEvery == 0) {
                // The writer of frame k used the other slot; this one still holds frame k−1.
                const Difference d = compare(rig->renderer->read_cloth(drawing->cloth_slot), state_of_drawing);
                EXPECT_TRUE(d.positions_identical) << "frame " << drawing->stamp;
                ++compared;
            }
        }
        if (!next) break;
        rig->renderer->submit(*next);
        drawing = std::move(next);
        if (k % kContentEvery == 0) state_of_drawing = state;
    }
    std::printf("[ overlap  ] %d frames (%lld steps): %lld checked, %lld torn, %d slots compared with the state\n",
                kFrames, static_cast<long long>(steps), static_cast<long long>(feed.checked_frames()),
                static_cast<long long>(feed.torn_frames()), compared);
    EXPECT_EQ(feed.checked_frames(), kFrames);
    EXPECT_EQ(feed.torn_frames(), 0);
    EXPECT_EQ(compared, kFrames / kContentEvery);
    EXPECT_GT(steps, kFrames / 2) << "the loop ran the simulation";
    EXPECT_EQ(rig->renderer->validation_messages(), 0);

    // The check itself can fail: a frame that expected another state is counted as torn.
    render::RenderFrame wrong = *drawing;
    wrong.stamp += 2;
    EXPECT_FALSE(feed.check(wrong, rig->renderer->transfer()));
    EXPECT_EQ(feed.torn_frames(), 1);
}

// One world across two GPUs (two parts on one GPU where the host has one: the test mode): every part
// writes its owned vertices into a buffer on the first GPU, which copies it into the slot; the
// renderer draws the solver's state with no cloth byte through the host.
TEST_P(RenderInterop, AWorldAcrossGpusWritesTheSlotsToo) {
    WEFT_REQUIRE_GPU();
    const bool one_device = cuda::devices().size() < 2;
    if (one_device) setenv(cuda::multi::kPartsOnOneDeviceEnv, "1", 1);
    std::string why;
    std::optional<Rig> rig;
    try {
        rig = make_rig(GetParam(), why, {"solver.gpus=2"});
    } catch (...) {
        unsetenv(cuda::multi::kPartsOnOneDeviceEnv);
        throw;
    }
    unsetenv(cuda::multi::kPartsOnOneDeviceEnv);
    if (!rig) GTEST_SKIP() << "no " << GetParam() << " renderer: " << why;
    render::ClothFeed feed(*rig->world, *rig->renderer, rig->scene);
    ASSERT_TRUE(feed.zero_copy()) << feed.fallback_reason();
    std::printf("[ interop  ] %s, %s\n", feed.describe().c_str(), rig->world->device_description().c_str());
    render::RenderFrame last;
    for (int k = 1; k <= 20; ++k) {
        last = feed.simulate([&] { (void)rig->world->step(); });
        EXPECT_EQ(last.cloth_slot, (k - 1) % 2);
        (void)rig->renderer->draw(last);
        ASSERT_EQ(rig->renderer->transfer().path, "interop") << "frame " << k;
        ASSERT_EQ(rig->renderer->transfer().bytes_uploaded, 0U) << "frame " << k;
        ASSERT_TRUE(feed.check(last, rig->renderer->transfer())) << "frame " << k;
    }
    const std::vector<render::RenderVertex> slot = rig->renderer->read_cloth(last.cloth_slot);
    std::vector<render::RenderVertex> host;
    render::cloth_vertices(*rig->world, rig->scene, host);
    ASSERT_EQ(slot.size(), host.size());
    const Difference d = compare(slot, host);
    std::printf("[ interop  ] %zu vertices from 2 parts: positions within %.3g m, normals within %.3g of the host's\n",
                host.size(), d.position, d.normal);
    EXPECT_TRUE(d.positions_identical) << "every part's vertices, each where the renderer reads it";
    EXPECT_LT(d.normal, 1e-4);
    EXPECT_EQ(rig->renderer->validation_messages(), 0);
}

// The same feed with zero-copy off takes the host path on the same GPU and draws the same picture.
TEST_P(RenderInterop, HostUploadFallbackDrawsTheSamePicture) {
    WEFT_REQUIRE_GPU();
    std::string why;
    std::optional<Rig> a = make_rig(GetParam(), why);
    if (!a) GTEST_SKIP() << "no " << GetParam() << " renderer: " << why;
    std::optional<Rig> b = make_rig(GetParam(), why);
    ASSERT_TRUE(b) << why;
    render::ClothFeed shared(*a->world, *a->renderer, a->scene);
    render::ClothFeed uploaded(*b->world, *b->renderer, b->scene, render::ClothFeed::Options{false});
    ASSERT_TRUE(shared.zero_copy());
    ASSERT_FALSE(uploaded.zero_copy());
    EXPECT_EQ(uploaded.fallback_reason(), "zero-copy switched off");
    render::Image pa, pb;
    for (int k = 0; k < 10; ++k) {
        pa = a->renderer->draw(shared.simulate([&] { (void)a->world->step(); }));
        const render::RenderFrame f = uploaded.simulate([&] { (void)b->world->step(); });
        pb = b->renderer->draw(f);
        EXPECT_TRUE(uploaded.check(f, b->renderer->transfer()));
        EXPECT_EQ(b->renderer->transfer().path, "host upload");
        EXPECT_EQ(b->renderer->transfer().bytes_uploaded, b->scene.cloth_vertices * sizeof(render::RenderVertex));
    }
    const render::ImageDifference d = render::compare(pa, pb, 16);
    EXPECT_LT(d.mean, 0.5);
    EXPECT_LT(d.fraction_over, 0.002);
}

// The writer puts each slot's stamps after the world's vertices, so it must know them when it
// imports the slots. A world is built at its first step or read; sharing before that through the
// backend directly is refused with the reason, and World::share_output builds it first. (Sharing an
// unbuilt world once put the stamps at offset 0: the first frames read stale stamps and no cloth.)
TEST_P(RenderInterop, SharingNeedsABuiltWorld) {
    WEFT_REQUIRE_GPU();
    std::string why;
    std::optional<Rig> rig = make_rig(GetParam(), why);
    if (!rig) GTEST_SKIP() << "no " << GetParam() << " renderer: " << why;
    std::optional<render::ClothInterop> link = rig->renderer->export_cloth(why);
    ASSERT_TRUE(link) << why;
    std::string refused;
    EXPECT_EQ(rig->world->backend().share_output(link->slots, link->device_uuid, refused), nullptr);
    EXPECT_NE(refused.find("not built"), std::string::npos) << refused;

    // A new export (the first one's fds were given up above), now through the world: its first
    // frame reads its own stamps.
    render::ClothFeed feed(*rig->world, *rig->renderer, rig->scene);
    ASSERT_TRUE(feed.zero_copy()) << feed.fallback_reason();
    const render::RenderFrame frame = feed.simulate({});
    (void)rig->renderer->draw(frame);
    EXPECT_TRUE(feed.check(frame, rig->renderer->transfer()))
        << "stamps " << rig->renderer->transfer().stamp_first << "/" << rig->renderer->transfer().stamp_last;
}

INSTANTIATE_TEST_SUITE_P(Renderers, RenderInterop, ::testing::Values("vulkan", "egl"),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

}  // namespace
}  // namespace weft
