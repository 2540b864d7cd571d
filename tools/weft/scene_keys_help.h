#pragma once
/// @file
/// `weft help scene-keys`: every key of a scene file, from the parameter table (weft/parameters.h),
/// as text for the terminal or as the Markdown tables of docs/scene-format.md (which are generated
/// from it; tests/cli/test_scene_keys_doc.cpp holds the two equal).

#include <string>
#include <string_view>
#include <vector>

namespace weft::cli {

/// The help topic's name: `weft help scene-keys`.
inline constexpr std::string_view kSceneKeysTopic = "scene-keys";

/// The sections of the parameter table in its order ("scene", "solver", …, "cloth.material", …).
[[nodiscard]] std::vector<std::string_view> scene_key_sections();

/// Every key with its type, unit, default, valid values, what a change takes and its doc, section
/// by section.
[[nodiscard]] std::string scene_keys_text();

/// The Markdown table of one section's keys, as docs/scene-format.md has it between
/// `scene_keys_begin(section)` and `kSceneKeysEnd`.
[[nodiscard]] std::string scene_keys_markdown(std::string_view section);
/// The comment line that opens a generated table in docs/scene-format.md.
[[nodiscard]] std::string scene_keys_begin(std::string_view section);
inline constexpr std::string_view kSceneKeysEnd = "<!-- end of generated table -->";

/// Every section's table between its markers: what `weft help scene-keys --markdown` prints, to be
/// pasted into docs/scene-format.md when the table changes.
[[nodiscard]] std::string scene_keys_markdown();

}  // namespace weft::cli
