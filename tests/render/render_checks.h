#pragma once
// What the Vulkan and the EGL renderer tests check the same way, on the scene of
// render_test_scenes.h: helpers that read pictures and the scene's geometry, and the checks
// themselves, each taking the renderer under test. The test files keep how they create their
// renderer (and when they skip) and what only their renderer has.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "weft/error.h"
#include "weft/render/image.h"
#include "weft/render/renderer.h"

#include "frame_uniforms.h"
#include "render_test_scenes.h"

namespace weft::render::test {

// ---------------------------------------------------------------------------------------------
// Renderers at the test size

/// The size of the test pictures: small enough for a software rasteriser, large enough that the
/// ball's shadow covers dozens of ground pixels.
inline constexpr int kWidth = 320;
inline constexpr int kHeight = 240;
inline constexpr int kShadowMap = 1024;

/// Options for a kWidth×kHeight picture with `samples` MSAA samples and a kShadowMap² shadow map;
/// `validation` turns on the Vulkan layer or the GL debug context and its message count.
inline RendererOptions small_options(int samples = 4, bool validation = false) {
    RendererOptions o;
    o.width = kWidth;
    o.height = kHeight;
    o.samples = samples;
    o.shadow_map_size = kShadowMap;
    o.validation = validation;
    return o;
}

/// The renderer, or why this machine has none (a reason to skip, not a failure).
struct Created {
    std::unique_ptr<Renderer> renderer;
    std::string skip;
};

/// Creates the renderer `name`. An error for which `machine_lacks` gives a reason is the machine's
/// (no device, no display, no validation layer): the reason comes back, to skip on. Any other
/// error is the renderer's own and propagates, failing the test.
inline Created create(std::string_view name, const RendererOptions& options,
                      std::string (*machine_lacks)(const Error&)) {
    try {
        return {create_renderer(name, options), {}};
    } catch (const Error& e) {
        std::string why = machine_lacks(e);
        if (why.empty()) throw;
        return {nullptr, std::move(why)};
    }
}

/// With WEFT_TEST_IMAGES=<folder> in the environment, writes `image` there as
/// `<renderer>_<name>.png` (the renderer's name as prefix, so the Vulkan and the EGL pictures of
/// one check lie side by side); without it, does nothing.
inline void save(std::string_view renderer, const std::string& name, const Image& image) {
    const char* folder = std::getenv("WEFT_TEST_IMAGES");
    if (folder == nullptr || *folder == '\0') return;
    std::filesystem::create_directories(folder);
    write_png(std::filesystem::path(folder) / (std::string(renderer) + "_" + name + ".png"), image);
}

// ---------------------------------------------------------------------------------------------
// Reading pictures

/// Luminance (Rec. 709 weights, 0–255) of pixel (x, y), sRGB-encoded as read back: what "darker"
/// and "brighter" mean in the shadow check.
inline double luminance(const Image& image, int x, int y) {
    const std::uint8_t* p = image.pixel(x, y);
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

/// Mean colour of the (2r+1)² pixels around (x, y) with r + g + b = 1: the hue and saturation,
/// whatever the lighting's brightness, so that a lit and a shaded patch of one colour compare equal.
inline glm::vec3 chromaticity(const Image& image, int x, int y, int r) {
    glm::vec3 sum(0.0F);
    for (int j = y - r; j <= y + r; ++j)
        for (int i = x - r; i <= x + r; ++i) {
            const std::uint8_t* p = image.pixel(i, j);
            sum += glm::vec3(p[0], p[1], p[2]);
        }
    return sum / (sum.r + sum.g + sum.b);
}

/// A linear channel value (clamped to 0..1) as the renderers write it: sRGB-encoded, 0..1.
inline float encode_srgb(float linear) {
    linear = std::clamp(linear, 0.0F, 1.0F);
    return linear <= 0.0031308F ? linear * 12.92F : 1.055F * std::pow(linear, 1.0F / 2.4F) - 0.055F;
}

/// The chromaticity (r + g + b = 1) that a linear colour of the scene has in the picture, after sRGB
/// encoding: what `chromaticity` of a patch of that colour comes near.
inline glm::vec3 srgb_chromaticity(glm::vec3 linear) {
    const glm::vec3 c(encode_srgb(linear.r), encode_srgb(linear.g), encode_srgb(linear.b));
    return c / (c.r + c.g + c.b);
}

// ---------------------------------------------------------------------------------------------
// The scene's geometry, as the renderers project it

/// The camera matrix the renderers draw a `width`×`height` picture of `scene` with (the same code
/// as theirs, render/src/frame_uniforms.h): the tests find things in the picture where the
/// renderer puts them, not where a second camera model would.
inline glm::mat4 view_projection(const RenderScene& scene, int width, int height) {
    return detail::frame_uniforms(scene, width, height, kShadowMap).view_projection;
}

/// Where world point `p` lands in a `width`×`height` picture: column, row (rows top to bottom,
/// while clip y points up).
inline glm::vec2 project(const glm::mat4& view_projection, glm::vec3 p, int width, int height) {
    const glm::vec4 c = view_projection * glm::vec4(p, 1.0F);
    return {(c.x / c.w + 1.0F) * 0.5F * static_cast<float>(width),
            (1.0F - c.y / c.w) * 0.5F * static_cast<float>(height)};
}

/// The camera ray through the centre of a pixel, and the ground point (y = 0) it meets.
struct GroundRay {
    glm::vec3 eye;        ///< on the near plane
    glm::vec3 direction;  ///< unit, away from the camera
    glm::vec3 ground;     ///< where the ray meets y = 0
};

/// The ray through the centre of pixel (x, y) of a `width`×`height` picture, onto the ground
/// plane; nullopt for pixels at or above the horizon, whose ray never meets it.
inline std::optional<GroundRay> ground_ray(const glm::mat4& view_projection, int x, int y, int width, int height) {
    const glm::mat4 inverse = glm::inverse(view_projection);
    const glm::vec2 ndc((static_cast<float>(x) + 0.5F) / static_cast<float>(width) * 2.0F - 1.0F,
                        1.0F - (static_cast<float>(y) + 0.5F) / static_cast<float>(height) * 2.0F);
    const glm::vec4 n = inverse * glm::vec4(ndc, 0.0F, 1.0F);  // clip depth 0..1
    const glm::vec4 f = inverse * glm::vec4(ndc, 1.0F, 1.0F);
    const glm::vec3 eye = glm::vec3(n) / n.w;
    const glm::vec3 d = glm::vec3(f) / f.w - eye;
    if (d.y >= 0.0F) return std::nullopt;
    return GroundRay{eye, glm::normalize(d), eye + d * (-eye.y / d.y)};
}

/// Distance from `p` to the segment from `a` to `b`: whether `p` lies near a way from one point to
/// another (from the eye to a ground point, from a ground point to the light).
inline float distance_to_segment(glm::vec3 p, glm::vec3 a, glm::vec3 b) {
    const glm::vec3 ab = b - a;
    const float s = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0F, 1.0F);
    return glm::length(p - (a + s * ab));
}

/// Distance from `point` to the whole line through `origin` along unit `direction`.
inline float distance_to_line(glm::vec3 point, glm::vec3 origin, glm::vec3 direction) {
    const glm::vec3 v = point - origin;
    return glm::length(v - direction * glm::dot(v, direction));
}

/// Whether the segment from `a` to `b` crosses a cloth triangle of `t` (Möller–Trumbore): whether
/// the sheet hides a ground point from the eye, or from the light.
inline bool hits_cloth(const TestScene& t, glm::vec3 a, glm::vec3 b) {
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

/// Index of the collider called `name` in `scene` (a failure, and 0, when there is none): frames
/// hold collider models by index.
inline std::size_t collider_index(const RenderScene& scene, const std::string& name) {
    for (std::size_t k = 0; k < scene.colliders.size(); ++k)
        if (scene.colliders[k].name == name) return k;
    ADD_FAILURE() << "no collider " << name;
    return 0;
}

// ---------------------------------------------------------------------------------------------
// Checks of a renderer

/// Whether `image` of `scene` is upright (a renderer that forgets the Vulkan viewport flip or
/// GL's bottom-up read-back draws it upside down): the top row is the clear colour, sRGB-encoded
/// and opaque, at both corners and the middle; the bottom rows are ground, not sky.
inline void expect_upright(const Image& image, const RenderScene& scene) {
    for (const int x : {0, image.width / 2, image.width - 1}) {
        const std::uint8_t* top = image.pixel(x, 0);
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(top[k], encode_srgb(scene.background[k]) * 255.0F, 1.0F)
                << "pixel (" << x << ", 0), channel " << k;
        EXPECT_EQ(top[3], 255) << "pixel (" << x << ", 0) is not opaque";
    }
    EXPECT_GT(
        glm::length(chromaticity(image, image.width / 2, image.height - 3, 2) - srgb_chromaticity(scene.background)),
        0.01F)
        << "the bottom rows show the sky: the picture is upside down or the ground is missing";
}

/// `r` (made with small_options) draws sheet_over_ball: a kWidth×kHeight picture that is not
/// blank and is upright, without validation or debug messages, the cloth's vertices uploaded from
/// the host, all of them.
inline void expect_draws_sheet_over_ball(Renderer& r) {
    const TestScene t = sheet_over_ball();
    r.load(t.scene);
    const Image image = r.draw(t.frame);
    save(r.name(), "sheet_over_ball", image);
    ASSERT_EQ(image.width, kWidth);
    ASSERT_EQ(image.height, kHeight);
    EXPECT_GT(luminance_spread(image), 10.0);
    EXPECT_EQ(r.validation_messages(), 0);
    EXPECT_EQ(r.transfer().path, "host upload");
    EXPECT_EQ(r.transfer().bytes_uploaded, std::uint64_t{t.scene.cloth_vertices} * sizeof(RenderVertex));
    expect_upright(image, t.scene);
}

/// Cloth is two-sided (front and back colour chosen by facing, not by winding alone): at the
/// sheet's centre, projected as the renderer projects it, the picture has the hue of the side that
/// faces the camera, for the sheet as it is and turned over.
inline void expect_shows_the_side_facing_the_camera(Renderer& r) {
    for (const bool show_back : {false, true}) {
        const TestScene t = sheet_over_ball(show_back);
        r.load(t.scene);
        const Image image = r.draw(t.frame);
        save(r.name(), show_back ? "sheet_back" : "sheet_front", image);
        glm::vec3 centre(0.0F);
        for (const RenderVertex& v : t.vertices) centre += glm::vec3(v.position[0], v.position[1], v.position[2]);
        centre /= static_cast<float>(t.vertices.size());
        const glm::vec2 p =
            project(view_projection(t.scene, image.width, image.height), centre, image.width, image.height);
        const int x = static_cast<int>(p.x), y = static_cast<int>(p.y);
        ASSERT_TRUE(x >= 2 && x < image.width - 2 && y >= 2 && y < image.height - 2) << p.x << ", " << p.y;
        const glm::vec3 seen = chromaticity(image, x, y, 2);
        const float to_front = glm::length(seen - srgb_chromaticity(t.scene.cloths[0].front_colour));
        const float to_back = glm::length(seen - srgb_chromaticity(t.scene.cloths[0].back_colour));
        if (show_back)
            EXPECT_LT(to_back, to_front) << "the turned-over sheet shows its front colour at (" << x << ", " << y
                                         << ")";
        else
            EXPECT_LT(to_front, to_back) << "the sheet shows its back colour at (" << x << ", " << y << ")";
    }
    EXPECT_EQ(r.validation_messages(), 0);
}

/// A character playing a clip is drawn where each frame's vertices put it: sliding_box drawn at
/// t = 0 and at t = 1 (the frame bringing the clip's last pose), the cube's centre at each time
/// shows the cube (darker or of another hue than the ground grid there) in the picture of that
/// time and the ground in the other; a frame without vertices keeps the last ones drawn.
inline void expect_draws_deforming_colliders_where_the_frame_puts_them(Renderer& r) {
    TestScene t = sliding_box();
    ASSERT_EQ(t.scene.deforming_vertices, 8U);
    r.load(t.scene);
    std::vector<RenderVertex> at_start, at_end;
    deforming_collider_vertices(t.scene, t.world->model(), 0.0, at_start);
    deforming_collider_vertices(t.scene, t.world->model(), 1.0, at_end);
    RenderFrame start = t.frame, end = t.frame;
    start.collider_vertices = at_start;
    end.collider_vertices = at_end;
    const Image first = r.draw(start);
    const Image second = r.draw(end);
    RenderFrame keep = t.frame;  // no vertices: the cube stays where `end` put it
    const Image third = r.draw(keep);
    save(r.name(), "sliding_box_start", first);
    save(r.name(), "sliding_box_end", second);
    const glm::mat4 vp = view_projection(t.scene, first.width, first.height);
    const auto pixel = [&](glm::vec3 p) {
        const glm::vec2 q = project(vp, p, first.width, first.height);
        return glm::ivec2(static_cast<int>(q.x), static_cast<int>(q.y));
    };
    const glm::ivec2 left = pixel({-0.5F, 0.2F, 0.2F}), right = pixel({0.5F, 0.2F, 0.2F});  // the front faces' centres
    const auto differs = [](const Image& a, const Image& b, glm::ivec2 at) {
        return std::abs(luminance(a, at.x, at.y) - luminance(b, at.x, at.y)) +
               255.0 * static_cast<double>(glm::length(chromaticity(a, at.x, at.y, 1) - chromaticity(b, at.x, at.y, 1)));
    };
    EXPECT_GT(differs(first, second, left), 10.0) << "the cube's place at t = 0 looks the same at t = 1";
    EXPECT_GT(differs(first, second, right), 10.0) << "the cube's place at t = 1 looks the same at t = 0";
    EXPECT_LT(differs(second, third, left) + differs(second, third, right), 1.0)
        << "a frame without collider vertices moved the cube";
    EXPECT_EQ(r.validation_messages(), 0);
}

/// The ball's shadow falls on the ground where the light puts it, and nowhere else: sheet_over_ball
/// drawn with the ball and with the ball 100 m away (outside the view and the shadow map), compared
/// on the ground around the ball's footprint where the ball itself is not in view (its silhouette
/// widened for antialiased edges). Two views of that ground:
/// - within 1 m of the footprint: moving the ball away may only brighten pixels, must brighten
///   some 150 of them by 12 levels or more (by 25 on average), and those it brightens lie in the
///   ball's shadow (widened by the PCF kernel and the normal offset);
/// - within 1.5 m: every pixel well inside the ball's shadow, in view and clear of the sheet's
///   shadow (where the ball's makes no difference), is at least 20 % darker with the ball, and
///   every pixel clear of the shadow and its soft edge keeps its bytes (within 2 levels).
inline void expect_ball_shadow_where_the_light_puts_it(Renderer& r) {
    const TestScene t = sheet_over_ball();
    r.load(t.scene);
    const Image with_ball = r.draw(t.frame);
    const std::size_t ball = collider_index(t.scene, "ball");
    RenderFrame away = t.frame;
    away.collider_models[ball] =
        glm::translate(glm::mat4(1.0F), glm::vec3(100.0F, 0.0F, 0.0F)) * away.collider_models[ball];
    const Image without_ball = r.draw(away);
    save(r.name(), "shadow_with_ball", with_ball);
    save(r.name(), "shadow_ball_away", without_ball);

    const glm::vec3 centre(t.frame.collider_models[ball][3]);
    float radius = 0.0F;
    for (const RenderVertex& v : t.scene.colliders[ball].mesh.vertices)
        radius = std::max(radius, glm::length(glm::vec3(v.position[0], v.position[1], v.position[2])));
    const glm::vec3 to_light = -glm::normalize(t.scene.light.direction);
    const int width = with_ball.width, height = with_ball.height;
    const glm::mat4 camera = view_projection(t.scene, width, height);

    int region = 0, darker = 0, darker_in_shadow = 0, brighter = 0;  // within 1 m of the footprint
    double darker_drop = 0.0;
    int shadowed = 0, shadowed_darker = 0, clear = 0, clear_changed = 0;  // within 1.5 m
    double shadowed_drop = 0.0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const std::optional<GroundRay> ray = ground_ray(camera, x, y, width, height);
            if (!ray) continue;
            const glm::vec3 g = ray->ground;
            const double difference = luminance(without_ball, x, y) - luminance(with_ball, x, y);

            if (glm::length(glm::vec2(g.x - centre.x, g.z - centre.z)) <= 1.0F &&
                distance_to_line(centre, ray->eye, ray->direction) >= radius * 1.1F) {
                ++region;
                if (difference < -3.0) ++brighter;
                if (difference > 12.0) {
                    ++darker;
                    darker_drop += difference;
                    if (distance_to_line(centre, g, to_light) < radius * 1.25F) ++darker_in_shadow;
                }
            }

            if (std::abs(g.x - centre.x) > 1.5F || std::abs(g.z - centre.z) > 1.5F) continue;
            if (distance_to_segment(centre, ray->eye, g) < 1.15F * radius) continue;
            const float off_axis = distance_to_segment(centre, g, g + 5.0F * to_light);
            if (off_axis > 1.4F * radius) {
                ++clear;
                for (int k = 0; k < 3; ++k)
                    if (std::abs(with_ball.pixel(x, y)[k] - without_ball.pixel(x, y)[k]) > 2) {
                        ++clear_changed;
                        break;
                    }
            } else if (off_axis < 0.8F * radius && !hits_cloth(t, ray->eye, g)) {
                // Not in or near the sheet's shadow (PCF blurs its edge).
                bool sheet_shadow = false;
                for (const glm::vec2 jitter : {glm::vec2(0.0F), glm::vec2(0.04F, 0.0F), glm::vec2(-0.04F, 0.0F),
                                               glm::vec2(0.0F, 0.04F), glm::vec2(0.0F, -0.04F)}) {
                    const glm::vec3 q = g + glm::vec3(jitter.x, 0.0F, jitter.y);
                    sheet_shadow = sheet_shadow || hits_cloth(t, q, q + 5.0F * to_light);
                }
                if (sheet_shadow) continue;
                ++shadowed;
                shadowed_drop += difference;
                if (luminance(with_ball, x, y) < 0.8 * luminance(without_ball, x, y)) ++shadowed_darker;
            }
        }
    std::printf(
        "shadow, within 1 m: %d ground pixels, %d darker (mean %.1f levels), %d of them in the ball's shadow, "
        "%d brighter\n",
        region, darker, darker > 0 ? darker_drop / darker : 0.0, darker_in_shadow, brighter);
    std::printf(
        "shadow, within 1.5 m: %d ground pixels in the ball's shadow, %d darker by 20 %% or more (mean drop "
        "%.1f levels); %d ground pixels outside it, %d changed\n",
        shadowed, shadowed_darker, shadowed > 0 ? shadowed_drop / shadowed : 0.0, clear, clear_changed);
    ASSERT_GT(region, 2000);
    ASSERT_GT(shadowed, 30) << "the test's geometry left no ground in the ball's shadow in view";
    ASSERT_GT(clear, 2000);
    EXPECT_GT(darker, 150) << "the ball casts no shadow";
    EXPECT_GE(darker_in_shadow, darker * 95 / 100) << "darkened ground away from where the ball's shadow falls";
    EXPECT_GT(darker > 0 ? darker_drop / darker : 0.0, 25.0) << "the shadow is faint";
    EXPECT_LE(brighter, 2) << "the ball brightens the ground";
    EXPECT_GE(shadowed_darker, shadowed * 95 / 100) << "the ball's shadow is missing or misplaced";
    EXPECT_EQ(clear_changed, 0) << "the ball changed ground away from its shadow";
    EXPECT_EQ(r.validation_messages(), 0);
}

/// MSAA smooths edges and nothing else: `one_sample` and `four_samples` (small_options with 1 and
/// 4 samples) draw sheet_over_ball; somewhat more than 0.2 % of the pixels differ by more than 16
/// levels (the edges), but under 8 %, and the mean difference stays under 2 levels.
inline void expect_multisampling_smooths_edges_only(Renderer& one_sample, Renderer& four_samples) {
    const TestScene t = sheet_over_ball();
    one_sample.load(t.scene);
    four_samples.load(t.scene);
    const Image aliased = one_sample.draw(t.frame);
    const Image smooth = four_samples.draw(t.frame);
    save(one_sample.name(), "msaa_1", aliased);
    save(four_samples.name(), "msaa_4", smooth);
    const ImageDifference d = compare(aliased, smooth);
    std::printf("msaa 1 vs 4: mean %.3f, max %d, %.2f %% of pixels over 16\n", d.mean, d.max, 100.0 * d.fraction_over);
    EXPECT_GT(d.max, 16) << "4× MSAA changes no edge";
    EXPECT_GT(d.fraction_over, 0.002) << "4× MSAA changes almost no edge";
    EXPECT_LT(d.mean, 2.0) << "4× MSAA changes more than edges";
    EXPECT_LT(d.fraction_over, 0.08);
    EXPECT_EQ(one_sample.validation_messages(), 0);
    EXPECT_EQ(four_samples.validation_messages(), 0);
}

/// Frames are reproducible and each one's cloth reaches the renderer: drawing before load() throws;
/// the same frame draws bit for bit the same, uploading all the cloth's vertices; a frame without
/// cloth vertices uploads nothing and draws what the last frame put in the buffer (the first
/// frame's, then the lifted sheet's); a frame with the sheet lifted 20 cm draws differently; a
/// frame with too few vertices throws and leaves the renderer drawing as before.
inline void expect_redraws_the_same_frame_bit_for_bit(Renderer& r) {
    EXPECT_THROW((void)r.draw(RenderFrame{}), Error) << "draw() before load()";
    const TestScene t = sheet_over_ball();
    r.load(t.scene);
    const std::uint64_t bytes = std::uint64_t{t.scene.cloth_vertices} * sizeof(RenderVertex);
    const Image a = r.draw(t.frame);
    const Image b = r.draw(t.frame);
    EXPECT_EQ(a.rgba, b.rgba);
    EXPECT_EQ(r.transfer().bytes_uploaded, bytes);

    // No cloth in the frame: the buffer keeps what the last frame put there, nothing is uploaded.
    RenderFrame device_filled = t.frame;
    device_filled.cloth = {};
    const Image d = r.draw(device_filled);
    EXPECT_EQ(r.transfer().path, "host upload");
    EXPECT_EQ(r.transfer().bytes_uploaded, 0U);
    EXPECT_EQ(d.rgba, a.rgba);

    // Each frame's vertices are uploaded: the sheet lifted by 20 cm draws differently, and a frame
    // without cloth then draws the lifted sheet.
    std::vector<RenderVertex> lifted = t.vertices;
    for (RenderVertex& v : lifted) v.position[1] += 0.2F;
    RenderFrame moved = t.frame;
    moved.cloth = lifted;
    const Image m = r.draw(moved);
    EXPECT_EQ(r.transfer().bytes_uploaded, bytes);
    EXPECT_GT(compare(a, m).fraction_over, 0.01) << "the second frame's vertices were not uploaded";
    const Image dm = r.draw(device_filled);
    EXPECT_EQ(r.transfer().bytes_uploaded, 0U);
    EXPECT_EQ(dm.rgba, m.rgba);

    RenderFrame short_frame = t.frame;
    short_frame.cloth = short_frame.cloth.first(short_frame.cloth.size() - 1);
    EXPECT_THROW((void)r.draw(short_frame), Error);
    EXPECT_EQ(r.draw(t.frame).rgba, a.rgba) << "a rejected frame left the renderer in another state";
    EXPECT_EQ(r.validation_messages(), 0);
}

/// The sheet over the ball seen with a box between the camera and the sheet's left half (on the line
/// from the camera to the sheet's point (−0.3, 0.9, 0)): what stands in front of the cloth, for the
/// overlay tests.
inline TestScene sheet_over_ball_behind_a_box() {
    TestScene t = sheet_over_ball();
    ColliderDesc box{.name = "screen", .shape = ColliderShape::Box};
    box.half_extents = {0.12, 0.12, 0.04};
    box.motion.origin = {-0.2, 1.14, 0.9};
    t.world->add_collider(box);
    make_sheet_over_ball_view(t);
    return t;
}

/// The on-screen bounds (pixels, low and high corners) of sheet_over_ball_behind_a_box's box.
inline std::pair<glm::vec2, glm::vec2> screen_box_outline(const glm::mat4& vp, int width, int height) {
    glm::vec2 lo(1e9F), hi(-1e9F);
    for (int k = 0; k < 8; ++k) {
        const glm::vec3 corner(-0.2F + ((k & 1) ? 0.12F : -0.12F), 1.14F + ((k & 2) ? 0.12F : -0.12F),
                               0.9F + ((k & 4) ? 0.04F : -0.04F));
        const glm::vec2 q = project(vp, corner, width, height);
        lo = glm::min(lo, q);
        hi = glm::max(hi, q);
    }
    return {lo, hi};
}

/// The overlay points (OverlayLines::points, the editor's contact and pin marks): squares at the
/// listed cloth vertices, read from the cloth buffer, hidden where something is in front. The sheet
/// over the ball behind the box of the lines' test, every fourth vertex marked in magenta: marks
/// change pixels near the listed vertices only (none near an unlisted vertex that no listed one is
/// near), none inside the box's outline; the mark's colour is drawn; no points draws the picture
/// without them; a point past the cloth buffer and too many lists are errors naming the renderer.
inline void expect_overlay_points_at_the_listed_vertices_where_seen(Renderer& r) {
    TestScene t = sheet_over_ball_behind_a_box();
    r.load(t.scene);
    const Image plain = r.draw(t.frame);
    RenderFrame marked = t.frame;
    OverlayPoints list;
    list.colour = {1.0F, 0.0F, 1.0F};
    for (std::uint32_t v = 0; v < t.scene.cloth_vertices; v += 4) list.vertices.push_back(v);
    marked.lines.points.push_back(list);
    marked.lines.point_size = 5.0F;
    const Image points = r.draw(marked);
    save(r.name(), "overlay_points", points);

    const glm::mat4 vp = view_projection(t.scene, plain.width, plain.height);
    const auto [box_lo, box_hi] = screen_box_outline(vp, plain.width, plain.height);
    std::vector<glm::vec2> listed;
    for (const std::uint32_t v : list.vertices) {
        const RenderVertex& rv = t.vertices[v];
        listed.push_back(project(vp, glm::vec3(rv.position[0], rv.position[1], rv.position[2]), plain.width, plain.height));
    }
    int changed = 0, in_box = 0, away = 0, magenta = 0;
    for (int y = 0; y < plain.height; ++y)
        for (int x = 0; x < plain.width; ++x) {
            bool differs = false;
            for (int c = 0; c < 3; ++c) differs = differs || std::abs(int{plain.pixel(x, y)[c]} - int{points.pixel(x, y)[c]}) > 24;
            if (!differs) continue;
            ++changed;
            const glm::vec2 q(static_cast<float>(x) + 0.5F, static_cast<float>(y) + 0.5F);
            if (q.x > box_lo.x + 2.0F && q.x < box_hi.x - 2.0F && q.y > box_lo.y + 2.0F && q.y < box_hi.y - 2.0F) ++in_box;
            float nearest = 1e9F;
            for (const glm::vec2& p : listed) nearest = std::min(nearest, glm::length(p - q));
            if (nearest > 5.0F) ++away;  // a 5-pixel square reaches 3.5 pixels from its centre, plus antialiasing
            const auto* px = points.pixel(x, y);
            if (px[0] > 200 && px[1] < 60 && px[2] > 200) ++magenta;
        }
    std::printf("%s overlay points: %zu listed, %d pixels changed, %d magenta, %d inside the box, %d away from a listed vertex\n",
                std::string(r.name()).c_str(), list.vertices.size(), changed, magenta, in_box, away);
    ASSERT_GT(box_hi.x - box_lo.x, 8.0F) << "the box is too small on screen to test hiding";
    EXPECT_GT(changed, 300) << "the points were not drawn";
    EXPECT_GT(magenta, 100) << "the points are not the list's colour";
    EXPECT_EQ(in_box, 0) << "points drawn through the box in front of the sheet (no depth test)";
    EXPECT_EQ(away, 0) << "points away from the listed vertices";
    EXPECT_EQ(r.draw(t.frame).rgba, plain.rgba) << "no points must draw the picture without them";

    RenderFrame past = t.frame;
    past.lines.points.push_back({{t.scene.cloth_vertices}, {1.0F, 0.0F, 0.0F}});
    try {
        (void)r.draw(past);
        ADD_FAILURE() << "a point past the cloth buffer was drawn";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("overlay point at cloth vertex"), std::string::npos) << e.what();
    }
    RenderFrame many = t.frame;
    many.lines.points.assign(kMaxOverlayPointLists + 1, OverlayPoints{{0}, {1.0F, 0.0F, 0.0F}});
    EXPECT_THROW((void)r.draw(many), Error);
    EXPECT_EQ(r.draw(t.frame).rgba, plain.rgba) << "a rejected frame left the renderer in another state";
    EXPECT_EQ(r.validation_messages(), 0);
}

/// The overlay lines (RenderFrame::lines): the wireframe and the normals are drawn from the cloth
/// buffer, over the cloth where nothing is in front of it and hidden where something is. The sheet
/// over the ball with a box between the camera and the sheet's left half: lines change many pixels
/// of the sheet, none inside the box's outline on screen, none outside the cloth's (and its
/// normals') projected bounds; the normals add pixels the wireframe does not; lines off draws the
/// same picture as before.
inline void expect_overlay_lines_over_the_cloth_only_where_seen(Renderer& r) {
    TestScene t = sheet_over_ball_behind_a_box();
    ASSERT_EQ(t.scene.cloth_edges.size(), 2U * (16U * 17U * 2U + 16U * 16U));  // grid edges and one diagonal a cell
    r.load(t.scene);
    const Image plain = r.draw(t.frame);
    RenderFrame wire_frame = t.frame;
    wire_frame.lines.wireframe = true;
    const Image wire = r.draw(wire_frame);
    RenderFrame normal_frame = t.frame;
    normal_frame.lines.normal_length = 0.08F;
    const Image normals = r.draw(normal_frame);
    save(r.name(), "overlay_plain", plain);
    save(r.name(), "overlay_wireframe", wire);
    save(r.name(), "overlay_normals", normals);

    const glm::mat4 vp = view_projection(t.scene, plain.width, plain.height);
    const auto [box_lo, box_hi] = screen_box_outline(vp, plain.width, plain.height);
    // The cloth's bounds on screen, grown by the normals' length and two pixels.
    glm::vec2 cloth_lo(1e9F), cloth_hi(-1e9F);
    for (const RenderVertex& v : t.vertices)
        for (const float along : {0.0F, 0.08F}) {
            const glm::vec3 p = glm::vec3(v.position[0], v.position[1], v.position[2]) +
                                along * glm::vec3(v.normal[0], v.normal[1], v.normal[2]);
            const glm::vec2 q = project(vp, p, plain.width, plain.height);
            cloth_lo = glm::min(cloth_lo, q);
            cloth_hi = glm::max(cloth_hi, q);
        }
    const auto differs = [](const Image& a, const Image& b, int x, int y) {
        for (int c = 0; c < 3; ++c)
            if (std::abs(int{a.pixel(x, y)[c]} - int{b.pixel(x, y)[c]}) > 24) return true;
        return false;
    };
    int wire_pixels = 0, in_box = 0, outside_cloth = 0, normal_only = 0;
    for (int y = 0; y < plain.height; ++y)
        for (int x = 0; x < plain.width; ++x) {
            const auto fx = static_cast<float>(x), fy = static_cast<float>(y);
            const bool boxed = fx > box_lo.x + 2.0F && fx < box_hi.x - 2.0F && fy > box_lo.y + 2.0F && fy < box_hi.y - 2.0F;
            const bool near_cloth = fx >= cloth_lo.x - 2.0F && fx <= cloth_hi.x + 2.0F && fy >= cloth_lo.y - 2.0F &&
                                    fy <= cloth_hi.y + 2.0F;
            for (const Image* lines : {&wire, &normals}) {
                if (!differs(plain, *lines, x, y)) continue;
                if (boxed) ++in_box;
                if (!near_cloth) ++outside_cloth;
            }
            if (differs(plain, wire, x, y)) ++wire_pixels;
            if (differs(plain, normals, x, y) && !differs(plain, wire, x, y)) ++normal_only;
        }
    std::printf("%s overlay: wireframe %d pixels, normals alone %d, inside the box %d, outside the cloth %d "
                "(box %.0f..%.0f x %.0f..%.0f)\n",
                std::string(r.name()).c_str(), wire_pixels, normal_only, in_box, outside_cloth, double{box_lo.x},
                double{box_hi.x}, double{box_lo.y}, double{box_hi.y});
    ASSERT_GT(box_hi.x - box_lo.x, 8.0F) << "the box is too small on screen to test hiding";
    EXPECT_GT(wire_pixels, 1000) << "the wireframe was not drawn";
    EXPECT_GT(normal_only, 200) << "the normals were not drawn";
    EXPECT_EQ(in_box, 0) << "lines drawn through the box in front of the sheet (no depth test)";
    EXPECT_EQ(outside_cloth, 0) << "lines away from the cloth buffer's vertices";
    EXPECT_EQ(r.draw(t.frame).rgba, plain.rgba) << "lines off must draw the picture without them";
    EXPECT_EQ(r.validation_messages(), 0);
}

}  // namespace weft::render::test
