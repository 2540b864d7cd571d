#pragma once
// A small raster canvas for the benchmarks' PNG plots: anti-aliased lines and discs, and text in
// Dear ImGui's built-in font (its font atlas, rasterised on the CPU: no window, no GPU), written
// through the renderer's PNG writer (libpng). Coordinates are pixels, y down.

#include <cstdint>
#include <filesystem>
#include <string>

#include "weft/render/image.h"

namespace weft::bench {

struct Rgb {
    std::uint8_t r = 0, g = 0, b = 0;
};

class RasterCanvas {
public:
    /// A white canvas of `width` × `height` pixels.
    RasterCanvas(int width, int height);

    /// A line of `width` pixels from (x0, y0) to (x1, y1), its edges anti-aliased.
    void line(double x0, double y0, double x1, double y1, Rgb colour, double width = 1.0);
    /// A disc of radius `r` at (cx, cy), filled with `fill` and ringed by `stroke` `ring` pixels wide.
    void disc(double cx, double cy, double r, Rgb fill, Rgb stroke, double ring = 1.5);
    /// `text` with its baseline-left corner at (x, y) (`anchor` 0), centred on x (0.5) or ending at
    /// x (1); `scale` enlarges the 13-pixel font; `vertical` turns it a quarter left (reading upwards),
    /// (x, y) then being the point its baseline starts from.
    void text(double x, double y, const std::string& text, Rgb colour, double anchor = 0.0, int scale = 1, bool vertical = false);
    /// Width of `text` in pixels at `scale`.
    [[nodiscard]] double text_width(const std::string& text, int scale = 1) const;

    /// Writes the canvas as a PNG. Throws weft::Error naming the file.
    void save(const std::filesystem::path& file) const;
    [[nodiscard]] const render::Image& image() const { return image_; }

private:
    /// Blends `colour` over pixel (x, y) with coverage `alpha` in [0, 1].
    void blend(int x, int y, Rgb colour, double alpha);
    render::Image image_;
};

}  // namespace weft::bench
