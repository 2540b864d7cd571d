#pragma once
/// @file
/// Presets: named sets of parameter values, applied through the parameter table like any widget
/// (docs/editor.md, "Presets"). Material presets are starting points for common fabrics; solver
/// presets trade speed for accuracy (docs/results.md measures them).
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace weft::editor {

struct Preset {
    std::string name;         ///< "silk", "fast"
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
/// Solver settings: fast, balanced (the SolverSettings defaults), accurate.
[[nodiscard]] std::span<const Preset> solver_presets();
/// The preset called `name` in `presets`, or nullptr.
[[nodiscard]] const Preset* find_preset(std::span<const Preset> presets, std::string_view name);
/// "cotton, silk, …", for messages.
[[nodiscard]] std::string preset_names(std::span<const Preset> presets);

}  // namespace weft::editor
