#pragma once
// `--set key=value` overrides of a parsed scene document (scene.h, docs/scene-format.md).

#include <toml++/toml.h>

#include <span>
#include <string>

namespace weft::scene_toml {

/// Applies each "dotted.key=value" override to `document` as if it had been written in the file.
/// The value is parsed as TOML (a bare word such as `float` is taken as a string). A path element
/// that meets an array of tables selects an entry by index (`cloth.0`) or by its `name`
/// (`cloth.flag`). Nodes inserted here carry the source label "--set 'key=value'" so that the
/// validator reports problems in them against the override rather than the file. Throws
/// `weft::Error` for malformed overrides and for entries that do not exist.
void apply_overrides(toml::table& document, std::span<const std::string> overrides);

}  // namespace weft::scene_toml
