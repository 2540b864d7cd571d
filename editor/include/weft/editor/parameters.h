#pragma once
/// @file
/// The editor's live parameters: every knob a panel shows, with its key, unit and valid range
/// (one row per live key of the runtime's parameter table, weft/parameters.h, a vector's by
/// component), and how it is read from and written to a `World`. The panels draw their
/// widgets from this table, and a script's `set KEY VALUE` goes through the same table: it leaves a
/// pending value that the panel code picks up on its next frame and applies with the same setter a
/// widget uses (`ParameterTable::take_pending`), so the script exercises the UI's code path.
#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "weft/stats.h"
#include "weft/world.h"

namespace weft::editor {

enum class ParameterKind : unsigned char {
    real,     ///< a number, edited by a slider (logarithmic where `log_scale`)
    integer,  ///< a whole number
    boolean,  ///< a checkbox; the value is 0 or 1
    choice,   ///< one of `choices`; the value is its index
};

struct Parameter {
    std::string key;    ///< what scripts name it by, as in the scene file: "solver.substeps"
    std::string panel;  ///< "solver", "materials", "collision", "world", "motions", "colliders"
    std::string group;  ///< a heading inside the panel ("" for none): "cloth flag", "motion spin", "collider pole (capsule)"
    std::string label;  ///< the widget's label
    std::string unit;   ///< SI unit, "" when dimensionless
    std::string hint;   ///< shown in the tooltip: the parameter's doc (what a special value means, "0: automatic")
    ParameterKind kind = ParameterKind::real;
    double min = 0.0, max = 1.0;  ///< valid range, inclusive (the slider's, where the table gives one)
    bool log_scale = false;       ///< slider in log space (ranges over many decades)
    std::vector<std::string> choices;
    std::function<double(const World&)> get;
    std::function<void(World&, double)> set;  ///< called with a value already clamped to [min, max]
    /// Where set and false for the world as it is, the panels leave the row out (a collider's size
    /// that its present shape does not have); a script may still set it.
    std::function<bool(const World&)> shown;
    /// What the last step says it used, where a step reports it (StepStats::substeps); checked by
    /// a script's `expect` once a step has run since the value was applied.
    std::function<std::optional<double>(const StepStats&)> observed;
};

/// The parameters of one world: solver, collision, wind and gravity, and per cloth its material.
class ParameterTable {
public:
    /// Builds the table for `world`'s settings, cloths and motions (materials keyed by the cloth's
    /// name: "cloth.flag.material.stretch_stiffness"; "cloth.0.material…" finds the same; motions by
    /// `motion_names`, the scene's `[[motion]]` names in order: "motion.spin.angular_velocity.y",
    /// "motion.0…" finds the same, and a motion without a name is keyed by its index).
    /// Analytic colliders by name ("collider.pole.radius", "collider.0.radius" finds the same): their
    /// shape (World::set_collider_shape), the sizes of every analytic shape (those of the present
    /// shape shown), friction, and the position of one that follows no motion.
    /// `collider_motions`: per collider, the name of the motion it follows (SceneDesc::collider_motions),
    /// so that a motion's change moves its colliders with it.
    explicit ParameterTable(const World& world, std::span<const std::string> motion_names = {},
                            std::span<const std::string> collider_motions = {});

    [[nodiscard]] const std::vector<Parameter>& parameters() const { return parameters_; }
    /// The parameter for `key`, or nullptr.
    [[nodiscard]] const Parameter* find(std::string_view key) const;

    /// Parses `text` as a value of `p` (numbers; true/false/on/off/1/0; a choice's name) and checks
    /// its range. Throws weft::Error naming the key, the text and the range.
    [[nodiscard]] static double parse_value(const Parameter& p, std::string_view text);
    /// `value` for display: integers without decimals, booleans as true/false, choices by name.
    [[nodiscard]] static std::string format_value(const Parameter& p, double value);
    /// Clamps `value` to the range (and rounds integers) and sets it on `world`; returns what was set.
    static double apply(const Parameter& p, World& world, double value);

    /// Queues `value` for `key` (scripts). Throws weft::Error for an unknown key.
    void set_pending(std::string_view key, double value);
    /// The panel code's side: the queued value for `p`, removed from the queue.
    [[nodiscard]] std::optional<double> take_pending(const Parameter& p);
    [[nodiscard]] bool has_pending() const { return !pending_.empty(); }

private:
    std::vector<Parameter> parameters_;
    std::map<std::string, double, std::less<>> pending_;
    std::map<std::string, std::size_t, std::less<>> aliases_;  ///< "cloth.0.material.x" → index
};

}  // namespace weft::editor
