// Image tests of the capture paths (label `render`): shipped scenes simulated on the CPU backend for
// a fixed number of frames, drawn by the EGL (OpenGL 4.5) and the Vulkan renderer, and held to
// - golden images in tests/render/golden/ (per scene and renderer, with a tolerance for rounding),
// - each other (the same shaders and matrices: the two paths agree within a tolerance),
// - not being blank (a black or single-colour frame fails).
// Regenerate the goldens after an intended change of the look with WEFT_UPDATE_GOLDEN=1 and look at
// them before committing. Validation (Vulkan layers, GL debug output) is on and must stay silent.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>

#include "render_test_scenes.h"
#include "weft/error.h"
#include "weft/render/image.h"
#include "weft/render/renderer.h"
#include "weft/scene.h"

namespace weft::render {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 180;

const std::filesystem::path kGoldenDir = std::filesystem::path(WEFT_SOURCE_DIR) / "tests" / "render" / "golden";

bool updating_goldens() {
    const char* v = std::getenv("WEFT_UPDATE_GOLDEN");
    return v != nullptr && std::string(v) == "1";
}

/// The renderer `name` at the test size with validation, or nullptr with the reason in `why`.
std::unique_ptr<Renderer> try_renderer(const std::string& name, std::string& why) {
    RendererOptions o;
    o.width = kWidth;
    o.height = kHeight;
    o.validation = true;
    try {
        return create_renderer(name, o);
    } catch (const Error& e) {
        why = e.what();
        return nullptr;
    }
}

/// What "a picture was drawn" means here: luminance varies (not blank, black or one colour) and
/// more than one hue is present in quantity. Returns an empty string when it holds, else why not.
std::string not_a_picture(const Image& image) {
    if (image.empty()) return "empty image";
    const double spread = luminance_spread(image);
    if (spread < 8.0) return "luminance spread " + std::to_string(spread) + " < 8: blank frame";
    std::map<int, int> colours;  // coarse colour histogram, 4 levels per channel
    for (std::size_t p = 0; p < image.rgba.size(); p += 4)
        ++colours[(image.rgba[p] >> 6) * 16 + (image.rgba[p + 1] >> 6) * 4 + (image.rgba[p + 2] >> 6)];
    int common = 0;
    for (const auto& [colour, count] : colours)
        if (count > static_cast<int>(image.rgba.size() / 4 / 100)) ++common;
    if (common < 3) return std::to_string(common) + " colours cover more than 1 % each: nothing drawn";
    return {};
}

struct Case {
    const char* scene;
    std::vector<std::string> overrides;
    int frames;
};

const Case kCases[] = {
    {"flag", {}, 40},
    {"layers", {}, 40},
};

/// The scene after `frames` CPU frames, as a render scene and frame.
struct Simulated {
    std::unique_ptr<World> world;
    RenderScene scene;
    std::vector<RenderVertex> vertices;
    RenderFrame frame;
};

Simulated simulate(const Case& c) {
    Simulated s;
    const auto file = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / (std::string(c.scene) + ".toml");
    const SceneDesc desc = load_scene(file, c.overrides);
    s.world = build_world(desc, "cpu");
    for (int f = 0; f < c.frames; ++f) (void)s.world->step();
    s.scene = make_render_scene(*s.world, desc.camera);
    cloth_vertices(*s.world, s.scene, s.vertices);
    s.frame.cloth = s.vertices;
    s.frame.collider_models = collider_models(s.scene, s.world->model(), s.world->time());
    return s;
}

TEST(Capture, TheBlankFrameCheckFails) {
    // The check every image test relies on: it must reject what a broken renderer gives.
    EXPECT_FALSE(not_a_picture(Image(kWidth, kHeight)).empty()) << "black";
    Image grey(kWidth, kHeight);
    std::fill(grey.rgba.begin(), grey.rgba.end(), 160);
    EXPECT_FALSE(not_a_picture(grey).empty()) << "one colour";
    Image two(kWidth, kHeight);  // two flat colours, as a clear colour plus a flat quad would give
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) std::fill_n(two.pixel(x, y), 3, static_cast<std::uint8_t>(y < kHeight / 2 ? 40 : 220));
    EXPECT_FALSE(not_a_picture(two).empty()) << "two flat colours";
}

TEST(Capture, ScenesMatchTheirGoldensOnEveryRendererAndAgree) {
    std::map<std::string, std::unique_ptr<Renderer>> renderers;
    for (const std::string name : {"egl", "vulkan"}) {
        std::string why;
        if (auto r = try_renderer(name, why)) {
            renderers[name] = std::move(r);
        } else {
            std::printf("[  SKIPPED ] renderer %s: %s\n", name.c_str(), why.c_str());
        }
    }
    if (renderers.empty()) GTEST_SKIP() << "no renderer can start on this machine";
    if (updating_goldens()) std::filesystem::create_directories(kGoldenDir);
    for (const Case& c : kCases) {
        SCOPED_TRACE(c.scene);
        const Simulated s = simulate(c);
        std::map<std::string, Image> images;
        for (auto& [name, renderer] : renderers) {
            SCOPED_TRACE(name);
            renderer->load(s.scene);
            const Image image = renderer->draw(s.frame);
            EXPECT_EQ(not_a_picture(image), "");
            EXPECT_EQ(renderer->validation_messages(), 0);
            const auto golden = kGoldenDir / (std::string(c.scene) + "_" + name + ".png");
            if (updating_goldens()) {
                write_png(golden, image);
                std::printf("[ golden   ] wrote %s\n", golden.c_str());
            } else if (std::filesystem::exists(golden)) {
                // The same build of the same driver gives the same bytes; the tolerance absorbs a
                // different CPU's or driver build's rounding of the odd edge pixel.
                const ImageDifference d = compare(image, read_png(golden), 24);
                std::printf("[ golden   ] %s %s: mean %.3f, max %d, %.3f %% of pixels over 24\n", c.scene, name.c_str(),
                            d.mean, d.max, 100.0 * d.fraction_over);
                EXPECT_LE(d.mean, 1.5);
                EXPECT_LE(d.fraction_over, 0.01);
                if (d.mean > 1.5 || d.fraction_over > 0.01) {
                    const auto failed = std::filesystem::temp_directory_path() / ("weft_" + golden.filename().string());
                    write_png(failed, image);
                    std::printf("[ golden   ] this run's image: %s\n", failed.c_str());
                }
            } else {
                ADD_FAILURE() << "no golden image " << golden << " (run with WEFT_UPDATE_GOLDEN=1 and look at it)";
            }
            images[name] = image;
        }
        if (images.size() == 2) {
            // Two rasterisers of the same shaders: edges and the shadow map's texel boundaries may
            // land on different pixels, surfaces must not differ.
            const ImageDifference d = compare(images["egl"], images["vulkan"], 48);
            std::printf("[ agree    ] %s egl against vulkan: mean %.3f, max %d, %.3f %% of pixels over 48\n", c.scene,
                        d.mean, d.max, 100.0 * d.fraction_over);
            EXPECT_LE(d.mean, 3.0);
            EXPECT_LE(d.fraction_over, 0.02);
        }
    }
}

}  // namespace
}  // namespace weft::render
