// `weft edit [SCENE]`: the ImGui editor (weft/editor/editor.h) on a scene found and loaded as
// `weft run` does.
#include "weft/error.h"

#include "commands.h"
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
    editor.width = options.width;
    editor.height = options.height;
    editor.time_scale = options.time_scale;
    editor.validation = options.validation;
    editor.frames = options.frames;
    editor.screenshot = options.screenshot;
    editor.ini_file = editor::default_ini_file();
    if (loaded.desc.name.empty()) loaded.desc.name = options.scene;
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
