// The screenshot of `weft view flag --frames 20 --size 320x240` under Xvfb (tests/cli, cli.view_flag):
// the picture that went through the swapchain path must be the flag, not a blank or cleared frame.
#include <gtest/gtest.h>

#include <filesystem>

#include "weft/render/image.h"

namespace weft::render {
namespace {

TEST(ViewScreenshot, ShowsTheFlag) {
    const std::filesystem::path file = WEFT_VIEW_SCREENSHOT;
    if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " missing: cli.view_flag did not run";
    const Image image = read_png(file);
    EXPECT_EQ(image.width, 320);
    EXPECT_EQ(image.height, 240);
    // Not blank: the background, the ground grid, the pole and the lit and shaded cloth.
    EXPECT_GT(luminance_spread(image), 10.0);
    // The flag is the first cloth: front colour (0.8, 0.3, 0.2) linear, a clear red whatever the
    // lighting. It covers a good part of the picture (about a quarter at the scene's camera).
    int red = 0;
    for (int i = 0; i < image.width * image.height; ++i) {
        const int r = image.rgba[4 * i], g = image.rgba[4 * i + 1], b = image.rgba[4 * i + 2];
        if (r > g + 40 && r > b + 40) ++red;
    }
    const double fraction = static_cast<double>(red) / (image.width * image.height);
    EXPECT_GT(fraction, 0.05) << "red (flag) pixels";
    EXPECT_LT(fraction, 0.8) << "red (flag) pixels";
}

}  // namespace
}  // namespace weft::render
