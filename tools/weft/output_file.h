#pragma once
/// @file
/// Opening the files `weft` writes (stats, bench results) up front, so that a bad path fails before
/// the simulation rather than after it; they are written whole or not at all (weft/atomic_file.h).

#include <filesystem>
#include <string_view>

#include "weft/atomic_file.h"

namespace weft::cli {

/// Creates the parent folders of `file` and opens its temporary copy for writing (binary). Throws
/// `weft::Error` naming `what` ("stats file") and the path when either fails.
[[nodiscard]] AtomicFile open_output_file(const std::filesystem::path& file, std::string_view what);

/// Finishes `out`: the file replaces `file` whole. Throws `weft::Error` naming `what` if anything
/// written failed (then `file` is as it was before the run).
void close_output_file(AtomicFile& out, const std::filesystem::path& file, std::string_view what);

}  // namespace weft::cli
