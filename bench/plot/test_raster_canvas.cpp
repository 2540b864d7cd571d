// The benchmarks' raster canvas and PNG plot (bench/plot): lines and discs land where they are
// drawn and nowhere else, text in ImGui's font leaves ink inside its box only, and the tradeoff
// plot's PNG reads back with the front drawn in its colour.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "raster_canvas.h"
#include "tradeoff_plot.h"
#include "weft/error.h"

namespace weft::bench {
namespace {

bool white(const render::Image& im, int x, int y) {
    const std::uint8_t* p = im.pixel(x, y);
    return p[0] == 255 && p[1] == 255 && p[2] == 255;
}

int ink_in(const render::Image& im, int x0, int y0, int x1, int y1) {
    int n = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) n += white(im, x, y) ? 0 : 1;
    return n;
}

TEST(RasterCanvas, LinesAndDiscsLandWhereDrawn) {
    RasterCanvas c(100, 60);
    c.line(10, 20, 90, 20, Rgb{0, 0, 0}, 2.0);
    const render::Image& im = c.image();
    EXPECT_EQ(im.pixel(50, 19)[0], 0) << "on the line";
    EXPECT_TRUE(white(im, 50, 40)) << "far from the line";
    EXPECT_TRUE(white(im, 5, 20)) << "before its start";
    c.disc(50, 45, 6, Rgb{200, 0, 0}, Rgb{0, 0, 0});
    EXPECT_EQ(im.pixel(50, 45)[0], 200);
    EXPECT_EQ(im.pixel(50, 45)[1], 0);
    EXPECT_TRUE(white(im, 60, 45));
}

TEST(RasterCanvas, TextLeavesInkInsideItsBoxOnly) {
    RasterCanvas c(200, 60);
    const double w = c.text_width("1e-3 error");
    EXPECT_GT(w, 40.0);
    EXPECT_LT(w, 100.0);
    c.text(20, 30, "1e-3 error", Rgb{0, 0, 0});
    const render::Image& im = c.image();
    EXPECT_GT(ink_in(im, 20, 16, 20 + static_cast<int>(w) + 1, 34), 40);
    EXPECT_EQ(ink_in(im, 0, 0, 200, 14), 0) << "above the line of text";
    EXPECT_EQ(ink_in(im, 21 + static_cast<int>(w), 0, 200, 60), 0) << "past its end";
    // Right-aligned at x = 180, and upright vertical text reading upwards from (10, 55).
    RasterCanvas r(200, 60);
    r.text(180, 30, "abc", Rgb{0, 0, 0}, 1.0);
    EXPECT_EQ(ink_in(r.image(), 181, 0, 200, 60), 0);
    EXPECT_GT(ink_in(r.image(), 170, 16, 180, 34), 5);
    RasterCanvas v(60, 100);
    v.text(20, 90, "vertical", Rgb{0, 0, 0}, 0.0, 1, true);
    EXPECT_EQ(ink_in(v.image(), 0, 91, 60, 100), 0) << "below its start";
    EXPECT_GT(ink_in(v.image(), 5, 40, 25, 90), 20);
}

TEST(TradeoffPlot, WritesSvgAndPngAndRefusesWhatItCannot) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path();
    const std::vector<TradeoffPoint> points = {{"a", 100.0, 1e-3, true, true}, {"b", 1000.0, 1e-4, true, true},
                                               {"c", 2000.0, 5e-4, false, false}};
    write_tradeoff_plot(dir / "weft_plot_test.svg", "t", points);
    EXPECT_GT(std::filesystem::file_size(dir / "weft_plot_test.svg"), 500U);
    write_tradeoff_plot(dir / "weft_plot_test.png", "t", points);
    EXPECT_GT(std::filesystem::file_size(dir / "weft_plot_test.png"), 1000U);
    EXPECT_THROW(write_tradeoff_plot(dir / "weft_plot_test.jpg", "t", points), Error);
    EXPECT_THROW(write_tradeoff_plot(dir / "weft_plot_test.png", "t", {{"nan", 0.0, 1.0, false, true}}), Error);
    std::filesystem::remove(dir / "weft_plot_test.svg");
    std::filesystem::remove(dir / "weft_plot_test.png");
}

}  // namespace
}  // namespace weft::bench
