#include "usage.h"

namespace weft::cli {

namespace {

constexpr std::string_view kOverview = R"(weft: real-time cloth simulation

Usage:
  weft run SCENE [options]        simulate a scene, write meshes and stats
  weft bench SCENE... [options]   time scenes after a warm-up, report per-stage medians
  weft view SCENE [options]       simulate a scene live in a window (Vulkan; builds with the renderer)
  weft edit [SCENE] [options]     the ImGui editor: play a scene and tune it live (builds with the editor)
  weft info                       version, backends, devices and build options
  weft help [COMMAND]             this text, or a command's options
  weft help scene-keys            every scene key with its unit, valid range, default and doc
  weft --version

SCENE is a scene file (assets/scenes/*.toml) or the bare name of one, e.g. 'flag'.
Run 'weft help run' for the options of a command.

Exit codes: 0 success, 1 error (bad scene, unreadable mesh, unwritable output),
            2 usage error, 3 the simulation produced NaN/Inf, 4 collisions left,
            5 a step failed mid-run (a device fault, out of device memory),
            130 interrupted by Ctrl-C or SIGTERM (the stats of the frames done are still written).
)";

constexpr std::string_view kRun = R"(Usage: weft run SCENE [options]

Simulates SCENE (a .toml file, or a name looked up in ./assets/scenes and in the source tree's
assets/scenes) and prints a summary: per-stage times, CG iterations, warnings.

Options:
  --backend NAME     simulation backend: cpu, cuda (see 'weft info'); default auto:
                     cuda when a GPU is present, else cpu
  --threads N        CPU worker threads, 0 = all cores; results do not depend on it
  --host-wait MODE   how the host waits for the GPU: spin (lowest latency, keeps a core
                     busy), block (sleeps, frees the core), yield, auto (the driver's choice, default)
  --gpus N           GPUs one world is split across (cuda backend; docs/multi-gpu.md); default: the
                     scene's solver.gpus (1)
  --device-memory-limit MIB
                     device memory the cuda backend may hold on each GPU; a scene needing more
                     fails at build with the bytes needed and free; default: the whole device
  --frames N         frames to simulate; default: the scene's 'frames'
  --out DIR          write a mesh per cloth per frame: DIR/frame_0000_<cloth>.ply (frame 0 = initial state)
  --format ply|obj   mesh format for --out; default ply
  --cache FILE.pc2   write the run as a PC2 point cache (Blender's Mesh Cache modifier, 3ds Max,
                     Maya) with its rest mesh beside it as FILE.obj; several cloths: FILE_<cloth>.pc2
  --cache FILE.glb   or as one glTF 2.0 binary: a mesh per cloth, its frames as animated morph targets
  --checkpoint DIR   write a checkpoint DIR/frame_NNNNNN.state at the end of the run (and where Ctrl-C
                     or SIGTERM stops it): everything that decides the next frame
  --checkpoint-every N
                     also every N frames (needs --checkpoint)
  --resume FILE      start from a checkpoint of the same scene (the CPU backend goes on bit for bit);
                     outputs are numbered from its frame on
  --capture egl|vulkan|none
                     render every frame headless to DIR/frame_0000.png (needs --out DIR; meshes
                     then only with --format), plus DIR/contact_sheet.png and DIR/capture.mp4
                     when ffmpeg is installed; egl: OpenGL 4.5 through EGL, vulkan: the Vulkan
                     renderer; default none
  --size WxH         picture size for --capture, pixels; default 1280x720
  --stats FILE.json  write run statistics as JSON (per-stage ms, CG iterations, per-frame series)
  --set KEY=VALUE    override a scene key, as if written in the file; repeatable
  --preset NAME      a solver preset (interactive, game, balanced, accurate, piled: docs/tuning.md)
                     under the --set keys
                     e.g. --set solver.substeps=4 --set 'wind.velocity=[2, 0, 0]'
  --quiet            no progress bar and no summary table (warnings are still printed)
  --check            after every frame, test every pair of triangles exactly for intersection
                     (costly; the count is in the summary and the stats JSON)
  -h, --help         this text

Exit code 3 means the solver met non-finite values (NaN/Inf) at least once; 4 that a collision
was left unresolved or --check found intersecting triangles; 5 that a step failed (a device fault,
out of device memory): the message names the stage, and the stats, meshes and cache hold the
frames before it.
)";

constexpr std::string_view kBench = R"(Usage: weft bench SCENE... [options]

For each scene: build, step --warmup frames untimed, then time --frames frames. Prints a table of
per-stage medians, frames per second, CG iterations per step and memory per triangle.

Options:
  --frames N         timed frames per scene; default 100
  --warmup N         untimed frames first; default 10
  --json FILE        write the results as a JSON array (one object per scene)
  --backend NAME     simulation backend: cpu, cuda; default auto (cuda when a GPU is present)
  --threads N        CPU worker threads, 0 = all cores
  --host-wait MODE   how the host waits for the GPU: spin (lowest latency, keeps a core
                     busy), block (sleeps, frees the core), yield, auto (the driver's choice, default)
  --gpus LIST        GPU counts to run every scene on, e.g. 1,2 (cuda backend); default: the
                     scene's solver.gpus (1)
  --device-memory-limit MIB
                     device memory the cuda backend may hold on each GPU; default: the whole device
  --set KEY=VALUE    override a scene key in every scene; repeatable
  --preset NAME      a solver preset (interactive, game, balanced, accurate, piled: docs/tuning.md)
                     under the --set keys
  -h, --help         this text
)";

constexpr std::string_view kView = R"(Usage: weft view SCENE [options]

Simulates SCENE live in a window drawn by the Vulkan renderer: the simulation runs at real time
(times --time-scale) whatever the display rate, and the title shows fps, simulated time and state.
Needs a display: set DISPLAY, or run under 'xvfb-run -a' where there is none.

Keys and mouse:
  left drag          orbit the camera round its target
  right/middle drag  pan
  scroll             zoom
  Space              pause / resume
  Right arrow, N     one step while paused
  + / -              time scale x2 / /2
  R                  reset the camera
  S                  screenshot to the --screenshot file, or weft_view_NNNN.png
  Esc, Q             quit

Options:
  --backend NAME     simulation backend: cpu, cuda (see 'weft info'); default auto
  --threads N        CPU worker threads, 0 = all cores
  --host-wait MODE   how the host waits for the GPU: spin (lowest latency, keeps a core
                     busy), block (sleeps, frees the core), yield, auto (the driver's choice, default)
  --gpus N           GPUs one world is split across (cuda backend; docs/multi-gpu.md); default: the
                     scene's solver.gpus (1)
  --set KEY=VALUE    override a scene key, as if written in the file; repeatable
  --preset NAME      a solver preset (interactive, game, balanced, accurate, piled: docs/tuning.md)
                     under the --set keys
  --frames N         quit after N displayed frames (scripted runs, tests)
  --screenshot FILE.png
                     write the last displayed frame to FILE.png at exit
  --size WxH         window size, pixels; default 1280x720
  --time-scale X     simulated seconds per wall second, 0.01 to 100; default 1
  --validation       enable the Vulkan validation layer; its messages go to stderr
  -h, --help         this text
)";

constexpr std::string_view kEdit = R"(Usage: weft edit [SCENE] [options]

Opens SCENE (default: flag) in the editor: the scene simulated live in a window with ImGui panels
to play, pause, step and reset it and to tune the solver, the materials of each cloth, collisions,
wind and gravity while it runs, with plots of the last 300 steps' timings, CG iterations,
residuals and contacts. Changes apply at the next step. Needs a display (or 'xvfb-run -a').
The panels' layout is kept in $XDG_CONFIG_HOME/weft/imgui.ini (else ~/.config/weft/imgui.ini).
See docs/editor.md.

Keys and mouse (when the panels do not have them):
  left drag          orbit the camera round its target
  right/middle drag  pan
  scroll             zoom
  Space              pause / resume
  Right arrow, N     one step (pauses)
  + / -              time scale x2 / /2
  R                  reset the camera
  S                  screenshot to the --screenshot file, or weft_edit.png
  Esc, Q             quit

Options:
  --backend NAME     simulation backend: cpu, cuda (see 'weft info'); default auto
  --threads N        CPU worker threads, 0 = all cores
  --host-wait MODE   how the host waits for the GPU: spin (lowest latency, keeps a core
                     busy), block (sleeps, frees the core), yield, auto (the driver's choice, default)
  --gpus N           GPUs one world is split across (cuda backend; docs/multi-gpu.md); default: the
                     scene's solver.gpus (1)
  --set KEY=VALUE    override a scene key, as if written in the file; repeatable
  --preset NAME      a solver preset (interactive, game, balanced, accurate, piled: docs/tuning.md)
                     under the --set keys
  --script FILE      run FILE's commands instead of waiting for a person, one step per
                     displayed frame (frame N, set KEY VALUE, expect KEY VALUE, pause, play,
                     step, reset, timescale X, screenshot FILE.png, quit; see docs/editor.md);
                     exit code 1 when an expect fails. No imgui.ini is read or written.
  --frames N         quit after N displayed frames
  --screenshot FILE.png
                     write the last displayed frame, panels included, to FILE.png at exit
  --size WxH         window size, pixels; default 1280x720
  --time-scale X     simulated seconds per wall second, 0.01 to 100; default 1
  --validation       enable the Vulkan validation layer; a message makes the exit code 1
  --ui-scale S       the panels' size, 0.5 to 4 (fonts and spacing); default: the monitor's scale
  -h, --help         this text
)";

constexpr std::string_view kInfo = R"(Usage: weft info

Prints the version, the compiled backends and the devices they run on, CPU threads and the build
options (CUDA, renderer, editor, mesh import).
)";

constexpr std::string_view kHelp = R"(Usage: weft help [COMMAND]
       weft help scene-keys [--markdown]

Prints the overview, or the options of COMMAND (run, bench, view, edit, info).
'scene-keys' lists every key a scene file may hold (the keys --set and the editor's scripts
take) with its type, unit, default, valid range, what a change takes and a line of doc;
--markdown prints them as the tables of docs/scene-format.md.
)";

}  // namespace

std::string_view usage_text(std::string_view topic) {
    if (topic == "run") return kRun;
    if (topic == "bench") return kBench;
    if (topic == "view") return kView;
    if (topic == "edit") return kEdit;
    if (topic == "info") return kInfo;
    if (topic == "help") return kHelp;
    return kOverview;
}

std::string usage_hint(std::string_view command) {
    if (command.empty()) return "Try 'weft help'.";
    return "Try 'weft " + std::string(command) + " --help'.";
}

}  // namespace weft::cli
