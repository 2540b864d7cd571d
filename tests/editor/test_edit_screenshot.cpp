// The screenshot `weft edit flag --script data/tune.txt --size 1024x640` wrote under Xvfb
// (cli.edit_script): the ImGui panels are drawn into the window's picture over the scene, the
// controls column on the left and the stats column on the right, with the flag between them.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>

#include "weft/render/image.h"

namespace weft::render {
namespace {

struct Region {
    int x0, x1;  ///< columns [x0, x1)
};

// ImGui's dark style: window background (0.06, 0.06, 0.06) at 94 % over the scene, so a near-black
// grey; headers, sliders and buttons in its blue (0.26, 0.59, 0.98) at various opacities.
double fraction(const Image& image, Region r, bool (*test)(int, int, int)) {
    int hits = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
            const std::uint8_t* p = &image.rgba[4 * (static_cast<std::size_t>(y) * image.width + x)];
            if (test(p[0], p[1], p[2])) ++hits;
        }
    return static_cast<double>(hits) / ((r.x1 - r.x0) * image.height);
}

bool window_grey(int r, int g, int b) { return r < 45 && g < 45 && b < 45 && std::abs(r - g) < 10 && std::abs(g - b) < 12; }
bool imgui_blue(int r, int g, int b) { return b > 90 && b > r + 40 && g > r; }
bool flag_red(int r, int g, int b) { return r > g + 40 && r > b + 40; }

TEST(EditScreenshot, ShowsThePanelsAndTheFlag) {
    const std::filesystem::path file = WEFT_EDIT_SCREENSHOT;
    if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " missing: cli.edit_script did not run";
    const Image image = read_png(file);
    ASSERT_EQ(image.width, 1024);
    ASSERT_EQ(image.height, 640);
    EXPECT_GT(luminance_spread(image), 10.0) << "not blank";

    // The two columns are 340 pixels wide (editor/src/panels.cpp).
    const Region left{0, 340}, middle{340, 1024 - 340}, right{1024 - 340, 1024};
    EXPECT_GT(fraction(image, left, window_grey), 0.4) << "the controls' window background";
    EXPECT_GT(fraction(image, left, imgui_blue), 0.03) << "the controls' headers and sliders";
    EXPECT_GT(fraction(image, right, window_grey), 0.4) << "the stats window's background";
    EXPECT_GT(fraction(image, right, imgui_blue), 0.01) << "the stats window's plots";
    EXPECT_LT(fraction(image, middle, window_grey), 0.05) << "no panel over the scene";
    EXPECT_GT(fraction(image, middle, flag_red), 0.1) << "the flag between the columns";
}

}  // namespace
}  // namespace weft::render
