#include "text_table.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace weft::cli {

std::size_t display_width(std::string_view text) {
    // Count every byte that does not continue a UTF-8 sequence (10xxxxxx).
    return static_cast<std::size_t>(
        std::count_if(text.begin(), text.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

void TextTable::add_row(std::vector<std::string> cells) {
    if (cells.size() > columns_.size()) throw std::invalid_argument("TextTable: more cells than columns");
    cells.resize(columns_.size());
    rows_.push_back(std::move(cells));
}

void TextTable::print(std::ostream& out, std::string_view indent) const {
    std::vector<std::size_t> width(columns_.size());
    for (std::size_t c = 0; c < columns_.size(); ++c) {
        width[c] = display_width(columns_[c].title);
        for (const auto& row : rows_) width[c] = std::max(width[c], display_width(row[c]));
    }
    const auto print_row = [&](const auto& cell_of) {
        std::string line(indent);
        for (std::size_t c = 0; c < columns_.size(); ++c) {
            const std::string_view cell = cell_of(c);
            const std::string pad(width[c] - display_width(cell), ' ');
            if (c > 0) line += "  ";
            if (columns_[c].align == Align::Right) line += pad;
            line += cell;
            if (columns_[c].align == Align::Left && c + 1 < columns_.size()) line += pad;
        }
        out << line << '\n';
    };
    print_row([&](std::size_t c) -> std::string_view { return columns_[c].title; });
    std::size_t total = 0;
    for (const std::size_t w : width) total += w;
    total += 2 * (columns_.empty() ? 0 : columns_.size() - 1);
    out << indent << std::string(total, '-') << '\n';
    for (const auto& row : rows_) print_row([&](std::size_t c) -> std::string_view { return row[c]; });
}

std::string format_fixed(double value, int decimals) {
    if (!std::isfinite(value)) return "-";
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.*f", decimals, value);
    return buf;
}

std::string format_duration(double seconds) {
    if (!std::isfinite(seconds) || seconds < 0.0) return "-:--";
    const auto total = static_cast<long long>(std::llround(seconds));
    const long long h = total / 3600;
    const long long m = (total / 60) % 60;
    const long long s = total % 60;
    char buf[48];
    if (h > 0)
        std::snprintf(buf, sizeof(buf), "%lld:%02lld:%02lld", h, m, s);
    else
        std::snprintf(buf, sizeof(buf), "%lld:%02lld", m, s);
    return buf;
}

}  // namespace weft::cli
