// The Vulkan offscreen renderer on whatever device the loader gives here (lavapipe in CI, the GPU on
// a GPU host), with the validation layer on: the picture is there and upright, cloth is two-sided,
// the ball's shadow falls where the light puts it, MSAA only touches edges, frames are reproducible
// and uploads are counted. Every test that needs a device skips, saying why, where there is none.
// With WEFT_TEST_IMAGES=<folder> in the environment the pictures are written there as PNG files.
#include <gtest/gtest.h>

#include <cstring>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <string>
#include <utility>
#include <vector>

#include "weft/error.h"
#include "weft/render/image.h"
#include "weft/render/renderer.h"

#include "frame_uniforms.h"
#include "render_test_scenes.h"
#include "vulkan/vulkan_context.h"

namespace weft::render {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr int kShadowMap = 1024;

RendererOptions small_options(int samples = 4) {
    RendererOptions o;
    o.width = kWidth;
    o.height = kHeight;
    o.samples = samples;
    o.shadow_map_size = kShadowMap;
    o.validation = true;
    return o;
}

/// The renderer, or why this machine has none (no Vulkan device, no validation layer): a reason to
/// skip. Errors of the renderer itself are not caught here: they fail the test.
struct Created {
    std::unique_ptr<Renderer> renderer;
    std::string skip;
};

/// Why `e` means this machine cannot run the renderer, or "" when it is the renderer's own error.
std::string machine_lacks(const Error& e) {
    const std::string what = e.what();
    if (what.find("no Vulkan device") != std::string::npos || what.find("is not installed") != std::string::npos ||
        what.find("older than Vulkan 1.1") != std::string::npos)
        return "Vulkan renderer unavailable: " + what;
    return {};
}

Created create(const RendererOptions& options) {
    try {
        return {create_renderer("vulkan", options), {}};
    } catch (const Error& e) {
        std::string why = machine_lacks(e);
        if (why.empty()) throw;
        return {nullptr, std::move(why)};
    }
}

void save(const Image& image, const std::string& name) {
    const char* folder = std::getenv("WEFT_TEST_IMAGES");
    if (folder == nullptr || *folder == '\0') return;
    std::filesystem::create_directories(folder);
    write_png(std::filesystem::path(folder) / ("vulkan_" + name + ".png"), image);
}

float encode_srgb(float linear) {
    linear = std::clamp(linear, 0.0F, 1.0F);
    return linear <= 0.0031308F ? linear * 12.92F : 1.055F * std::pow(linear, 1.0F / 2.4F) - 0.055F;
}

double luminance(const Image& image, int x, int y) {
    const std::uint8_t* p = image.pixel(x, y);
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

/// Mean colour of the (2r+1)² pixels around (x, y) with r + g + b = 1: the hue and saturation,
/// whatever the lighting's brightness.
glm::vec3 chromaticity(const Image& image, int x, int y, int r) {
    glm::vec3 sum(0.0F);
    for (int j = y - r; j <= y + r; ++j)
        for (int i = x - r; i <= x + r; ++i) {
            const std::uint8_t* p = image.pixel(i, j);
            sum += glm::vec3(p[0], p[1], p[2]);
        }
    return sum / (sum.r + sum.g + sum.b);
}

glm::vec3 encoded_chromaticity(glm::vec3 linear) {
    const glm::vec3 c(encode_srgb(linear.r), encode_srgb(linear.g), encode_srgb(linear.b));
    return c / (c.r + c.g + c.b);
}

/// Pixel (column, row from the top) where world point `p` lands: clip y points up, rows go down.
glm::vec2 to_pixel(const glm::mat4& view_projection, glm::vec3 p) {
    const glm::vec4 c = view_projection * glm::vec4(p, 1.0F);
    return {(c.x / c.w + 1.0F) * 0.5F * kWidth, (1.0F - c.y / c.w) * 0.5F * kHeight};
}

/// The point of the ground (y = 0) seen through the centre of pixel (x, y); false above the horizon.
bool ground_point(const glm::mat4& view_projection, int x, int y, glm::vec3& eye, glm::vec3& ground) {
    const glm::mat4 inverse = glm::inverse(view_projection);
    const glm::vec2 ndc((static_cast<float>(x) + 0.5F) / kWidth * 2.0F - 1.0F,
                        1.0F - (static_cast<float>(y) + 0.5F) / kHeight * 2.0F);
    const glm::vec4 n = inverse * glm::vec4(ndc, 0.0F, 1.0F);  // clip depth 0..1
    const glm::vec4 f = inverse * glm::vec4(ndc, 1.0F, 1.0F);
    eye = glm::vec3(n) / n.w;
    const glm::vec3 d = glm::vec3(f) / f.w - eye;
    if (d.y >= 0.0F) return false;
    ground = eye + d * (-eye.y / d.y);
    return true;
}

/// Distance from `p` to the segment from `a` to `b`.
float distance_to_segment(glm::vec3 p, glm::vec3 a, glm::vec3 b) {
    const glm::vec3 ab = b - a;
    const float s = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0F, 1.0F);
    return glm::length(p - (a + s * ab));
}

/// Whether the segment from `a` to `b` crosses a cloth triangle (Möller–Trumbore).
bool hits_cloth(const test::TestScene& t, glm::vec3 a, glm::vec3 b) {
    const glm::vec3 d = b - a;
    const auto at = [&](std::uint32_t i) {
        const RenderVertex& v = t.vertices[i];
        return glm::vec3(v.position[0], v.position[1], v.position[2]);
    };
    for (std::size_t k = 0; k + 2 < t.scene.cloth_indices.size(); k += 3) {
        const glm::vec3 p0 = at(t.scene.cloth_indices[k]), e1 = at(t.scene.cloth_indices[k + 1]) - p0,
                        e2 = at(t.scene.cloth_indices[k + 2]) - p0;
        const glm::vec3 q = glm::cross(d, e2);
        const float det = glm::dot(e1, q);
        if (std::abs(det) < 1e-12F) continue;
        const glm::vec3 s = (a - p0) / det;
        const float u = glm::dot(s, q);
        const glm::vec3 r = glm::cross(s, e1);
        const float v = glm::dot(d, r);
        const float h = glm::dot(e2, r);
        if (u >= 0.0F && v >= 0.0F && u + v <= 1.0F && h >= 0.0F && h <= 1.0F) return true;
    }
    return false;
}

std::size_t collider_index(const RenderScene& scene, const std::string& name) {
    for (std::size_t k = 0; k < scene.colliders.size(); ++k)
        if (scene.colliders[k].name == name) return k;
    ADD_FAILURE() << "no collider " << name;
    return 0;
}

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
    Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    Renderer& r = *c.renderer;
    EXPECT_EQ(r.name(), "vulkan");
    const std::string device = r.device_description();
    EXPECT_NE(device.find(", Vulkan 1."), std::string::npos) << device;
    std::printf("vulkan renderer: %s\n", device.c_str());

    const test::TestScene t = test::sheet_over_ball();
    r.load(t.scene);
    const Image image = r.draw(t.frame);
    save(image, "sheet_over_ball");
    ASSERT_EQ(image.width, kWidth);
    ASSERT_EQ(image.height, kHeight);
    EXPECT_GT(luminance_spread(image), 10.0);
    EXPECT_EQ(r.validation_messages(), 0);
    EXPECT_EQ(r.transfer().path, "host upload");
    EXPECT_EQ(r.transfer().bytes_uploaded, std::uint64_t{t.scene.cloth_vertices} * sizeof(RenderVertex));

    // Upright: the top row is the clear colour (sRGB-encoded), the bottom rows are ground.
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(image.pixel(0, 0)[k], encode_srgb(t.scene.background[k]) * 255.0F, 1.0F) << "channel " << k;
        EXPECT_NEAR(image.pixel(kWidth - 1, 0)[k], encode_srgb(t.scene.background[k]) * 255.0F, 1.0F)
            << "channel " << k;
    }
    EXPECT_EQ(image.pixel(0, 0)[3], 255);
    EXPECT_GT(glm::length(chromaticity(image, kWidth / 2, kHeight - 3, 2) - encoded_chromaticity(t.scene.background)),
              0.01F)
        << "the bottom rows show the sky: the picture is upside down or the ground is missing";

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
    const Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    for (const bool show_back : {false, true}) {
        const test::TestScene t = test::sheet_over_ball(show_back);
        c.renderer->load(t.scene);
        const Image image = c.renderer->draw(t.frame);
        save(image, show_back ? "sheet_back" : "sheet_front");
        glm::vec3 centre(0.0F);
        for (const RenderVertex& v : t.vertices) centre += glm::vec3(v.position[0], v.position[1], v.position[2]);
        centre /= static_cast<float>(t.vertices.size());
        const detail::FrameUniforms u = detail::frame_uniforms(t.scene, kWidth, kHeight, kShadowMap);
        const glm::vec2 p = to_pixel(u.view_projection, centre);
        const int x = static_cast<int>(p.x), y = static_cast<int>(p.y);
        ASSERT_TRUE(x >= 2 && x < kWidth - 2 && y >= 2 && y < kHeight - 2) << p.x << ", " << p.y;
        const glm::vec3 seen = chromaticity(image, x, y, 2);
        const float to_front = glm::length(seen - encoded_chromaticity(t.scene.cloths[0].front_colour));
        const float to_back = glm::length(seen - encoded_chromaticity(t.scene.cloths[0].back_colour));
        if (show_back)
            EXPECT_LT(to_back, to_front) << "the turned-over sheet shows its front colour at (" << x << ", " << y
                                         << ")";
        else
            EXPECT_LT(to_front, to_back) << "the sheet shows its back colour at (" << x << ", " << y << ")";
    }
    EXPECT_EQ(c.renderer->validation_messages(), 0);
}

// Drawn with the ball and with the ball 100 m away (outside the view and the shadow map): ground
// pixels whose way to the light passes through the ball get darker, and everything clear of the
// ball and its shadow stays exactly the same. Pixels where the ball is in view, and ground near the
// edge of its shadow, are left out; so are shadowed ground points hidden by the sheet or in its
// shadow, where the ball's makes no difference.
TEST(VulkanRenderer, BallShadowsTheGroundWhereTheLightPutsIt) {
    const Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    const test::TestScene t = test::sheet_over_ball();
    c.renderer->load(t.scene);
    const Image with_ball = c.renderer->draw(t.frame);
    const std::size_t ball = collider_index(t.scene, "ball");
    RenderFrame away = t.frame;
    away.collider_models[ball] =
        glm::translate(glm::mat4(1.0F), glm::vec3(100.0F, 0.0F, 0.0F)) * away.collider_models[ball];
    const Image without_ball = c.renderer->draw(away);
    save(with_ball, "shadow_with_ball");
    save(without_ball, "shadow_ball_away");

    const glm::vec3 centre(t.frame.collider_models[ball][3]);
    float radius = 0.0F;
    for (const RenderVertex& v : t.scene.colliders[ball].mesh.vertices)
        radius = std::max(radius, glm::length(glm::vec3(v.position[0], v.position[1], v.position[2])));
    const glm::vec3 to_light = -glm::normalize(t.scene.light.direction);
    const detail::FrameUniforms u = detail::frame_uniforms(t.scene, kWidth, kHeight, kShadowMap);

    int shadowed = 0, shadowed_darker = 0, clear = 0, clear_changed = 0;
    double drop = 0.0;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            glm::vec3 eye, g;
            if (!ground_point(u.view_projection, x, y, eye, g)) continue;
            if (std::abs(g.x - centre.x) > 1.5F || std::abs(g.z - centre.z) > 1.5F) continue;
            // The ball's silhouette, widened for antialiased edges, hides the ground.
            if (distance_to_segment(centre, eye, g) < 1.15F * radius) continue;
            const float off_axis = distance_to_segment(centre, g, g + 5.0F * to_light);
            if (off_axis > 1.4F * radius) {
                // Clear of the shadow and of its soft edge: the same bytes with the ball or without.
                ++clear;
                for (int k = 0; k < 3; ++k)
                    if (std::abs(with_ball.pixel(x, y)[k] - without_ball.pixel(x, y)[k]) > 2) {
                        ++clear_changed;
                        break;
                    }
            } else if (off_axis < 0.8F * radius && !hits_cloth(t, eye, g)) {
                // In the ball's shadow and in view; not in or near the sheet's shadow (PCF blurs
                // its edge), where the ball's makes no difference.
                bool sheet_shadow = false;
                for (const glm::vec2 jitter : {glm::vec2(0.0F), glm::vec2(0.04F, 0.0F), glm::vec2(-0.04F, 0.0F),
                                               glm::vec2(0.0F, 0.04F), glm::vec2(0.0F, -0.04F)}) {
                    const glm::vec3 q = g + glm::vec3(jitter.x, 0.0F, jitter.y);
                    sheet_shadow = sheet_shadow || hits_cloth(t, q, q + 5.0F * to_light);
                }
                if (sheet_shadow) continue;
                ++shadowed;
                drop += luminance(without_ball, x, y) - luminance(with_ball, x, y);
                if (luminance(with_ball, x, y) < 0.8 * luminance(without_ball, x, y)) ++shadowed_darker;
            }
        }
    std::printf(
        "shadow: %d ground pixels in the ball's shadow, %d darker by 20 %% or more (mean drop %.1f levels); "
        "%d ground pixels outside it, %d changed\n",
        shadowed, shadowed_darker, shadowed > 0 ? drop / shadowed : 0.0, clear, clear_changed);
    ASSERT_GT(shadowed, 30) << "the test's geometry left no ground in the ball's shadow in view";
    ASSERT_GT(clear, 2000);
    EXPECT_GE(shadowed_darker, shadowed * 95 / 100) << "the ball's shadow is missing or misplaced";
    EXPECT_EQ(clear_changed, 0) << "the ball changed ground away from its shadow";
    EXPECT_EQ(c.renderer->validation_messages(), 0);
}

TEST(VulkanRenderer, MultisamplingSmoothsEdgesOnly) {
    const Created c1 = create(small_options(1));
    if (!c1.renderer) GTEST_SKIP() << c1.skip;
    const Created c4 = create(small_options(4));
    ASSERT_TRUE(c4.renderer) << c4.skip;
    const test::TestScene t = test::sheet_over_ball();
    c1.renderer->load(t.scene);
    c4.renderer->load(t.scene);
    const Image aliased = c1.renderer->draw(t.frame);
    const Image smooth = c4.renderer->draw(t.frame);
    save(aliased, "msaa_1");
    save(smooth, "msaa_4");
    const ImageDifference d = compare(aliased, smooth);
    std::printf("msaa 1 vs 4: mean %.3f, max %d, %.2f %% of pixels over 16\n", d.mean, d.max, 100.0 * d.fraction_over);
    EXPECT_GT(d.max, 16) << "4× MSAA changes no edge";
    EXPECT_GT(d.fraction_over, 0.002);
    EXPECT_LT(d.mean, 2.0) << "4× MSAA changes more than edges";
    EXPECT_LT(d.fraction_over, 0.08);
    EXPECT_EQ(c1.renderer->validation_messages(), 0);
    EXPECT_EQ(c4.renderer->validation_messages(), 0);
}

TEST(VulkanRenderer, RedrawsTheSameFrameBitForBitAndCountsUploads) {
    const Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    Renderer& r = *c.renderer;
    EXPECT_THROW((void)r.draw(RenderFrame{}), Error) << "draw() before load()";
    const test::TestScene t = test::sheet_over_ball();
    r.load(t.scene);
    const std::uint64_t bytes = std::uint64_t{t.scene.cloth_vertices} * sizeof(RenderVertex);
    const Image a = r.draw(t.frame);
    const Image b = r.draw(t.frame);
    EXPECT_EQ(a.rgba, b.rgba);
    EXPECT_EQ(r.transfer().bytes_uploaded, bytes);

    // Each frame's vertices are uploaded: the sheet lifted by 20 cm draws differently.
    std::vector<RenderVertex> lifted = t.vertices;
    for (RenderVertex& v : lifted) v.position[1] += 0.2F;
    RenderFrame moved = t.frame;
    moved.cloth = lifted;
    const Image m = r.draw(moved);
    EXPECT_GT(compare(a, m).fraction_over, 0.01) << "the second frame's vertices were not uploaded";

    // No cloth in the frame: the buffer keeps what the last frame put there, nothing is uploaded.
    RenderFrame device_filled = t.frame;
    device_filled.cloth = {};
    const Image d = r.draw(device_filled);
    EXPECT_EQ(r.transfer().path, "host upload");
    EXPECT_EQ(r.transfer().bytes_uploaded, 0U);
    EXPECT_EQ(d.rgba, m.rgba);

    RenderFrame short_frame = t.frame;
    short_frame.cloth = short_frame.cloth.first(short_frame.cloth.size() - 1);
    EXPECT_THROW((void)r.draw(short_frame), Error);
    EXPECT_EQ(r.draw(t.frame).rgba, a.rgba) << "a rejected frame left the renderer in another state";
    EXPECT_EQ(r.validation_messages(), 0);
}

// Not a check of speed (lavapipe's depends on the machine): the draw time per frame, median of 11,
// for the record, at the test size and at 720p with the default options.
// The zero-copy export: on a device that can export memory and timeline semaphores (an NVIDIA GPU)
// it hands out fds and draws "interop" frames ordered by the timeline; on one that cannot (lavapipe
// has no exportable semaphores) it says why, and the host upload keeps working. The GPU side (CUDA
// writing into the buffer) is tests/gpu/test_render_interop.cpp.
TEST(VulkanRenderer, ExportsTheClothBufferOrSaysWhyNot) {
    const Created c = create(small_options());
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
        const std::vector<RenderVertex> back = r.read_cloth();
        ASSERT_EQ(back.size(), t.vertices.size());
        EXPECT_EQ(std::memcmp(back.data(), t.vertices.data(), back.size() * sizeof(RenderVertex)), 0)
            << "the buffer holds what was uploaded";
        return;
    }
    EXPECT_GE(link->memory.fd, 0);
    EXPECT_GE(link->timeline.fd, 0);
    EXPECT_EQ(link->memory.size, std::uint64_t{t.scene.cloth_vertices} * sizeof(RenderVertex));
    EXPECT_GE(link->memory.allocation_size, link->memory.size);
    (void)r.draw(timed);  // nothing waits: value 1 is signalled after the frame
    EXPECT_EQ(r.transfer().path, "interop");
    EXPECT_EQ(r.transfer().bytes_uploaded, 0U);
    EXPECT_THROW((void)r.draw(timed), Error) << "timeline values must increase";
    ::close(link->memory.fd);
    ::close(link->timeline.fd);
    EXPECT_EQ(r.validation_messages(), 0);
}

TEST(VulkanRenderer, ReportsDrawTime) {
    for (const auto& [w, h] : {std::pair{320, 240}, std::pair{1280, 720}}) {
        RendererOptions o;
        o.width = w;
        o.height = h;
        const Created c = create(o);
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
        save(last, "sheet_over_ball_" + std::to_string(w) + "x" + std::to_string(h));
    }
}

}  // namespace
}  // namespace weft::render
