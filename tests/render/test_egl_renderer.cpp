// The EGL + OpenGL 4.5 capture renderer on whatever EGL gives here (llvmpipe in CI, the GPU on a
// GPU host): the picture is there and upright, cloth is two-sided, the ball casts its shadow where
// the light puts it, MSAA only touches edges, frames are reproducible, and renderers coexist.
// Every test skips, saying why, where no EGL display gives an OpenGL 4.5 core context.
// With WEFT_TEST_IMAGES=<folder> in the environment the pictures are written there as PNG files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "frame_uniforms.h"
#include "render_test_scenes.h"
#include "weft/error.h"
#include "weft/render/image.h"
#include "weft/render/renderer.h"

namespace weft::render {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;

RendererOptions small_options(bool validation = false) {
    RendererOptions o;
    o.width = kWidth;
    o.height = kHeight;
    o.samples = 4;
    o.shadow_map_size = 1024;
    o.validation = validation;
    return o;
}

/// The renderer, or why there is none here: a missing EGL display or OpenGL 4.5 context (or debug
/// context) is the machine's, a reason to skip; any other error is the renderer's and fails.
struct Created {
    std::unique_ptr<Renderer> renderer;
    std::string skip;
};

Created create(const RendererOptions& options) {
    try {
        return {create_renderer("egl", options), {}};
    } catch (const Error& e) {
        const std::string what = e.what();
        if (what.find("no EGL display") != std::string::npos || what.find("no debug context") != std::string::npos)
            return {nullptr, "EGL renderer unavailable: " + what};
        throw;
    }
}

void save(const Image& image, const std::string& name) {
    const char* folder = std::getenv("WEFT_TEST_IMAGES");
    if (folder == nullptr || *folder == '\0') return;
    std::filesystem::create_directories(folder);
    write_png(std::filesystem::path(folder) / ("egl_" + name + ".png"), image);
}

double luminance(const Image& im, int x, int y) {
    const std::uint8_t* p = im.pixel(x, y);
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

/// Where world point `p` lands in the image: column, row (rows top to bottom).
glm::vec2 project(const glm::mat4& view_projection, glm::vec3 p, int width, int height) {
    const glm::vec4 c = view_projection * glm::vec4(p, 1.0F);
    const glm::vec2 ndc(c.x / c.w, c.y / c.w);
    return {(ndc.x + 1.0F) * 0.5F * static_cast<float>(width), (1.0F - ndc.y) * 0.5F * static_cast<float>(height)};
}

/// The camera ray through the centre of pixel (x, y): origin and unit direction.
struct Ray {
    glm::vec3 origin;
    glm::vec3 direction;
};
Ray pixel_ray(const glm::mat4& view_projection, int x, int y, int width, int height) {
    const glm::mat4 inverse = glm::inverse(view_projection);
    const float nx = (static_cast<float>(x) + 0.5F) / static_cast<float>(width) * 2.0F - 1.0F;
    const float ny = 1.0F - (static_cast<float>(y) + 0.5F) / static_cast<float>(height) * 2.0F;
    const glm::vec4 near = inverse * glm::vec4(nx, ny, 0.0F, 1.0F);  // clip depth 0..1
    const glm::vec4 far = inverse * glm::vec4(nx, ny, 1.0F, 1.0F);
    const glm::vec3 a = glm::vec3(near) / near.w;
    const glm::vec3 b = glm::vec3(far) / far.w;
    return {a, glm::normalize(b - a)};
}

/// Distance from `point` to the line through `origin` along unit `direction`.
float distance_to_line(glm::vec3 point, glm::vec3 origin, glm::vec3 direction) {
    const glm::vec3 v = point - origin;
    return glm::length(v - direction * glm::dot(v, direction));
}

/// Mean colour of the (2r+1)² pixels around (x, y), normalised to r + g + b = 1 (chromaticity).
glm::vec3 chromaticity(const Image& im, int x, int y, int r) {
    glm::vec3 sum(0.0F);
    for (int j = y - r; j <= y + r; ++j)
        for (int i = x - r; i <= x + r; ++i) {
            const std::uint8_t* p = im.pixel(i, j);
            sum += glm::vec3(p[0], p[1], p[2]);
        }
    return sum / (sum.r + sum.g + sum.b);
}

/// A linear colour as the renderer writes it (sRGB-encoded), normalised to r + g + b = 1.
glm::vec3 srgb_chromaticity(glm::vec3 linear) {
    glm::vec3 c;
    for (int k = 0; k < 3; ++k)
        c[k] = linear[k] <= 0.0031308F ? linear[k] * 12.92F : 1.055F * std::pow(linear[k], 1.0F / 2.4F) - 0.055F;
    return c / (c.r + c.g + c.b);
}

std::size_t collider_index(const RenderScene& scene, const std::string& name) {
    for (std::size_t k = 0; k < scene.colliders.size(); ++k)
        if (scene.colliders[k].name == name) return k;
    ADD_FAILURE() << "no collider " << name;
    return 0;
}

TEST(EglRenderer, DrawsSheetOverBallWithoutDebugMessages) {
    const Created c = create(small_options(true));
    if (!c.renderer) GTEST_SKIP() << c.skip;
    Renderer& r = *c.renderer;
    EXPECT_EQ(r.name(), "egl");
    const std::string device = r.device_description();
    EXPECT_NE(device.find(", OpenGL "), std::string::npos) << device;
    EXPECT_NE(device.find("(EGL "), std::string::npos) << device;
    std::printf("egl renderer: %s\n", device.c_str());

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

    // Upright: the top row is sky (the clear colour, sRGB-encoded), the bottom row ground.
    const glm::vec3 sky = srgb_chromaticity(t.scene.background);  // normalised; compare the bytes too
    const std::uint8_t* top = image.pixel(kWidth / 2, 0);
    for (int k = 0; k < 3; ++k) {
        const float linear = t.scene.background[k];
        const float encoded = linear <= 0.0031308F ? linear * 12.92F : 1.055F * std::pow(linear, 1.0F / 2.4F) - 0.055F;
        EXPECT_NEAR(top[k], encoded * 255.0F, 1.0F) << "channel " << k;
    }
    EXPECT_GT(glm::length(chromaticity(image, kWidth / 2, kHeight - 3, 2) - sky), 0.01F)
        << "the bottom rows show the sky colour: the image is upside down or the ground is missing";
}

TEST(EglRenderer, ShowsTheSideOfTheClothThatFacesTheCamera) {
    const Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    for (const bool show_back : {false, true}) {
        const test::TestScene t = test::sheet_over_ball(show_back);
        c.renderer->load(t.scene);
        const Image image = c.renderer->draw(t.frame);
        save(image, show_back ? "sheet_back" : "sheet_front");
        // The sheet's centre (mean of its vertices), projected as the renderer projects it.
        glm::vec3 centre(0.0F);
        for (const RenderVertex& v : t.vertices) centre += glm::vec3(v.position[0], v.position[1], v.position[2]);
        centre /= static_cast<float>(t.vertices.size());
        const detail::FrameUniforms u = detail::frame_uniforms(t.scene, kWidth, kHeight, 1024);
        const glm::vec2 p = project(u.view_projection, centre, kWidth, kHeight);
        const int x = static_cast<int>(p.x);
        const int y = static_cast<int>(p.y);
        ASSERT_TRUE(x >= 2 && x < kWidth - 2 && y >= 2 && y < kHeight - 2) << p.x << ", " << p.y;
        const glm::vec3 seen = chromaticity(image, x, y, 2);
        const float to_front = glm::length(seen - srgb_chromaticity(t.scene.cloths[0].front_colour));
        const float to_back = glm::length(seen - srgb_chromaticity(t.scene.cloths[0].back_colour));
        if (show_back)
            EXPECT_LT(to_back, to_front) << "the turned-over sheet shows its front colour at (" << x << ", " << y << ")";
        else
            EXPECT_LT(to_front, to_back) << "the sheet shows its back colour at (" << x << ", " << y << ")";
    }
}

TEST(EglRenderer, BallShadowsTheGroundWhereTheLightPutsIt) {
    const Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    const test::TestScene t = test::sheet_over_ball();
    c.renderer->load(t.scene);
    const Image with_ball = c.renderer->draw(t.frame);
    const std::size_t ball = collider_index(t.scene, "ball");
    RenderFrame away = t.frame;
    away.collider_models[ball] = glm::translate(glm::mat4(1.0F), glm::vec3(100.0F, 0.0F, 0.0F)) * away.collider_models[ball];
    const Image without_ball = c.renderer->draw(away);
    save(with_ball, "shadow_with_ball");
    save(without_ball, "shadow_ball_away");

    const glm::vec3 centre(t.frame.collider_models[ball][3]);
    float radius = 0.0F;
    for (const RenderVertex& v : t.scene.colliders[ball].mesh.vertices)
        radius = std::max(radius, glm::length(glm::vec3(v.position[0], v.position[1], v.position[2])));
    const glm::vec3 light = glm::normalize(t.scene.light.direction);
    const detail::FrameUniforms u = detail::frame_uniforms(t.scene, kWidth, kHeight, 1024);

    // Ground pixels within 1 m of the ball's footprint where the ball itself is not in view (its
    // silhouette widened for antialiased edges): moving the ball away may only brighten them, and
    // must brighten those in its shadow, the ground points whose way to the light passes the ball.
    int region = 0, darker = 0, darker_in_shadow = 0, brighter = 0;
    double drop = 0.0;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            const Ray ray = pixel_ray(u.view_projection, x, y, kWidth, kHeight);
            if (ray.direction.y >= 0.0F) continue;
            const glm::vec3 ground = ray.origin + ray.direction * (-ray.origin.y / ray.direction.y);
            if (glm::length(glm::vec2(ground.x - centre.x, ground.z - centre.z)) > 1.0F) continue;
            if (distance_to_line(centre, ray.origin, ray.direction) < radius * 1.1F) continue;
            ++region;
            const double difference = luminance(without_ball, x, y) - luminance(with_ball, x, y);
            if (difference < -3.0) ++brighter;
            if (difference > 12.0) {
                ++darker;
                drop += difference;
                // Within the shadow, widened by the PCF kernel and the normal offset.
                if (distance_to_line(centre, ground, -light) < radius * 1.25F) ++darker_in_shadow;
            }
        }
    std::printf("shadow: %d ground pixels, %d darker (mean %.1f levels), %d of them in the ball's shadow, %d brighter\n",
                region, darker, darker > 0 ? drop / darker : 0.0, darker_in_shadow, brighter);
    ASSERT_GT(region, 2000);
    EXPECT_GT(darker, 150) << "the ball casts no shadow";
    EXPECT_GE(darker_in_shadow, darker * 95 / 100) << "darkened ground away from where the ball's shadow falls";
    EXPECT_GT(darker > 0 ? drop / darker : 0.0, 25.0) << "the shadow is faint";
    EXPECT_LE(brighter, 2) << "the ball brightens the ground";
}

TEST(EglRenderer, MultisamplingSmoothsEdgesOnly) {
    RendererOptions single = small_options();
    single.samples = 1;
    const Created c1 = create(single);
    if (!c1.renderer) GTEST_SKIP() << c1.skip;
    const Created c4 = create(small_options());
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
    EXPECT_GT(d.fraction_over, 0.001) << "4× MSAA changes almost no edge";
    EXPECT_LT(d.mean, 2.0) << "4× MSAA changes more than edges";
    EXPECT_LT(d.fraction_over, 0.08);
}

TEST(EglRenderer, RedrawsTheSameFrameBitForBit) {
    const Created c = create(small_options());
    if (!c.renderer) GTEST_SKIP() << c.skip;
    Renderer& r = *c.renderer;
    EXPECT_THROW((void)r.draw(RenderFrame{}), Error) << "draw() before load()";
    const test::TestScene t = test::sheet_over_ball();
    r.load(t.scene);
    const Image a = r.draw(t.frame);
    const Image b = r.draw(t.frame);
    EXPECT_EQ(a.rgba, b.rgba);

    // No cloth in the frame: the buffer keeps what the last frame put there, nothing is uploaded.
    RenderFrame device_filled = t.frame;
    device_filled.cloth = {};
    const Image d = r.draw(device_filled);
    EXPECT_EQ(r.transfer().bytes_uploaded, 0U);
    EXPECT_EQ(r.transfer().path, "host upload");
    EXPECT_EQ(a.rgba, d.rgba);

    RenderFrame short_frame = t.frame;
    short_frame.cloth = short_frame.cloth.first(short_frame.cloth.size() - 1);
    EXPECT_THROW((void)r.draw(short_frame), Error);
}

TEST(EglRenderer, SeveralRenderersLiveSideBySide) {
    Created first = create(small_options());
    if (!first.renderer) GTEST_SKIP() << first.skip;
    Created second = create(small_options());
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
    const Created third = create(small_options());
    ASSERT_TRUE(third.renderer) << third.skip;
    third.renderer->load(t.scene);
    EXPECT_EQ(third.renderer->draw(t.frame).rgba, a.rgba);
}

}  // namespace
}  // namespace weft::render
