#pragma once
/// @file
/// Help texts of `weft` and its subcommands.

#include <string>
#include <string_view>

namespace weft::cli {

/// Full help for `topic`: "" for the overview, or "run", "bench", "view", "edit", "info", "help"
/// (`weft help scene-keys` is scene_keys_help.h).
[[nodiscard]] std::string_view usage_text(std::string_view topic);
/// The line printed under a usage error, e.g. "Try 'weft run --help'.".
[[nodiscard]] std::string usage_hint(std::string_view command);

}  // namespace weft::cli
