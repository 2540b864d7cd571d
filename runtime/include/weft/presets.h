#pragma once
/// @file
/// Presets: named sets of parameter values, applied through the parameter table (the editor's
/// menus, docs/editor.md "Presets"; `weft run --preset`, docs/tuning.md). Material presets are
/// starting points for common fabrics; solver presets are points on the speed/accuracy trade
/// (docs/results.md measures them).
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace weft {

struct WorldDesc;

struct Preset {
    std::string name;         ///< "silk", "interactive"
    std::string description;  ///< one line, shown in the tooltip
    /// Parameter keys and values. Material presets name the field after "material."
    /// ("stretch_stiffness"); solver presets give whole keys ("solver.substeps").
    std::vector<std::pair<std::string, double>> values;
    /// Material presets: the fabric's areal density, kg/m². It is cooked into the masses, so
    /// applying the preset re-cooks the cloth when it differs (0: leave the density).
    double density = 0.0;
};

/// Fabrics: cotton (the Material defaults), silk, denim, leather, rubber sheet.
[[nodiscard]] std::span<const Preset> material_presets();
/// Solver settings: interactive, game, balanced (the SolverSettings defaults), accurate, piled.
[[nodiscard]] std::span<const Preset> solver_presets();
/// The preset called `name` in `presets`, or nullptr.
[[nodiscard]] const Preset* find_preset(std::span<const Preset> presets, std::string_view name);
/// "cotton, silk, …", for messages.
[[nodiscard]] std::string preset_names(std::span<const Preset> presets);
/// A solver preset as scene overrides ("solver.substeps=4", `solver.precision="double"`), in the
/// form `load_scene` and `--set` take: what `weft run --preset NAME` puts before its `--set`s.
[[nodiscard]] std::vector<std::string> preset_overrides(const Preset& preset);
/// The overrides of solver preset `name`; throws weft::Error naming the presets when there is none.
[[nodiscard]] std::vector<std::string> solver_preset_overrides(std::string_view name);
/// Sets solver preset `name`'s values in `desc` (a world built in code: `World world(desc)`);
/// throws weft::Error naming the presets when there is none.
void apply_solver_preset(WorldDesc& desc, std::string_view name);

}  // namespace weft
