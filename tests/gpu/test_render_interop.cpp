// Zero-copy interop between the CUDA backend and the Vulkan renderer (docs/rendering.md), on a GPU
// host: the renderer exports its cloth buffer and a timeline semaphore, CUDA imports them, the
// solver's last kernel writes positions and normals straight into the buffer, and Vulkan draws
// from it, the two ordered by the timeline with no host wait between them.
// - Vulkan reads exactly the bytes CUDA wrote (the buffer copied out through each API, compared).
// - Those bytes are the solver's state (positions against World::positions, rounded to float).
// - The picture equals the host-upload picture of the same state (normals computed on the host).
// - No cloth byte crosses the bus: the renderer uploads 0 bytes per frame on this path.
#include <gtest/gtest.h>

#include <cuda_runtime_api.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "gpu_test_util.h"
#include "weft/cuda/external_memory.h"
#include "weft/error.h"
#include "weft/render/renderer.h"
#include "weft/scene.h"

namespace weft {
namespace {

std::unique_ptr<render::Renderer> vulkan_renderer(std::string& why) {
    render::RendererOptions o;
    o.width = 320;
    o.height = 240;
    // Validation where the layer is installed (the GPU host gets it from .gpu-deps), else without.
    for (const bool validation : {true, false}) {
        o.validation = validation;
        try {
            return render::create_renderer("vulkan", o);
        } catch (const Error& e) {
            why = e.what();
        }
    }
    return nullptr;
}

int cuda_device_of(const DeviceUuid& uuid) {
    for (const cuda::DeviceInfo& d : cuda::devices())
        if (std::equal(uuid.begin(), uuid.end(), std::begin(d.uuid))) return d.ordinal;
    return -1;
}

TEST(RenderInterop, CudaWritesTheBufferVulkanDrawsWithoutACopy) {
    WEFT_REQUIRE_GPU();
    std::string why;
    auto renderer = vulkan_renderer(why);
    if (!renderer) GTEST_SKIP() << "no Vulkan renderer: " << why;
    const auto file = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / "flag.toml";
    const SceneDesc desc = load_scene(file, {});
    auto world = build_world(desc, "cuda");
    const render::RenderScene scene = render::make_render_scene(*world, desc.camera);
    renderer->load(scene);
    auto link = renderer->export_cloth(why);
    ASSERT_TRUE(link.has_value()) << "an NVIDIA Vulkan device must export: " << why;
    const int device = cuda_device_of(link->device_uuid);
    ASSERT_EQ(device, 0) << "the Vulkan device is CUDA device 0 (the backend's), matched by UUID";

    cuda::ImportedBuffer buffer(device, link->memory);
    cuda::ImportedTimeline timeline(device, link->timeline);
    ASSERT_EQ(buffer.size(), std::uint64_t{scene.cloth_vertices} * sizeof(render::RenderVertex));
    cuda::CudaBackendApi* api = cuda::as_cuda(world->backend());
    ASSERT_NE(api, nullptr);
    cudaStream_t stream = nullptr;
    ASSERT_EQ(cudaStreamCreate(&stream), cudaSuccess);
    api->set_stream(stream);
    api->set_output(buffer.device_pointer());

    // Per frame k: CUDA waits for the renderer's release of frame k−1 (2k−2), steps (the output
    // kernel writes the buffer), signals 2k−1; the renderer waits for 2k−1, draws, signals 2k.
    constexpr int kFrames = 30;
    render::Image picture;
    for (int k = 1; k <= kFrames; ++k) {
        timeline.wait(2U * static_cast<std::uint64_t>(k) - 2U, stream);
        (void)world->step();
        timeline.signal(2U * static_cast<std::uint64_t>(k) - 1U, stream);
        render::RenderFrame frame;
        frame.collider_models = render::collider_models(scene, world->model(), world->time());
        frame.wait_value = 2U * static_cast<std::uint64_t>(k) - 1U;
        frame.signal_value = 2U * static_cast<std::uint64_t>(k);
        picture = renderer->draw(frame);
        ASSERT_EQ(renderer->transfer().path, "interop") << "frame " << k;
        ASSERT_EQ(renderer->transfer().bytes_uploaded, 0U) << "frame " << k;
    }
    ASSERT_EQ(cudaStreamSynchronize(stream), cudaSuccess);

    // The same bytes through both APIs.
    const std::vector<render::RenderVertex> seen_by_vulkan = renderer->read_cloth();
    std::vector<render::RenderVertex> written_by_cuda(scene.cloth_vertices);
    ASSERT_EQ(cudaMemcpy(written_by_cuda.data(), buffer.device_pointer(), buffer.size(), cudaMemcpyDeviceToHost),
              cudaSuccess);
    ASSERT_EQ(seen_by_vulkan.size(), written_by_cuda.size());
    EXPECT_EQ(std::memcmp(seen_by_vulkan.data(), written_by_cuda.data(), buffer.size()), 0)
        << "Vulkan must read exactly what CUDA wrote";

    // They are the solver's state after the last step.
    std::vector<render::RenderVertex> host;
    render::cloth_vertices(*world, scene, host);
    double position_error = 0.0, normal_error = 0.0;
    for (std::size_t i = 0; i < host.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            position_error = std::max(position_error, static_cast<double>(std::abs(host[i].position[c] - written_by_cuda[i].position[c])));
            normal_error = std::max(normal_error, static_cast<double>(std::abs(host[i].normal[c] - written_by_cuda[i].normal[c])));
        }
    std::printf("[ interop  ] %u vertices after %d frames: positions within %.3g m, normals within %.3g of the host's\n",
                scene.cloth_vertices, kFrames, position_error, normal_error);
    EXPECT_LT(position_error, 1e-6);
    EXPECT_LT(normal_error, 1e-4);

    // The picture drawn from the shared buffer equals the host-upload picture of the same state.
    auto reference = vulkan_renderer(why);
    ASSERT_TRUE(reference) << why;
    reference->load(scene);
    render::RenderFrame upload;
    upload.cloth = host;
    upload.collider_models = render::collider_models(scene, world->model(), world->time());
    const render::Image expected = reference->draw(upload);
    EXPECT_EQ(reference->transfer().bytes_uploaded, host.size() * sizeof(render::RenderVertex));
    const render::ImageDifference d = render::compare(picture, expected, 16);
    std::printf("[ interop  ] picture against the host upload: mean %.4f, max %d, %.4f %% over 16\n", d.mean, d.max,
                100.0 * d.fraction_over);
    EXPECT_LT(d.mean, 0.5);
    EXPECT_LT(d.fraction_over, 0.002);
    EXPECT_GT(render::luminance_spread(picture), 10.0);
    EXPECT_EQ(renderer->validation_messages(), 0);

    api->set_output(nullptr);
    api->set_stream(nullptr);
    cudaStreamDestroy(stream);
}

}  // namespace
}  // namespace weft
