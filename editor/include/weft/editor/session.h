#pragma once
/// @file
/// What the editor edits: the scene as loaded, the world built from it, the frame loop that plays
/// it, the parameter table and the stats history. Panels, keys and scripts all change it through
/// this object, so the three share one code path.
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "weft/backend.h"
#include "weft/frame_loop.h"
#include "weft/scene.h"
#include "weft/world.h"

#include "weft/editor/parameters.h"
#include "weft/editor/stats_history.h"
#include "weft/editor/vertex_picking.h"

namespace weft::editor {

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
    /// A new grid resolution for a cloth (the Mesh panel, the script's `cells`): applied by the
    /// editor's loop after the panels with Session::recook_grid.
    struct GridChange {
        std::string cloth;  ///< the `[[cloth]]` table's name
        int cells_x = 0, cells_y = 0;
    };
    std::optional<GridChange> recook;
    /// The mouse on the cloth (Ctrl+drag grabs, Shift+click pins; the script's grab, drag, release
    /// and pin), at picture pixels: applied in order by the editor's loop, which has the camera.
    struct MouseAction {
        enum class Kind : unsigned char { grab, drag, release, pin } kind = Kind::grab;
        double x = 0.0, y = 0.0;  ///< pixels from the picture's top-left corner
    };
    std::vector<MouseAction> mouse;
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
    void set_message(std::string message) { message_ = std::move(message); }

    /// Builds the world again from the scene (time 0, the initial state), keeping the tuned
    /// settings and materials, the pause state and the time scale; clears the stats.
    void reset();
    [[nodiscard]] int resets() const { return resets_; }
    /// Gives the grid cloth `cloth` (a `[[cloth]]` table's name) cells_x × cells_y cells ([1, 4096]
    /// each). The live world cannot take this: the fabric is cooked again, so the world is rebuilt
    /// from the changed scene as reset() does, keeping what was tuned. Returns the rebuild's wall
    /// time, ms, and says what changed in message(). Throws weft::Error, the session unchanged, for
    /// an unknown cloth, a cloth from a mesh file, or cells out of range.
    double recook_grid(const std::string& cloth, int cells_x, int cells_y);
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
    SceneDesc scene_;
    std::string backend_;
    BackendOptions options_;
    std::unique_ptr<World> world_;
    std::unique_ptr<FrameLoop> loop_;
    ParameterTable parameters_;
    StatsHistory history_;
    PlayRequests requests_;
    RecordingStatus recording_;
    std::map<std::string, std::int64_t> applied_at_;
    std::int64_t steps_before_reset_ = 0;  ///< so that step counts keep rising across resets
    int resets_ = 0;
    std::string message_;
    std::function<void()> before_rebuild_;
    std::optional<Vec3d> grab_anchor_;
};

}  // namespace weft::editor
