#pragma once
/// @file
/// The editor's main loop (`weft edit`, docs/editor.md): the scene simulated in the live window
/// with the ImGui panels over it, played by weft::FrameLoop; with a script, driven by it instead of
/// a person, one step per displayed frame so that nothing depends on timing.
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "weft/backend_options.h"
#include "weft/scene.h"
#include "weft/world.h"

#include "weft/editor/script.h"

namespace weft::editor {

/// A scene opened from the Scenes panel or a script's `open`.
struct OpenedScene {
    SceneDesc scene;
    std::unique_ptr<World> world;  ///< built on EditorOptions::backend
};

struct EditorOptions {
    std::string backend = "cpu";  ///< resolved backend name; reset() rebuilds the world on it
    BackendOptions backend_options{};
    int width = 1280, height = 720;  ///< window size, screen pixels
    double time_scale = 1.0;         ///< [0.01, 100]
    float ui_scale = 0.0F;           ///< panels' size, [0.5, 4]; 0: the monitor's content scale
    bool validation = false;         ///< Vulkan validation layer; any message makes the run fail
    std::optional<int> frames;       ///< quit after this many displayed frames
    std::filesystem::path screenshot;  ///< the last displayed frame as PNG at exit (empty: none)
    std::optional<Script> script;      ///< scripted mode (checked against the scene's parameters here)
    /// Where ImGui keeps the layout; empty: nowhere. Scripted runs never use one.
    std::filesystem::path ini_file;
    /// Opens a scene by name (from `scene_names`) or file, as `weft edit SCENE` would; throws
    /// weft::Error saying why not. Unset: the Scenes panel lists nothing and `open` fails.
    std::function<OpenedScene(const std::string&)> open_scene;
    std::vector<std::string> scene_names;  ///< the Scenes panel's list
};

/// Runs the editor on `world`, built from `scene` on `options.backend`, until the window closes,
/// `options.frames` frames were shown, or the script ends. A summary on `out`; script failures and
/// validation messages on `err`. Returns 0, or 1 when an `expect` failed or validation reported
/// messages. Throws weft::Error for a bad script (before the window opens), no display, or a
/// renderer failure.
int run_editor(const SceneDesc& scene, std::unique_ptr<World> world, EditorOptions options, std::ostream& out,
               std::ostream& err);

/// The default place of the layout file: $XDG_CONFIG_HOME/weft/imgui.ini, else
/// ~/.config/weft/imgui.ini (the folder is created); empty when neither variable is set or the
/// folder cannot be made.
[[nodiscard]] std::filesystem::path default_ini_file();

}  // namespace weft::editor
