#pragma once
/// @file
/// Opening the files `weft` writes (stats, bench results) up front, so that a bad path fails before
/// the simulation rather than after it.

#include <filesystem>
#include <fstream>
#include <string_view>

namespace weft::cli {

/// Creates the parent folders of `file` and opens it for writing (binary, truncated). Throws
/// `weft::Error` naming `what` ("stats file") and the path when either fails.
[[nodiscard]] std::ofstream open_output_file(const std::filesystem::path& file, std::string_view what);

/// Closes `stream` and throws `weft::Error` if anything written to it failed.
void close_output_file(std::ofstream& stream, const std::filesystem::path& file, std::string_view what);

}  // namespace weft::cli
