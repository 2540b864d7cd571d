#pragma once
/// @file
/// A benchmark's results file: one JSON document written after the measurements.

#include <filesystem>
#include <functional>
#include <ostream>
#include <string_view>

namespace weft::bench {

/// Creates the folders above `file`, writes the document `write` puts on the stream and a newline,
/// and says `results: FILE` on stdout. When the file cannot be opened or written it says so on
/// stderr, prefixed with `program`, and returns false.
bool write_json_file(const std::filesystem::path& file, std::string_view program,
                     const std::function<void(std::ostream&)>& write);

}  // namespace weft::bench
