// The benchmarks' raster canvas (raster_canvas.h).
#include "raster_canvas.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace weft::bench {
namespace {

/// Dear ImGui's default font (ProggyClean, 13 px) baked into an 8-bit coverage atlas once. The
/// atlas needs no ImGui context: it is the library's own rasteriser, used here without a window.
struct FontAtlas {
    ImFontAtlas atlas;
    ImFont* font = nullptr;
    unsigned char* pixels = nullptr;
    int width = 0, height = 0;

    FontAtlas() {
        font = atlas.AddFontDefault();
        atlas.GetTexDataAsAlpha8(&pixels, &width, &height);
    }
    [[nodiscard]] float coverage(float u, float v) const {
        const int x = std::clamp(static_cast<int>(u * static_cast<float>(width)), 0, width - 1);
        const int y = std::clamp(static_cast<int>(v * static_cast<float>(height)), 0, height - 1);
        return static_cast<float>(pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + x]) / 255.0F;
    }
};

const FontAtlas& font_atlas() {
    static const auto atlas = std::make_unique<FontAtlas>();
    return *atlas;
}

/// The code points of UTF-8 `text` up to U+FFFF (the font has Latin-1, so "×" and "µ" draw; a
/// malformed byte stands for itself).
std::vector<ImWchar> code_points(const std::string& text) {
    std::vector<ImWchar> out;
    for (std::size_t i = 0; i < text.size();) {
        const auto b = static_cast<unsigned char>(text[i]);
        const int extra = b >= 0xE0 && b < 0xF0 ? 2 : b >= 0xC0 && b < 0xE0 ? 1 : 0;
        unsigned int c = extra == 2 ? b & 0x0Fu : extra == 1 ? b & 0x1Fu : b;
        bool ok = i + static_cast<std::size_t>(extra) < text.size();
        for (int k = 1; ok && k <= extra; ++k) {
            const auto next = static_cast<unsigned char>(text[i + static_cast<std::size_t>(k)]);
            ok = (next & 0xC0u) == 0x80u;
            c = (c << 6) | (next & 0x3Fu);
        }
        if (!ok) c = b;
        out.push_back(static_cast<ImWchar>(c));
        i += ok ? 1 + static_cast<std::size_t>(extra) : 1;
    }
    return out;
}

}  // namespace

RasterCanvas::RasterCanvas(int width, int height) : image_(width, height) {
    std::fill(image_.rgba.begin(), image_.rgba.end(), std::uint8_t{255});
}

void RasterCanvas::blend(int x, int y, Rgb c, double alpha) {
    if (x < 0 || y < 0 || x >= image_.width || y >= image_.height || !(alpha > 0.0)) return;
    const double a = std::min(1.0, alpha);
    std::uint8_t* p = image_.pixel(x, y);
    const auto mix = [a](std::uint8_t under, std::uint8_t over) {
        return static_cast<std::uint8_t>(std::lround(static_cast<double>(under) * (1.0 - a) + static_cast<double>(over) * a));
    };
    p[0] = mix(p[0], c.r);
    p[1] = mix(p[1], c.g);
    p[2] = mix(p[2], c.b);
    p[3] = 255;
}

void RasterCanvas::line(double x0, double y0, double x1, double y1, Rgb colour, double width) {
    // Coverage from the distance to the segment: full within half the width, fading over one pixel.
    const double dx = x1 - x0, dy = y1 - y0, length2 = dx * dx + dy * dy;
    const double half = 0.5 * width;
    const int xa = static_cast<int>(std::floor(std::min(x0, x1) - half - 1)), xb = static_cast<int>(std::ceil(std::max(x0, x1) + half + 1));
    const int ya = static_cast<int>(std::floor(std::min(y0, y1) - half - 1)), yb = static_cast<int>(std::ceil(std::max(y0, y1) + half + 1));
    for (int y = std::max(0, ya); y <= std::min(image_.height - 1, yb); ++y)
        for (int x = std::max(0, xa); x <= std::min(image_.width - 1, xb); ++x) {
            const double px = x + 0.5 - x0, py = y + 0.5 - y0;
            const double t = length2 > 0.0 ? std::clamp((px * dx + py * dy) / length2, 0.0, 1.0) : 0.0;
            const double ex = px - t * dx, ey = py - t * dy;
            const double d = std::sqrt(ex * ex + ey * ey);
            blend(x, y, colour, std::clamp(half + 0.5 - d, 0.0, 1.0));
        }
}

void RasterCanvas::disc(double cx, double cy, double r, Rgb fill, Rgb stroke, double ring) {
    const int xa = static_cast<int>(std::floor(cx - r - 2)), xb = static_cast<int>(std::ceil(cx + r + 2));
    const int ya = static_cast<int>(std::floor(cy - r - 2)), yb = static_cast<int>(std::ceil(cy + r + 2));
    for (int y = std::max(0, ya); y <= std::min(image_.height - 1, yb); ++y)
        for (int x = std::max(0, xa); x <= std::min(image_.width - 1, xb); ++x) {
            const double d = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
            blend(x, y, fill, std::clamp(r - ring + 0.5 - d, 0.0, 1.0));
            blend(x, y, stroke, std::clamp(0.5 * ring + 0.5 - std::abs(d - (r - 0.5 * ring)), 0.0, 1.0));
        }
}

double RasterCanvas::text_width(const std::string& text, int scale) const {
    const FontAtlas& f = font_atlas();
    double w = 0.0;
    for (const ImWchar c : code_points(text))
        if (const ImFontGlyph* g = f.font->FindGlyph(c)) w += static_cast<double>(g->AdvanceX);
    return w * scale;
}

void RasterCanvas::text(double x, double y, const std::string& text, Rgb colour, double anchor, int scale, bool vertical) {
    const FontAtlas& f = font_atlas();
    const double s = std::max(1, scale);
    // Pen position along the baseline, in font pixels from the text's start; the glyph boxes are
    // given from the line's top, so the baseline sits at the font's ascent.
    double pen = -anchor * text_width(text);
    const double ascent = static_cast<double>(f.font->Ascent);
    for (const ImWchar c : code_points(text)) {
        const ImFontGlyph* g = f.font->FindGlyph(c);
        if (g == nullptr) continue;
        const int gw = static_cast<int>(std::lround(g->X1 - g->X0)), gh = static_cast<int>(std::lround(g->Y1 - g->Y0));
        for (int j = 0; j < gh * s; ++j)
            for (int i = 0; i < gw * s; ++i) {
                const float u = g->U0 + (g->U1 - g->U0) * (static_cast<float>(i / s) + 0.5F) / static_cast<float>(gw);
                const float v = g->V0 + (g->V1 - g->V0) * (static_cast<float>(j / s) + 0.5F) / static_cast<float>(gh);
                const float a = f.coverage(u, v);
                if (a <= 0.0F) continue;
                // Offset of this pixel from the baseline start, along the text (a) and down from it (b).
                const double along = (pen + static_cast<double>(g->X0)) * s + i, down = (static_cast<double>(g->Y0) - ascent) * s + j;
                const double px = vertical ? x + down : x + along, py = vertical ? y - along : y + down;
                blend(static_cast<int>(std::floor(px)), static_cast<int>(std::floor(py)), colour, a);
            }
        pen += static_cast<double>(g->AdvanceX);
    }
}

void RasterCanvas::save(const std::filesystem::path& file) const { render::write_png(file, image_); }

}  // namespace weft::bench
