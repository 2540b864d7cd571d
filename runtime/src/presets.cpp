// The presets (weft/presets.h). Stretch stiffness is Young's modulus times thickness (N/m),
// bending stiffness the plate stiffness (N·m), both of the orders reported for woven fabrics and
// sheets; they are starting points to tune from, not measured fabrics.
#include "weft/presets.h"

#include <array>
#include <charconv>
#include <cmath>

#include "weft/error.h"

#include "weft/parameters.h"
#include "weft/settings.h"

namespace weft {
namespace {

Preset fabric(std::string name, std::string description, double stretch, double poisson, double bending,
              double damping, double drag, double lift, double friction, double density) {
    return Preset{std::move(name),
                  std::move(description),
                  {{"stretch_stiffness", stretch},
                   {"poisson_ratio", poisson},
                   {"bending_stiffness", bending},
                   {"damping_stiffness", damping},
                   {"drag_coefficient", drag},
                   {"lift_coefficient", lift},
                   {"friction", friction}},
                  density};
}

/// The real-time presets' SolverSettings::split_stretch: above the 1.5-2x that a running character's
/// legs stretch a skirt to in a step, below the 3x of a banner it drags open (whose split must start
/// before the drag has taken hold: at 2.5 the banner still tore, docs/results.md).
constexpr double kRealTimeSplitStretch = 2.0;

/// The preconditioner a solver preset sets (the index in the parameter's choices).
enum class PresetPreconditioner { Jacobi = 0, Mas = 1, Auto = 2 };

Preset solver(std::string name, std::string description, int substeps, int newton, double tolerance, int cap,
              bool single, bool projected, bool offset_contact = false,
              PresetPreconditioner preconditioner = PresetPreconditioner::Auto, double ccd_time_tolerance = 0.0,
              double split_stretch = 0.0) {
    return Preset{std::move(name),
                  std::move(description),
                  {{"solver.substeps", substeps},
                   {"solver.newton_iterations", newton},
                   {"solver.cg_tolerance", tolerance},
                   {"solver.cg_max_iterations", cap},
                   {"solver.precision", single ? 0.0 : 1.0},
                   {"solver.hessian", projected ? 1.0 : 0.0},
                   // Every solver preset sets the contact mode, so that leaving "piled" returns to the
                   // default one (the index in the parameter's choices: ccd_zones, offset).
                   {"collision.mode", offset_contact ? 1.0 : 0.0},
                   // And the preconditioner, for the same reason (the default: auto).
                   {"solver.preconditioner", static_cast<double>(preconditioner)},
                   // And the CCD's time tolerance (0: the backend's CCD default).
                   {"collision.ccd_time_tolerance", ccd_time_tolerance},
                   // And the splitting of overstretched substeps (0: off).
                   {"solver.split_stretch", split_stretch}},
                  0.0};
}

// The default of scene key `key`: "cotton" and "balanced" are the defaults, read where they are
// declared (the structs, through the parameter table) rather than written here again.
double default_of(std::string_view key) { return parameter_default_number(*find_parameter(key)); }

}  // namespace

std::span<const Preset> material_presets() {
    static const std::array<Preset, 5> presets{
        fabric("cotton", "light woven cotton (the defaults)", default_of("cloth.material.stretch_stiffness"),
               default_of("cloth.material.poisson_ratio"), default_of("cloth.material.bending_stiffness"),
               default_of("cloth.material.damping_stiffness"), default_of("cloth.material.drag_coefficient"),
               default_of("cloth.material.lift_coefficient"), default_of("cloth.material.friction"),
               default_of("cloth.density")),
        fabric("silk", "thin and soft: low bending, flutters", 2.0e3, 0.3, 1.0e-6, 5.0e-4, 1.2, 0.4, 0.2, 0.06),
        fabric("denim", "heavy twill: stiffer, folds in wide curves", 2.0e4, 0.25, 1.0e-4, 2.0e-3, 0.9, 0.2, 0.5, 0.4),
        fabric("leather", "stiff and heavy, barely stretches", 1.0e5, 0.4, 1.0e-3, 3.0e-3, 0.8, 0.1, 0.6, 0.9),
        fabric("rubber", "a rubber sheet: stretchy, nearly incompressible, grippy", 1.0e3, 0.49, 1.0e-4, 1.0e-3, 1.0,
               0.1, 1.0, 1.0),
    };
    return presets;
}

std::span<const Preset> solver_presets() {
    static const std::array<Preset, 5> presets{
        // CG to 1e-3, not looser: at 1e-2 the drape scene gains energy and the cloth leaves the ball
        // (docs/results.md, "Solver presets").
        // Both real-time presets take one step a frame, so they split the substeps in which a body
        // drags cloth open (a runner through a banner tore it 40x its rest length in one step a
        // frame, 2.3x split at 2; docs/results.md, "Splitting the substeps that tear").
        solver("interactive",
               "one float Newton step, CG to 1e-3 (at most 100 iterations), substeps split where a body drags cloth "
               "open: for many cloths in real time",
               1, 1, 1e-3, 100, true, false, false, PresetPreconditioner::Auto, 0.0, kRealTimeSplitStretch),
        // What a game ships: interactive's step with room for the iterations a stiff light cloth
        // needs at 60 Hz (at a cap of 100 the demo flag capped 58 frames of 60 and 3 substeps gained
        // energy; docs/results.md, "The CPU backend as a game fallback").
        // MAS at any size: on the demo flag it needs 75 iterations a frame where block-Jacobi needs 175
        // and still hits the cap in 4 frames of 60, in the same time (cpu backend).
        // CCD hits resolved to 1e-4 of the substep (the float GPU CCD's own default): a quarter off the
        // cpu backend's CCD on `layers` for 0.7% more constraints, each within 4% of eta
        // (docs/results.md, "Where layers' CCD time goes").
        solver("game",
               "one float Newton step a 60 Hz frame, MAS, CG to 1e-3 (at most 300 iterations), CCD to 1e-4 of the "
               "substep, substeps split where a body drags cloth open: a game's cloth",
               1, 1, 1e-3, 300, true, false, false, PresetPreconditioner::Mas, 1e-4, kRealTimeSplitStretch),
        solver("balanced", "the defaults: one double Newton step, CG to 1e-4",
               static_cast<int>(default_of("solver.substeps")), static_cast<int>(default_of("solver.newton_iterations")),
               default_of("solver.cg_tolerance"), static_cast<int>(default_of("solver.cg_max_iterations")),
               default_of("solver.precision") == 0.0, default_of("solver.hessian") == 1.0),
        // The element Hessians as the other presets form them: the projected ones cost 5-22x and
        // converged no closer in 3 Newton steps on cantilever, skirt and hanging (docs/results.md,
        // "Speed against accuracy").
        solver("accurate", "4 substeps of 3 Newton steps, CG to 1e-6: for reference runs", 4, 3, 1e-6, 2000, false, false),
        // Offset contact wins where the impact zones collapse: 50 stacked sheets 2.3x, the wound
        // 200K twist 5-9x; it is slower on loose cloth (docs/results.md, "Offset geometric contact").
        solver("piled", "the defaults with offset contact: for cloth that piles up or winds onto itself",
               static_cast<int>(default_of("solver.substeps")), static_cast<int>(default_of("solver.newton_iterations")),
               default_of("solver.cg_tolerance"), static_cast<int>(default_of("solver.cg_max_iterations")),
               default_of("solver.precision") == 0.0, default_of("solver.hessian") == 1.0, true),
    };
    return presets;
}

const Preset* find_preset(std::span<const Preset> presets, std::string_view name) {
    for (const Preset& p : presets)
        if (p.name == name) return &p;
    return nullptr;
}

std::string preset_names(std::span<const Preset> presets) {
    std::string out;
    for (const Preset& p : presets) out += (out.empty() ? "" : ", ") + p.name;
    return out;
}

std::vector<std::string> preset_overrides(const Preset& preset) {
    std::vector<std::string> out;
    for (const auto& [key, value] : preset.values) {
        const Parameter* p = find_parameter(key);
        if (p == nullptr) throw Error("preset '" + preset.name + "': no scene key '" + key + "'");
        std::string text;
        if (p->type == ParameterType::Choice) {
            const auto index = static_cast<std::size_t>(std::lround(value));
            if (index >= p->choices.size())
                throw Error("preset '" + preset.name + "': " + key + " has no choice " + std::to_string(index));
            text.reserve(p->choices[index].size() + 2);
            text.push_back('"');
            text.append(p->choices[index]);
            text.push_back('"');
        } else if (p->type == ParameterType::Integer) {
            text = std::to_string(std::lround(value));
        } else if (p->type == ParameterType::Boolean) {
            text = value != 0.0 ? "true" : "false";
        } else {
            char buffer[32];  // the shortest form that reads back as the same double
            const auto written = std::to_chars(buffer, buffer + sizeof buffer, value);
            text.assign(buffer, written.ptr);
            if (text.find_first_of(".eEn") == std::string::npos) text += ".0";  // a TOML float, not an integer
        }
        out.push_back(key + "=" + text);
    }
    return out;
}

std::vector<std::string> solver_preset_overrides(std::string_view name) {
    const Preset* preset = find_preset(solver_presets(), name);
    if (preset == nullptr)
        throw Error("unknown solver preset '" + std::string(name) + "' (presets: " + preset_names(solver_presets()) + ")");
    return preset_overrides(*preset);
}

void apply_solver_preset(WorldDesc& desc, std::string_view name) {
    const Preset* preset = find_preset(solver_presets(), name);
    if (preset == nullptr)
        throw Error("unknown solver preset '" + std::string(name) + "' (presets: " + preset_names(solver_presets()) + ")");
    for (const auto& [key, value] : preset->values) set_parameter_number(*find_parameter(key), desc, value);
}

}  // namespace weft
