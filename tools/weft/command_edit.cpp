// `weft edit [SCENE]`: the ImGui editor (weft/editor/editor.h) on a scene found and loaded as
// `weft run` does.
#include "weft/error.h"

#include <filesystem>

#include "commands.h"
#include "scene_lookup.h"
#include "world_setup.h"

#if WEFT_HAVE_EDITOR
#include "weft/editor/editor.h"
#include "weft/editor/script.h"
#endif

namespace weft::cli {

#if WEFT_HAVE_EDITOR

int edit_command(const EditOptions& options, std::ostream& out, std::ostream& err) {
    require_backend("edit", options.sim.backend);
    editor::EditorOptions editor;
    // The script is read and parsed before anything is built, so that a typo costs no start-up.
    if (!options.script.empty()) editor.script = editor::read_script(options.script);
    LoadedScene loaded = load_world(options.scene, options.sim);
    editor.backend = resolve_backend(options.sim.backend);
    editor.backend_options.threads = options.sim.threads;
    editor.backend_options.host_wait = options.sim.host_wait;
    editor.width = options.width;
    editor.height = options.height;
    editor.time_scale = options.time_scale;
    editor.ui_scale = options.ui_scale;
    editor.validation = options.validation;
    editor.frames = options.frames;
    editor.screenshot = options.screenshot;
    editor.ini_file = editor::default_ini_file();
    if (loaded.desc.name.empty()) loaded.desc.name = options.scene;
    // The Scenes panel: every scene in the first scene folder that exists, opened as this one was
    // (same backend, threads and --set overrides).
    for (const std::filesystem::path& folder : scene_folders())
        if (std::filesystem::is_directory(folder)) {
            editor.scene_names = scene_names(folder);
            break;
        }
    editor.open_scene = [sim = options.sim](const std::string& scene) {
        LoadedScene l = load_world(scene, sim);
        if (l.desc.name.empty()) l.desc.name = scene;
        return editor::OpenedScene{std::move(l.desc), std::move(l.world)};
    };
    return editor::run_editor(loaded.desc, std::move(loaded.world), std::move(editor), out, err);
}

#else

int edit_command(const EditOptions& /*options*/, std::ostream& /*out*/, std::ostream& /*err*/) {
    throw Error(
        "edit: this build has no editor (configure with -DWEFT_EDITOR=ON, which needs the renderer and "
        "the libimgui-dev package of tools/deps.sh)");
}

#endif

}  // namespace weft::cli
