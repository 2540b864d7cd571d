#pragma once
/// @file
/// What the editor edits: the scene as loaded, the world built from it, the frame loop that plays
/// it, the parameter table and the stats history. Panels, keys and scripts all change it through
/// this object, so the three share one code path.
#include <array>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "weft/backend_options.h"
#include "weft/frame_loop.h"
#include "weft/scene.h"
#include "weft/world.h"

#include "weft/editor/parameters.h"
#include "weft/editor/stats_history.h"
#include "weft/editor/vertex_picking.h"

namespace weft::editor {

/// What a re-cook changes on one `[[cloth]]` table: what is cooked into the fabric, so that the live
/// world cannot take it (docs/editor.md, "Re-cooking"). Unset fields stay as they are.
struct ClothRecook {
    std::optional<std::array<int, 2>> cells;  ///< grid resolution, [1, 4096] per side (grids only)
    std::optional<double> density;            ///< areal density, kg/m², (0, 100]
    std::optional<double> scale;              ///< mesh-file scale, (0, 1e6] (mesh files only)
    std::optional<bool> flat_rest_bending;    ///< rest dihedral angles 0 (flat) instead of the mesh's
    [[nodiscard]] bool empty() const { return !cells && !density && !scale && !flat_rest_bending; }
};

/// Play-control requests from keys and scripts, consumed by the play panel (which applies them
/// with the same calls as its buttons).
struct PlayRequests {
    std::optional<bool> paused;
    int single_steps = 0;
    bool reset = false;
    std::optional<double> time_scale;
    /// A scene to open (a name from the browser or a file), taken by the editor's loop after the
    /// panels: the Scenes panel and the script's `open`.
    std::optional<std::string> open;
    /// Start recording every displayed frame into this folder / stop it (the play panel, the
    /// script's `record` and `stop`); taken by the editor's loop.
    std::optional<std::filesystem::path> record;
    bool stop_recording = false;
    /// A re-cook of a cloth (the Mesh panel, the script's `cells` and `cook`): applied by the
    /// editor's loop after the panels with Session::recook.
    struct Recook {
        std::string cloth;  ///< the `[[cloth]]` table's name
        ClothRecook change;
    };
    std::optional<Recook> recook;
    /// A preset to apply (the preset menus, the script's `preset`): taken by the panels, which
    /// apply it with Session::apply_preset.
    struct PresetChoice {
        std::string target;  ///< "solver", or a `[[cloth]]` table's name for a material preset
        std::string name;
    };
    std::optional<PresetChoice> preset;
    /// The mouse on the cloth (Ctrl+drag grabs, Shift+click pins; the script's grab, drag, release
    /// and pin), at picture pixels: applied in order by the editor's loop, which has the camera.
    struct MouseAction {
        enum class Kind : unsigned char { grab, drag, release, pin } kind = Kind::grab;
        double x = 0.0, y = 0.0;  ///< pixels from the picture's top-left corner
    };
    std::vector<MouseAction> mouse;
};

/// What the viewport draws over the shaded scene (the View panel, the script's `show`;
/// docs/editor.md, "Display").
struct DisplayOptions {
    bool wireframe = false;  ///< the cloth's triangle edges
    bool normals = false;    ///< each vertex's normal, as a short line
    bool contacts = false;   ///< vertices within their contact distance of an analytic collider, and in a cloth contact
    bool pins = false;       ///< pinned vertices (the grab's spring is drawn whenever a vertex is grabbed)
};

/// The viewport recording, as the play panel shows it.
struct RecordingStatus {
    bool active = false;
    std::filesystem::path folder;  ///< of the current or the last recording
    int frames = 0;                ///< written to it so far
    std::string video;             ///< the MP4 of the last recording, or why there is none
};

class Session {
public:
    /// `world` was built from `scene` on `backend` with `options`; reset() builds it again that way.
    Session(SceneDesc scene, std::string backend, BackendOptions options, std::unique_ptr<World> world,
            double time_scale);

    [[nodiscard]] const SceneDesc& scene() const { return scene_; }
    [[nodiscard]] World& world() { return *world_; }
    [[nodiscard]] FrameLoop& loop() { return *loop_; }
    [[nodiscard]] ParameterTable& parameters() { return parameters_; }
    [[nodiscard]] StatsHistory& history() { return history_; }
    [[nodiscard]] PlayRequests& requests() { return requests_; }
    [[nodiscard]] RecordingStatus& recording() { return recording_; }
    [[nodiscard]] DisplayOptions& display() { return display_; }

    /// Sets `p` to `value` (clamped to its range) on the world — the one setter of panels and
    /// scripts. Remembers the step count, so that `expect` knows when a step has used it.
    double apply(const Parameter& p, double value);
    /// Steps taken before `key` was last applied, or nothing if it never was.
    [[nodiscard]] std::optional<std::int64_t> applied_at(const std::string& key) const;

    /// Saves the scene with what was tuned live (settings, materials) to `path` (docs/scene-format.md,
    /// "Saving a scene"); loading it gives the tuned scene. Throws weft::Error naming the file.
    void save(const std::filesystem::path& path) const;
    /// The file the Save button writes: NAME_tuned.toml next to the scene file.
    [[nodiscard]] std::filesystem::path default_save_path() const;

    /// The last file operation's outcome, shown under the play controls.
    [[nodiscard]] const std::string& message() const { return message_; }
    void set_message(std::string message) {
        message_ = std::move(message);
        ++messages_;
    }
    /// How many messages were said so far: a script prints each new one.
    [[nodiscard]] int messages() const { return messages_; }

    /// Builds the world again from the scene (time 0, the initial state), keeping what was tuned
    /// (what Save writes: settings, materials, motions, colliders, pins made or removed live, those
    /// at the cloth's start position), the pause state and the time scale; clears the stats.
    void reset();
    [[nodiscard]] int resets() const { return resets_; }
    /// Re-cooks the `[[cloth]]` table `cloth` with `change` (a new grid resolution, density, mesh
    /// scale or rest bending). The live world cannot take this: the fabric is cooked again, so the
    /// world is rebuilt from the changed scene, keeping what was tuned (pins made live on this cloth
    /// are dropped when its cells change: they name vertices of the old mesh; message() says so).
    /// Returns the rebuild's
    /// wall time, ms, and says what changed in message(). Throws weft::Error, the session unchanged,
    /// for an unknown cloth, cells for a mesh file or a scale for a grid, or a value out of range.
    double recook(const std::string& cloth, const ClothRecook& change);
    /// Applies preset `name` (presets.h) to `target`: "solver" (solver_presets), or the cloths of
    /// the `[[cloth]]` table `target` (material_presets; every copy of a repeated table alike). Each
    /// value goes through apply(), as a widget's would; a material preset whose density differs from
    /// the cloth's asks for a re-cook (requests().recook), which the editor's loop runs after the
    /// panels. Says what it did in message(). Throws weft::Error naming an unknown target or preset.
    void apply_preset(const std::string& target, const std::string& name);
    /// Starts pulling the picked vertex with a spring that holds its whole cloth within 2 cm of the
    /// target (weft/grab.h, grab_stiffness_for) and is ten times as stiff as the cloth's membrane
    /// (stretch stiffness, N/m), the target first where the vertex is. Replaces a grab in progress.
    void grab(const VertexPick& pick);
    /// Moves the grab's target (m); nothing without a grab.
    void drag_to(const Vec3d& target);
    /// Lets go of the grab (if any).
    void release_grab();
    /// The grab in progress: the point its drag plane goes through (the vertex where it was picked).
    [[nodiscard]] const std::optional<Vec3d>& grab_anchor() const { return grab_anchor_; }
    /// How far the grabbed vertex is from the grab's target now, m; nothing without a grab.
    [[nodiscard]] std::optional<double> grab_distance();
    /// Pins the vertex where it is, or unpins it (World::pin/unpin): the backend is rebuilt at the
    /// next step, keeping the state, so whatever holds on to the world lets go first (before_rebuild).
    /// Returns true when it is pinned now; says so, with the rebuild's time, in message().
    bool toggle_pin(std::size_t cloth, std::uint32_t vertex);

    /// Called by reset() before the old world goes: whatever holds on to it (the editor's ClothFeed,
    /// which the backend writes the renderer's buffers through) lets go here.
    void set_before_rebuild(std::function<void()> callback) { before_rebuild_ = std::move(callback); }

private:
    /// reset() without taking what was tuned into the scene first: the world built from scene_,
    /// the live settings and materials carried over.
    void rebuild();

    SceneDesc scene_;
    /// Each cloth's pin rules as the file wrote them: what a re-cook goes back to (pins made live
    /// name vertices of the old mesh).
    std::vector<std::vector<PinSelection>> file_pins_;
    std::string backend_;
    BackendOptions options_;
    std::unique_ptr<World> world_;
    std::unique_ptr<FrameLoop> loop_;
    ParameterTable parameters_;
    StatsHistory history_;
    PlayRequests requests_;
    RecordingStatus recording_;
    DisplayOptions display_;
    std::map<std::string, std::int64_t> applied_at_;
    std::int64_t steps_before_reset_ = 0;  ///< so that step counts keep rising across resets
    int resets_ = 0;
    std::string message_;
    int messages_ = 0;
    std::function<void()> before_rebuild_;
    std::optional<Vec3d> grab_anchor_;
};

}  // namespace weft::editor
