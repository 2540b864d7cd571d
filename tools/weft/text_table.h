#pragma once
/// @file
/// Plain-text tables for terminal summaries (`weft run`, `weft bench`), plus number formatting.

#include <cstddef>
#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "weft/byte_size.h"  // format_bytes, beside the table's other formats

namespace weft::cli {

class TextTable {
public:
    enum class Align : std::uint8_t { Left, Right };
    struct Column {
        std::string title;
        Align align = Align::Right;
    };
    explicit TextTable(std::vector<Column> columns) : columns_(std::move(columns)) {}

    /// Adds a row; missing cells are blank, extra cells are an error (std::invalid_argument).
    void add_row(std::vector<std::string> cells);
    /// Prints the title row, a rule and the rows, each line prefixed by `indent`.
    void print(std::ostream& out, std::string_view indent = "  ") const;

private:
    std::vector<Column> columns_;
    std::vector<std::vector<std::string>> rows_;
};

/// `value` with `decimals` digits after the point; "-" when not finite.
[[nodiscard]] std::string format_fixed(double value, int decimals);
/// Seconds as m:ss or h:mm:ss.
[[nodiscard]] std::string format_duration(double seconds);
/// Characters shown on a terminal for UTF-8 `text` (code points; no wide-character handling).
[[nodiscard]] std::size_t display_width(std::string_view text);

}  // namespace weft::cli
