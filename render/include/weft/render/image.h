#pragma once
/// @file
/// An RGBA8 image in memory, PNG files, and the comparisons the image tests use.
#include <cstdint>
#include <filesystem>
#include <vector>

namespace weft::render {

/// 8-bit RGBA, sRGB-encoded, rows top to bottom, no padding.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgba;  ///< width·height·4 bytes

    Image() = default;
    Image(int w, int h) : width(w), height(h), rgba(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4, 0) {}
    [[nodiscard]] bool empty() const { return width <= 0 || height <= 0; }
    [[nodiscard]] std::uint8_t* pixel(int x, int y) { return rgba.data() + (static_cast<std::size_t>(y) * width + x) * 4; }
    [[nodiscard]] const std::uint8_t* pixel(int x, int y) const {
        return rgba.data() + (static_cast<std::size_t>(y) * width + x) * 4;
    }
};

/// Writes `image` as an 8-bit RGBA PNG. Throws `weft::Error` naming the file on failure.
void write_png(const std::filesystem::path& file, const Image& image);
/// Reads a PNG of any bit depth and colour type, converted to 8-bit RGBA. Throws `weft::Error`
/// naming the file when it is missing or not a PNG.
[[nodiscard]] Image read_png(const std::filesystem::path& file);

/// How two images of the same size differ, per channel value (0–255) over the RGB channels.
struct ImageDifference {
    double mean = 0.0;               ///< mean absolute difference
    int max = 0;                     ///< largest absolute difference
    double fraction_over = 0.0;      ///< fraction of pixels with any channel differing by more than the threshold
};
/// Compares `a` and `b` (same size, else throws `weft::Error`); `threshold` is the per-channel
/// difference below which a pixel counts as equal in `fraction_over`.
[[nodiscard]] ImageDifference compare(const Image& a, const Image& b, int threshold = 16);

/// Standard deviation of the luminance (0–255): near 0 for a blank, black or single-colour frame.
[[nodiscard]] double luminance_spread(const Image& image);

/// Tiles `images` (all the same size) into a grid `columns` wide, each scaled down by `scale`
/// (an integer ≥ 1, box filter): the contact sheet of a run.
[[nodiscard]] Image contact_sheet(const std::vector<Image>& images, int columns, int scale);

}  // namespace weft::render
