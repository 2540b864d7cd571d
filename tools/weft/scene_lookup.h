#pragma once
/// @file
/// Finding a scene from what the user typed: a path, or a bare name such as `flag` that is looked up
/// in the scene folders (./assets/scenes, the source tree next to the binary, the tree it was built from).

#include <filesystem>
#include <string_view>
#include <vector>

namespace weft::cli {

/// Folders searched for bare scene names, in order, existing or not.
[[nodiscard]] std::vector<std::filesystem::path> scene_folders();

/// Resolves `name` against `folders`: an existing file as given (with `.toml` appended if missing),
/// else, for a name without a directory part, `folder/name.toml` in each folder. Throws `weft::Error`
/// naming `name`, the places tried and the scenes that do exist when nothing matches.
[[nodiscard]] std::filesystem::path find_scene(std::string_view name,
                                               const std::vector<std::filesystem::path>& folders);
[[nodiscard]] inline std::filesystem::path find_scene(std::string_view name) {
    return find_scene(name, scene_folders());
}

/// Scene names (file stems) in `folder`, sorted; empty if it does not exist.
[[nodiscard]] std::vector<std::string> scene_names(const std::filesystem::path& folder);

}  // namespace weft::cli
