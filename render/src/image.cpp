// PNG files through libpng, and image comparisons for the image tests (see image.h).
#include "weft/render/image.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "weft/atomic_file.h"
#include "weft/error.h"

namespace weft::render {
namespace {

struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

[[noreturn]] void png_fail(png_structp png, png_const_charp message) {
    // libpng requires this not to return: longjmp back to the setjmp in the caller.
    auto* what = static_cast<std::string*>(png_get_error_ptr(png));
    if (what != nullptr) *what = message;
    png_longjmp(png, 1);
}

void png_warn(png_structp, png_const_charp) {}

}  // namespace

/// libpng writes `image` to `path`; messages name `file`, the file the caller asked for.
static void write_png_to(const std::filesystem::path& path, const std::filesystem::path& file, const Image& image);

void write_png(const std::filesystem::path& file, const Image& image) {
    if (image.empty() || image.rgba.size() != static_cast<std::size_t>(image.width) * image.height * 4)
        throw Error("write_png: " + file.string() + ": the image is empty or its size does not match its pixels");
    // Whole or not at all: libpng writes the temporary file, which replaces `file` when complete.
    AtomicFile target(file);
    target.release_stream();
    write_png_to(target.temporary(), file, image);
    target.commit();
}

static void write_png_to(const std::filesystem::path& path, const std::filesystem::path& file, const Image& image) {
    File f(std::fopen(path.c_str(), "wb"));
    if (!f) throw Error("write_png: cannot open " + file.string() + " for writing");
    std::string what;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &what, png_fail, png_warn);
    png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
    if (png == nullptr || info == nullptr) {
        png_destroy_write_struct(&png, nullptr);
        throw Error("write_png: libpng could not start");
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        throw Error("write_png: " + file.string() + ": " + what);
    }
    png_init_io(png, f.get());
    png_set_IHDR(png, info, static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height), 8,
                 PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, 3);  // fast: captures write many frames
    png_write_info(png, info);
    for (int y = 0; y < image.height; ++y) png_write_row(png, image.pixel(0, y));
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    if (std::fflush(f.get()) != 0) throw Error("write_png: " + file.string() + ": write failed (disk full?)");
}

Image read_png(const std::filesystem::path& file) {
    File f(std::fopen(file.c_str(), "rb"));
    if (!f) throw Error("read_png: cannot open " + file.string());
    unsigned char signature[8] = {};
    if (std::fread(signature, 1, 8, f.get()) != 8 || png_sig_cmp(signature, 0, 8) != 0)
        throw Error("read_png: " + file.string() + " is not a PNG file");
    std::string what;
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &what, png_fail, png_warn);
    png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
    if (png == nullptr || info == nullptr) {
        png_destroy_read_struct(&png, nullptr, nullptr);
        throw Error("read_png: libpng could not start");
    }
    Image image;
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        throw Error("read_png: " + file.string() + ": " + what);
    }
    png_init_io(png, f.get());
    png_set_sig_bytes(png, 8);
    png_read_info(png, info);
    // Whatever the file holds, deliver 8-bit RGBA.
    png_set_expand(png);
    png_set_strip_16(png);
    png_set_gray_to_rgb(png);
    png_set_add_alpha(png, 0xff, PNG_FILLER_AFTER);
    png_read_update_info(png, info);
    image = Image(static_cast<int>(png_get_image_width(png, info)), static_cast<int>(png_get_image_height(png, info)));
    for (int y = 0; y < image.height; ++y) png_read_row(png, image.pixel(0, y), nullptr);
    png_read_end(png, nullptr);
    png_destroy_read_struct(&png, &info, nullptr);
    return image;
}

ImageDifference compare(const Image& a, const Image& b, int threshold) {
    if (a.width != b.width || a.height != b.height)
        throw Error("compare: images differ in size (" + std::to_string(a.width) + "×" + std::to_string(a.height) +
                    " against " + std::to_string(b.width) + "×" + std::to_string(b.height) + ")");
    ImageDifference d;
    if (a.empty()) return d;
    std::uint64_t sum = 0, over = 0;
    const std::size_t pixels = static_cast<std::size_t>(a.width) * a.height;
    for (std::size_t p = 0; p < pixels; ++p) {
        int worst = 0;
        for (int c = 0; c < 3; ++c) {
            const int diff = std::abs(static_cast<int>(a.rgba[4 * p + c]) - static_cast<int>(b.rgba[4 * p + c]));
            sum += static_cast<std::uint64_t>(diff);
            worst = std::max(worst, diff);
        }
        d.max = std::max(d.max, worst);
        if (worst > threshold) ++over;
    }
    d.mean = static_cast<double>(sum) / static_cast<double>(3 * pixels);
    d.fraction_over = static_cast<double>(over) / static_cast<double>(pixels);
    return d;
}

double luminance_spread(const Image& image) {
    if (image.empty()) return 0.0;
    double sum = 0.0, sum2 = 0.0;
    const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
    for (std::size_t p = 0; p < pixels; ++p) {
        const double l = 0.2126 * image.rgba[4 * p] + 0.7152 * image.rgba[4 * p + 1] + 0.0722 * image.rgba[4 * p + 2];
        sum += l;
        sum2 += l * l;
    }
    const double mean = sum / static_cast<double>(pixels);
    return std::sqrt(std::max(0.0, sum2 / static_cast<double>(pixels) - mean * mean));
}

Image contact_sheet(const std::vector<Image>& images, int columns, int scale) {
    if (images.empty()) return {};
    if (columns < 1 || scale < 1) throw Error("contact_sheet: columns and scale must be at least 1");
    const int w = images.front().width / scale, h = images.front().height / scale;
    const int rows = (static_cast<int>(images.size()) + columns - 1) / columns;
    Image sheet(w * std::min<int>(columns, static_cast<int>(images.size())), h * rows);
    for (std::size_t k = 0; k < images.size(); ++k) {
        const Image& im = images[k];
        if (im.width != images.front().width || im.height != images.front().height)
            throw Error("contact_sheet: image " + std::to_string(k) + " differs in size from the first");
        const int ox = static_cast<int>(k % static_cast<std::size_t>(columns)) * w;
        const int oy = static_cast<int>(k / static_cast<std::size_t>(columns)) * h;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 4; ++c) {
                    int sum = 0;
                    for (int sy = 0; sy < scale; ++sy)
                        for (int sx = 0; sx < scale; ++sx) sum += im.pixel(x * scale + sx, y * scale + sy)[c];
                    sheet.pixel(ox + x, oy + y)[c] = static_cast<std::uint8_t>(sum / (scale * scale));
                }
    }
    return sheet;
}

}  // namespace weft::render
