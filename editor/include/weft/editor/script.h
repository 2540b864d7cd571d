#pragma once
/// @file
/// The editor's scripts (`weft edit --script FILE`): a list of commands, one per line, that drive
/// the editor without a person and without depending on timing (docs/editor.md, "Scripts").
///
///     # comment; blank lines are ignored
///     frame 5                      run until 5 frames have been displayed
///     set solver.substeps 4        set a parameter through the panels' code path, at the next frame
///     expect solver.substeps 4     the world (and, once it stepped, the step) uses that value
///     pause | play | step | reset  the play controls (step: pause, then one step)
///     timescale 0.5                the play controls' time scale, [0.01, 100]
///     screenshot out/edit.png      the last displayed frame, with the panels, as PNG
///     save out/tuned.toml          the scene with what was tuned, as the Save button writes it
///     record out/rec               record every displayed frame to out/rec/frame_NNNN.png
///     stop                         stop recording (and make out/rec/capture.mp4 with ffmpeg)
///     cells flag 80 48             re-cook a grid cloth at 80×48 cells, as the Mesh panel does
///     cook flag density 0.3        re-cook a cloth with another density (kg/m²), mesh-file scale,
///                                  or flat_rest_bending (true/false), as the Mesh panel does
///     preset solver fast           apply a preset, as the preset menus do: "solver" or a cloth's
///     preset flag silk             name, then the preset's name (docs/editor.md, "Presets")
///     show wireframe on            a display toggle: wireframe, normals, contacts, pins (on/off)
///     grab 640 300                 Ctrl+press at picture pixel (640, 300): grab the cloth vertex
///                                  under it (the script fails where there is none)
///     drag 640 200                 move the mouse there while grabbing: the grab's target follows
///     held 0.05                    the grabbed vertex is within 0.05 m of the grab's target
///     release                      let go of the grab
///     pin 640 300                  Shift+click: pin the vertex under the pixel where it is (or unpin it)
///     open layers                  open a scene (a name from the browser, or a file), as the
///                                  Scenes panel does; the commands after it act on that scene
///     quit                         end (so does the end of the script)
///
/// Parsing checks the commands and their argument counts and numbers; parameter keys and values
/// are checked against the scene's parameters before the window opens (`check_script`), those after
/// an `open` against the opened scene's when they run (`check_command`).
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "weft/editor/parameters.h"

namespace weft::editor {

struct ScriptCommand {
    enum class Kind : unsigned char {
        frame, set, expect, pause, play, step, reset, timescale, screenshot, save, open, record, stop, cells,
        cook, preset, show, grab, drag, held, release, pin, quit
    };
    Kind kind = Kind::quit;
    int line = 0;         ///< 1-based line in the script
    int frame = 0;        ///< frame: the displayed-frame count to reach
    /// set, expect: the parameter's key; cells, cook: the cloth; preset: the target; show: the toggle
    std::string key;
    /// set, expect: the value as written; screenshot, save, record: the path; open: the scene;
    /// cook: the field (density, scale, flat_rest_bending); preset: the preset's name
    std::string text;
    double number = 0.0;  ///< timescale, cook; set, expect: the value once checked (check_script); show: 0 or 1
    bool checked = false;  ///< set, expect: key and value checked against the scene's parameters
    int cells_x = 0, cells_y = 0;  ///< cells: the grid resolution (the cloth's name is `key`)
    double x = 0.0, y = 0.0;       ///< grab, drag, pin: the picture pixel; held: x is the distance, m
};

struct Script {
    std::string name;  ///< the file, for messages
    std::vector<ScriptCommand> commands;
};

/// Parses `text` (named `name` in messages). Throws weft::Error "NAME:LINE: WHAT" for an unknown
/// command, a wrong number of arguments, a bad number, or a `frame` that does not move forward.
[[nodiscard]] Script parse_script(std::string_view text, const std::string& name);
/// Reads and parses `file`; throws weft::Error when it cannot be read.
[[nodiscard]] Script read_script(const std::filesystem::path& file);
/// Checks every `set`/`expect` key and value before the first `open` against `table` and stores the
/// values (`number`). Throws weft::Error "NAME:LINE: …" naming the first bad one.
void check_script(Script& script, const ParameterTable& table);
/// Checks one `set`/`expect` command of `script_name` against `table` (the scene open when it
/// runs), as check_script does.
void check_command(const std::string& script_name, ScriptCommand& command, const ParameterTable& table);

}  // namespace weft::editor
