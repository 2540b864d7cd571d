// The speed/accuracy plot (tradeoff_plot.h): one layout, drawn as SVG text or rasterised to PNG.
#include "tradeoff_plot.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "weft/error.h"
#ifdef WEFT_HAVE_PNG_PLOT
#include "raster_canvas.h"
#endif

namespace weft::bench {
namespace {

/// Where everything goes: log-decade axes fitted to the points, pixel positions of values.
struct Layout {
    double width = 900, height = 600, left = 90, right = 220, top = 50, bottom = 70;
    double lx0 = 0, lx1 = 1, ly0 = 0, ly1 = 1;
    std::vector<const TradeoffPoint*> shown, front;
    /// Per shown point: where its label's baseline starts (x, y), or no label where every place
    /// beside the point would cover another label (the table lists every run anyway).
    struct Label {
        bool drawn = false;
        double x = 0, y = 0;
    };
    std::vector<Label> labels;

    [[nodiscard]] double px(double v) const {
        return left + (std::log10(v) - lx0) / std::max(1.0, lx1 - lx0) * (width - left - right);
    }
    [[nodiscard]] double py(double v) const {
        return height - bottom - (std::log10(v) - ly0) / std::max(1.0, ly1 - ly0) * (height - top - bottom);
    }
};

/// Width of a label in pixels: 7 a character (the PNG's font; near the SVG's 12 px sans-serif).
double label_width(const std::string& text) {
    double n = 0;
    for (const unsigned char c : text) n += (c & 0xC0) == 0x80 ? 0 : 1;  // UTF-8 continuation bytes add nothing
    return 7.0 * n;
}

std::string label_of(const TradeoffPoint& p) { return p.label + (p.clean ? "" : " (not clean)"); }

/// Greedy: the front's labels first, each right, left, above or below its point, wherever it covers
/// no point and no label placed before it.
void place_labels(Layout& l) {
    struct Box {
        double x0, y0, x1, y1;
    };
    std::vector<Box> taken;
    for (const TradeoffPoint* p : l.shown) {  // every point's disc
        const double x = l.px(p->cost), y = l.py(p->error);
        taken.push_back({x - 6, y - 6, x + 6, y + 6});
    }
    l.labels.assign(l.shown.size(), {});
    std::vector<std::size_t> order(l.shown.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return l.shown[a]->front && !l.shown[b]->front; });
    for (const std::size_t k : order) {
        const TradeoffPoint& p = *l.shown[k];
        const double x = l.px(p.cost), y = l.py(p.error), w = label_width(label_of(p));
        const double places[4][2] = {{x + 8, y + 4}, {x - 8 - w, y + 4}, {x - w / 2, y - 9}, {x - w / 2, y + 19}};
        for (const auto& at : places) {
            const Box b{at[0], at[1] - 11, at[0] + w, at[1] + 3};
            const bool free = std::none_of(taken.begin(), taken.end(), [&](const Box& o) {
                return b.x0 < o.x1 && o.x0 < b.x1 && b.y0 < o.y1 && o.y0 < b.y1;
            });
            if (!free) continue;
            taken.push_back(b);
            l.labels[k] = {true, at[0], at[1]};
            break;
        }
    }
}

Layout layout_of(const std::filesystem::path& file, const std::vector<TradeoffPoint>& points) {
    Layout l;
    for (const TradeoffPoint& p : points)
        if (std::isfinite(p.cost) && std::isfinite(p.error) && p.cost > 0.0 && p.error > 0.0) l.shown.push_back(&p);
    if (l.shown.empty()) throw Error(file.string() + ": no run with a finite, positive cost and error to draw");
    double x0 = 1e300, x1 = 0.0, y0 = 1e300, y1 = 0.0;
    for (const TradeoffPoint* p : l.shown) {
        x0 = std::min(x0, p->cost);
        x1 = std::max(x1, p->cost);
        y0 = std::min(y0, p->error);
        y1 = std::max(y1, p->error);
        if (p->front) l.front.push_back(p);
    }
    l.lx0 = std::floor(std::log10(x0));
    l.lx1 = std::ceil(std::log10(x1) + 1e-9);
    l.ly0 = std::floor(std::log10(y0));
    l.ly1 = std::ceil(std::log10(y1) + 1e-9);
    std::sort(l.front.begin(), l.front.end(), [](const TradeoffPoint* a, const TradeoffPoint* b) { return a->cost < b->cost; });
    place_labels(l);
    return l;
}

std::string decade(double d) { return "1e" + std::to_string(static_cast<int>(d)); }

std::string xml(const std::string& s) {
    std::string out;
    for (const char c : s) {
        if (c == '<') out += "&lt;";
        else if (c == '>') out += "&gt;";
        else if (c == '&') out += "&amp;";
        else out += c;
    }
    return out;
}

const char* const kXLabel = "wall ms per simulated second";
const char* const kYLabel = "RMS position error, m";

void write_svg(const std::filesystem::path& file, const std::string& title, const Layout& l) {
    std::ofstream out(file);
    if (!out) throw Error("cannot write " + file.string());
    out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << l.width << "\" height=\"" << l.height
        << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
    out << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    out << "<text x=\"" << l.left << "\" y=\"28\" font-size=\"16\">" << xml(title) << "</text>\n";
    for (double d = l.lx0; d <= l.lx1 + 1e-9; d += 1.0) {
        const double x = l.px(std::pow(10.0, d));
        out << "<line x1=\"" << x << "\" y1=\"" << l.top << "\" x2=\"" << x << "\" y2=\"" << l.height - l.bottom << "\" stroke=\"#ddd\"/>\n";
        out << "<text x=\"" << x << "\" y=\"" << l.height - l.bottom + 18 << "\" text-anchor=\"middle\">" << decade(d) << "</text>\n";
    }
    for (double d = l.ly0; d <= l.ly1 + 1e-9; d += 1.0) {
        const double y = l.py(std::pow(10.0, d));
        out << "<line x1=\"" << l.left << "\" y1=\"" << y << "\" x2=\"" << l.width - l.right << "\" y2=\"" << y << "\" stroke=\"#ddd\"/>\n";
        out << "<text x=\"" << l.left - 8 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">" << decade(d) << "</text>\n";
    }
    out << "<text x=\"" << (l.left + l.width - l.right) / 2 << "\" y=\"" << l.height - 20 << "\" text-anchor=\"middle\">" << kXLabel
        << "</text>\n";
    out << "<text x=\"20\" y=\"" << (l.top + l.height - l.bottom) / 2 << "\" transform=\"rotate(-90 20 "
        << (l.top + l.height - l.bottom) / 2 << ")\" text-anchor=\"middle\">" << kYLabel << "</text>\n";
    if (l.front.size() > 1) {
        out << "<polyline fill=\"none\" stroke=\"#c0392b\" stroke-width=\"1.5\" points=\"";
        for (const TradeoffPoint* p : l.front) out << l.px(p->cost) << "," << l.py(p->error) << " ";
        out << "\"/>\n";
    }
    for (std::size_t k = 0; k < l.shown.size(); ++k) {
        const TradeoffPoint* p = l.shown[k];
        out << "<circle cx=\"" << l.px(p->cost) << "\" cy=\"" << l.py(p->error) << "\" r=\"5\" fill=\"" << (p->front ? "#c0392b" : "white")
            << "\" stroke=\"" << (p->clean ? "#333" : "#e67e22") << "\" stroke-width=\"1.5\"/>\n";
        if (l.labels[k].drawn)
            out << "<text x=\"" << l.labels[k].x << "\" y=\"" << l.labels[k].y << "\">" << xml(label_of(*p)) << "</text>\n";
    }
    out << "</svg>\n";
    if (!out) throw Error("cannot write " + file.string());
}

#ifdef WEFT_HAVE_PNG_PLOT
void write_png_plot(const std::filesystem::path& file, const std::string& title, const Layout& l) {
    RasterCanvas c(static_cast<int>(l.width), static_cast<int>(l.height));
    const Rgb grid{221, 221, 221}, ink{51, 51, 51}, red{192, 57, 43}, orange{230, 126, 34}, white{255, 255, 255};
    c.text(l.left, 30, title, Rgb{}, 0.0, 1);
    for (double d = l.lx0; d <= l.lx1 + 1e-9; d += 1.0) {
        const double x = l.px(std::pow(10.0, d));
        c.line(x, l.top, x, l.height - l.bottom, grid);
        c.text(x, l.height - l.bottom + 18, decade(d), ink, 0.5);
    }
    for (double d = l.ly0; d <= l.ly1 + 1e-9; d += 1.0) {
        const double y = l.py(std::pow(10.0, d));
        c.line(l.left, y, l.width - l.right, y, grid);
        c.text(l.left - 8, y + 4, decade(d), ink, 1.0);
    }
    c.text((l.left + l.width - l.right) / 2, l.height - 20, kXLabel, ink, 0.5);
    c.text(24, (l.top + l.height - l.bottom) / 2 + c.text_width(kYLabel) / 2, kYLabel, ink, 0.0, 1, true);
    for (std::size_t k = 1; k < l.front.size(); ++k)
        c.line(l.px(l.front[k - 1]->cost), l.py(l.front[k - 1]->error), l.px(l.front[k]->cost), l.py(l.front[k]->error), red, 1.5);
    for (std::size_t k = 0; k < l.shown.size(); ++k) {
        const TradeoffPoint* p = l.shown[k];
        c.disc(l.px(p->cost), l.py(p->error), 5, p->front ? red : white, p->clean ? ink : orange);
    }
    for (std::size_t k = 0; k < l.shown.size(); ++k)
        if (l.labels[k].drawn) c.text(l.labels[k].x, l.labels[k].y, label_of(*l.shown[k]), l.shown[k]->clean ? ink : orange);
    c.save(file);
}
#endif

}  // namespace

bool png_plots_available() {
#ifdef WEFT_HAVE_PNG_PLOT
    return true;
#else
    return false;
#endif
}

void write_tradeoff_plot(const std::filesystem::path& file, const std::string& title, const std::vector<TradeoffPoint>& points) {
    const std::string ext = file.extension().string();
    if (ext != ".svg" && ext != ".png")
        throw Error(file.string() + ": the plot is written as .svg or .png (got '" + ext + "')");
    const Layout l = layout_of(file, points);
    if (ext == ".svg") {
        write_svg(file, title, l);
        return;
    }
#ifdef WEFT_HAVE_PNG_PLOT
    write_png_plot(file, title, l);
#else
    throw Error(file.string() + ": PNG plots need the renderer and Dear ImGui's font (configure with WEFT_RENDER and "
                                "WEFT_EDITOR on); write .svg instead");
#endif
}

}  // namespace weft::bench
