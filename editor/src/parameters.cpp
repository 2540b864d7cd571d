// The editor's parameter table (see parameters.h). Ranges are those of docs/scene-format.md and the
// `Valid range` comments of settings.h and material.h.
#include "weft/backend/model.h"
#include "weft/editor/parameters.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>

#include "weft/error.h"

namespace weft::editor {
namespace {

std::string range_text(const Parameter& p) {
    if (p.kind == ParameterKind::boolean) return "true or false";
    if (p.kind == ParameterKind::choice) {
        std::string out;
        for (const std::string& c : p.choices) out += (out.empty() ? "" : ", ") + c;
        return "one of " + out;
    }
    std::ostringstream s;
    s << (p.kind == ParameterKind::integer ? "an integer" : "a number") << " in [" << p.min << ", " << p.max << "]";
    return s.str();
}

// Builders for the table's rows: a value read and written through a member of the world's settings
// or of a cloth's material.
template <typename T>
Parameter number(std::string key, std::string panel, std::string label, std::string unit, double min, double max,
                 bool log_scale, std::function<T&(World&)> field) {
    Parameter p;
    p.key = std::move(key);
    p.panel = std::move(panel);
    p.label = std::move(label);
    p.unit = std::move(unit);
    p.kind = std::is_integral_v<T> ? ParameterKind::integer : ParameterKind::real;
    p.min = min;
    p.max = max;
    p.log_scale = log_scale;
    // The getter takes a const world; the field accessor needs a mutable one to hand out a reference.
    p.get = [field](const World& w) { return static_cast<double>(field(const_cast<World&>(w))); };
    p.set = [field](World& w, double v) {
        if constexpr (std::is_integral_v<T>)
            field(w) = static_cast<T>(std::lround(v));
        else
            field(w) = static_cast<T>(v);
    };
    return p;
}

Parameter flag(std::string key, std::string panel, std::string label, std::function<bool&(World&)> field) {
    Parameter p;
    p.key = std::move(key);
    p.panel = std::move(panel);
    p.label = std::move(label);
    p.kind = ParameterKind::boolean;
    p.get = [field](const World& w) { return field(const_cast<World&>(w)) ? 1.0 : 0.0; };
    p.set = [field](World& w, double v) { field(w) = v != 0.0; };
    return p;
}

template <typename E>
Parameter choice(std::string key, std::string panel, std::string label, std::vector<std::string> names,
                 std::vector<E> values, std::function<E&(World&)> field) {
    Parameter p;
    p.key = std::move(key);
    p.panel = std::move(panel);
    p.label = std::move(label);
    p.kind = ParameterKind::choice;
    p.min = 0.0;
    p.max = static_cast<double>(names.size() - 1);
    p.choices = std::move(names);
    p.get = [field, values](const World& w) {
        const E current = field(const_cast<World&>(w));
        for (std::size_t i = 0; i < values.size(); ++i)
            if (values[i] == current) return static_cast<double>(i);
        return 0.0;
    };
    p.set = [field, values](World& w, double v) { field(w) = values.at(static_cast<std::size_t>(std::lround(v))); };
    return p;
}

// One component of a vector setting; the vector's length is kept within `max` (the scene format's
// "magnitude ≤ 1000"), scaling all three components down together.
Parameter component(std::string key, std::string panel, std::string label, std::string unit, double max, int axis,
                    std::function<Vec3d&(World&)> field) {
    Parameter p = number<double>(
        std::move(key), std::move(panel), std::move(label), std::move(unit), -max, max, false,
        [field, axis](World& w) -> double& { return axis == 0 ? field(w).x : axis == 1 ? field(w).y : field(w).z; });
    auto base = p.set;
    p.set = [base, field, max](World& w, double v) {
        base(w, v);
        Vec3d& vec = field(w);
        const double length = std::sqrt(vec.x * vec.x + vec.y * vec.y + vec.z * vec.z);
        if (length > max) {
            const double s = max / length;
            vec = Vec3d{vec.x * s, vec.y * s, vec.z * s};
        }
    };
    return p;
}

}  // namespace

ParameterTable::ParameterTable(const World& world, std::span<const std::string> motion_names,
                               std::span<const std::string> collider_motions) {
    using S = SolverSettings;
    auto solver = [](World& w) -> S& { return w.settings().solver; };
    auto& P = parameters_;
    // ---- solver
    P.push_back(number<double>("solver.dt", "solver", "time step", "s", 1e-5, 0.1, true,
                               [solver](World& w) -> double& { return solver(w).dt; }));
    P.push_back(number<int>("solver.substeps", "solver", "substeps", "", 1, 1000, true,
                            [solver](World& w) -> int& { return solver(w).substeps; }));
    P.back().observed = [](const StepStats& s) -> std::optional<double> { return s.substeps; };
    P.push_back(number<int>("solver.newton_iterations", "solver", "Newton iterations", "", 1, 50, false,
                            [solver](World& w) -> int& { return solver(w).newton_iterations; }));
    P.push_back(number<double>("solver.cg_tolerance", "solver", "CG tolerance", "", 1e-12, 1.0, true,
                               [solver](World& w) -> double& { return solver(w).cg_tolerance; }));
    P.push_back(number<int>("solver.cg_max_iterations", "solver", "CG iteration cap", "", 1, 100000, true,
                            [solver](World& w) -> int& { return solver(w).cg_max_iterations; }));
    P.push_back(flag("solver.cg_warm_start", "solver", "CG warm start",
                     [solver](World& w) -> bool& { return solver(w).cg_warm_start; }));
    P.push_back(choice<Precision>("solver.precision", "solver", "precision", {"float", "double"},
                                  {Precision::Float, Precision::Double},
                                  [solver](World& w) -> Precision& { return solver(w).precision; }));
    P.push_back(choice<HessianMode>("solver.hessian", "solver", "Hessian", {"fast", "projected"},
                                    {HessianMode::Fast, HessianMode::Projected},
                                    [solver](World& w) -> HessianMode& { return solver(w).hessian; }));
    P.push_back(number<double>("solver.contact_stiffness", "solver", "collider stiffness", "N/m", 0.0, 1e12, true,
                               [solver](World& w) -> double& { return solver(w).contact_stiffness; }));
    P.back().hint = "0: picked from the mass and the time step";

    // ---- collision
    auto col = [](World& w) -> CollisionSettings& { return w.settings().collision; };
    P.push_back(flag("collision.self", "collision", "self-collision",
                     [col](World& w) -> bool& { return col(w).self_collision; }));
    P.push_back(flag("collision.continuous", "collision", "continuous",
                     [col](World& w) -> bool& { return col(w).continuous; }));
    P.back().hint = "CCD and impact zones after the solve; off: proximity forces only";
    P.push_back(choice<CollisionCulling>("collision.culling", "collision", "culling", {"normal_cone", "none"},
                                         {CollisionCulling::NormalCone, CollisionCulling::None},
                                         [col](World& w) -> CollisionCulling& { return col(w).culling; }));
    P.push_back(flag("collision.cull_contacts", "collision", "cull contacts",
                     [col](World& w) -> bool& { return col(w).cull_contacts; }));
    P.push_back(number<double>("collision.thickness", "collision", "thickness", "m", 0.0, 0.1, false,
                               [col](World& w) -> double& { return col(w).thickness; }));
    P.back().hint = "0: the larger of the two cloths' contact thickness";
    P.push_back(number<double>("collision.stiffness", "collision", "stiffness", "N/m", 0.0, 1e9, true,
                               [col](World& w) -> double& { return col(w).stiffness; }));
    P.back().hint = "0: 100 m/h\u00b2 from the pair's mass and the substep";
    P.push_back(number<double>("collision.rest_exclusion", "collision", "rest exclusion", "thicknesses", 0.0, 10.0,
                               false, [col](World& w) -> double& { return col(w).rest_exclusion; }));
    P.push_back(number<int>("collision.max_impact_iterations", "collision", "impact-zone rounds", "", 1, 1000, true,
                            [col](World& w) -> int& { return col(w).max_impact_iterations; }));
    P.push_back(number<double>("collision.impact_tolerance", "collision", "impact tolerance", "thicknesses", 0.0, 0.5,
                               false, [col](World& w) -> double& { return col(w).impact_tolerance; }));
    P.back().hint = "a zone's projection stops within this fraction of the thickness; 0: the backend's default";
    P.push_back(number<int>("collision.max_impact_sweeps", "collision", "impact sweeps", "", 0, 100000, true,
                            [col](World& w) -> int& { return col(w).max_impact_sweeps; }));
    P.back().hint = "cap on one zone's projection iterations per round; 0: the backend's default";
    P.push_back(flag("collision.count_culled", "collision", "count culled pairs",
                     [col](World& w) -> bool& { return col(w).count_culled; }));
    P.back().hint = "also count the pairs culling removed (cpu backend; costs a box test per pair)";
    P.push_back(flag("collision.check", "collision", "exact check",
                     [col](World& w) -> bool& { return col(w).check; }));
    P.back().hint = "exact triangle-triangle intersection check after every step (costly; for testing)";

    // ---- world: gravity and wind
    const char* axes[] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a)
        P.push_back(component(std::string("world.gravity.") + axes[a], "world", std::string("gravity ") + axes[a],
                              "m/s\u00b2", 1000.0, a, [](World& w) -> Vec3d& { return w.settings().gravity; }));
    for (int a = 0; a < 3; ++a)
        P.push_back(component(std::string("wind.velocity.") + axes[a], "world", std::string("wind ") + axes[a], "m/s",
                              1000.0, a, [](World& w) -> Vec3d& { return w.settings().wind.velocity; }));
    auto wind = [](World& w) -> WindDesc& { return w.settings().wind; };
    P.push_back(number<double>("wind.air_density", "world", "air density", "kg/m\u00b3", 0.0, 100.0, false,
                               [wind](World& w) -> double& { return wind(w).air_density; }));
    P.push_back(number<double>("wind.turbulence", "world", "turbulence", "m/s", 0.0, 1000.0, false,
                               [wind](World& w) -> double& { return wind(w).turbulence; }));
    P.push_back(number<double>("wind.turbulence_frequency", "world", "gust frequency", "Hz", 0.0, 1000.0, false,
                               [wind](World& w) -> double& { return wind(w).turbulence_frequency; }));
    P.push_back(number<double>("wind.turbulence_scale", "world", "gust size", "m", 1e-3, 1e6, true,
                               [wind](World& w) -> double& { return wind(w).turbulence_scale; }));

    // ---- materials, per cloth
    const std::vector<ClothDesc>& cloths = world.model().cloths;
    for (std::size_t i = 0; i < cloths.size(); ++i) {
        const std::string name = cloths[i].name.empty() ? std::to_string(i) : cloths[i].name;
        auto mat = [i](World& w) -> Material& { return w.material(i); };
        struct Field {
            const char* key;
            const char* label;
            const char* unit;
            double min, max;
            bool log;
            double Material::*member;
        };
        const Field fields[] = {
            {"stretch_stiffness", "stretch stiffness", "N/m", 1.0, 1e8, true, &Material::stretch_stiffness},
            {"poisson_ratio", "Poisson ratio", "", 0.0, 0.49, false, &Material::poisson_ratio},
            {"bending_stiffness", "bending stiffness", "N\u00b7m", 0.0, 1.0, true, &Material::bending_stiffness},
            {"damping_mass", "damping (mass)", "1/s", 0.0, 100.0, false, &Material::damping_mass},
            {"damping_stiffness", "damping (stiffness)", "s", 0.0, 1.0, true, &Material::damping_stiffness},
            {"drag_coefficient", "drag coefficient", "", 0.0, 10.0, false, &Material::drag_coefficient},
            {"lift_coefficient", "lift coefficient", "", 0.0, 10.0, false, &Material::lift_coefficient},
            {"contact_thickness", "contact thickness", "m", 1e-5, 0.1, true, &Material::contact_thickness},
            {"friction", "friction", "", 0.0, 10.0, false, &Material::friction},
        };
        for (const Field& f : fields) {
            double Material::*member = f.member;
            Parameter p = number<double>("cloth." + name + ".material." + f.key, "materials", f.label, f.unit, f.min,
                                         f.max, f.log, [mat, member](World& w) -> double& {
                                             return mat(w).*member;
                                         });
            p.group = "cloth " + name;
            aliases_.emplace("cloth." + std::to_string(i) + ".material." + f.key, P.size());
            P.push_back(std::move(p));
        }
    }

    // ---- motions: live (World::motion), what pins and colliders following them do from the next
    // step on. The initial rotation is left to the file: changing it mid-run would turn everything
    // that follows the motion about its origin at once.
    for (std::size_t i = 0; i < world.model().motions.size(); ++i) {
        const int index = static_cast<int>(i);
        const std::string name = i < motion_names.size() && !motion_names[i].empty() ? motion_names[i] : std::to_string(i);
        // A collider that follows this motion holds a copy of it (ColliderDesc::motion): the copy
        // is updated with the motion, so that pins and colliders keep moving together.
        std::vector<std::size_t> followers;
        for (std::size_t k = 0; k < collider_motions.size() && k < world.model().colliders.size(); ++k)
            if (!collider_motions[k].empty() && i < motion_names.size() && collider_motions[k] == motion_names[i])
                followers.push_back(k);
        const auto follow = [index, followers](Parameter& p) {
            auto base = p.set;
            p.set = [base, index, followers](World& w, double v) {
                base(w, v);
                for (const std::size_t k : followers) w.collider(k).motion = w.motion(index);
            };
        };
        const auto alias = [&](const std::string& suffix) {
            aliases_.emplace("motion." + std::to_string(i) + "." + suffix, P.size());
        };
        struct VectorField {
            const char* key;
            const char* label;
            const char* unit;
            double max;
            Vec3d Motion::*member;
        };
        const VectorField vectors[] = {
            {"origin", "origin", "m", 1e4, &Motion::origin},
            {"linear_velocity", "velocity", "m/s", 1e3, &Motion::linear_velocity},
            {"angular_velocity", "angular velocity", "rad/s", 1e3, &Motion::angular_velocity},
            {"amplitude", "amplitude", "m", 1e3, &Motion::amplitude},
        };
        for (const VectorField& f : vectors)
            for (int a = 0; a < 3; ++a) {
                Vec3d Motion::*member = f.member;
                const std::string suffix = std::string(f.key) + "." + axes[a];
                alias(suffix);
                P.push_back(component("motion." + name + "." + suffix, "motions", std::string(f.label) + " " + axes[a],
                                      f.unit, f.max, a,
                                      [index, member](World& w) -> Vec3d& { return w.motion(index).*member; }));
                follow(P.back());
                P.back().group = "motion " + name;
            }
        alias("frequency");
        P.push_back(number<double>("motion." + name + ".frequency", "motions", "frequency", "Hz", 0.0, 1000.0, false,
                                   [index](World& w) -> double& { return w.motion(index).frequency; }));
        follow(P.back());
        P.back().group = "motion " + name;
        alias("phase");
        P.push_back(number<double>("motion." + name + ".phase", "motions", "phase", "rad", -1e3, 1e3, false,
                                   [index](World& w) -> double& { return w.motion(index).phase; }));
        follow(P.back());
        P.back().group = "motion " + name;
    }

    // ---- colliders: sizes, friction and (for one that follows no motion) position, read at every
    // substep (World::collider). A mesh collider's triangles are cooked: it has no live rows.
    constexpr const char* kShapes[] = {"plane", "sphere", "capsule", "box", "mesh"};
    for (std::size_t k = 0; k < world.model().colliders.size(); ++k) {
        const ColliderDesc& c = world.model().colliders[k];
        if (!c.is_analytic()) continue;
        const std::string name = c.name.empty() ? std::to_string(k) : c.name;
        const std::string group = "collider " + name + " (" + kShapes[static_cast<int>(c.shape)] + ")";
        auto collider = [k](World& w) -> ColliderDesc& { return w.collider(k); };
        const auto add = [&](const std::string& suffix, Parameter p) {
            aliases_.emplace("collider." + std::to_string(k) + "." + suffix, P.size());
            p.group = group;
            P.push_back(std::move(p));
        };
        const std::string key = "collider." + name + ".";
        if (c.shape == ColliderShape::Sphere || c.shape == ColliderShape::Capsule)
            add("radius", number<double>(key + "radius", "colliders", "radius", "m", 1e-6, 1e6, true,
                                         [collider](World& w) -> double& { return collider(w).radius; }));
        if (c.shape == ColliderShape::Capsule)
            add("half_height", number<double>(key + "half_height", "colliders", "half height", "m", 0.0, 1e6, true,
                                              [collider](World& w) -> double& { return collider(w).half_height; }));
        if (c.shape == ColliderShape::Box)
            for (int a = 0; a < 3; ++a)
                add(std::string("half_extents.") + axes[a],
                    number<double>(key + "half_extents." + axes[a], "colliders", std::string("half extent ") + axes[a],
                                   "m", 1e-6, 1e6, true, [collider, a](World& w) -> double& {
                                       Vec3d& e = collider(w).half_extents;
                                       return a == 0 ? e.x : a == 1 ? e.y : e.z;
                                   }));
        Parameter friction = number<double>(key + "friction", "colliders", "friction", "", -1.0, 10.0, false,
                                            [collider](World& w) -> double& { return collider(w).friction; });
        friction.hint = "below 0: each cloth's own friction (its material)";
        add("friction", std::move(friction));
        const bool follows = k < collider_motions.size() && !collider_motions[k].empty();
        if (!follows)
            for (int a = 0; a < 3; ++a)
                add(std::string("position.") + axes[a],
                    component(key + "position." + axes[a], "colliders", std::string("position ") + axes[a], "m", 1e4, a,
                              [collider](World& w) -> Vec3d& { return collider(w).motion.origin; }));
    }
}

const Parameter* ParameterTable::find(std::string_view key) const {
    for (const Parameter& p : parameters_)
        if (p.key == key) return &p;
    if (const auto it = aliases_.find(key); it != aliases_.end()) return &parameters_[it->second];
    return nullptr;
}

double ParameterTable::parse_value(const Parameter& p, std::string_view text) {
    const std::string shown(text);
    auto bad = [&](const std::string& why) {
        return Error("'" + p.key + "': " + why + " '" + shown + "' (expected " + range_text(p) + ")");
    };
    switch (p.kind) {
        case ParameterKind::boolean:
            if (text == "true" || text == "on" || text == "1") return 1.0;
            if (text == "false" || text == "off" || text == "0") return 0.0;
            throw bad("not a boolean:");
        case ParameterKind::choice:
            for (std::size_t i = 0; i < p.choices.size(); ++i)
                if (p.choices[i] == text) return static_cast<double>(i);
            throw bad("unknown choice");
        case ParameterKind::integer:
        case ParameterKind::real: {
            double value = 0.0;
            const char* end = text.data() + text.size();
            const auto [ptr, ec] = std::from_chars(text.data(), end, value);
            if (ec != std::errc{} || ptr != end || !std::isfinite(value)) throw bad("not a number:");
            if (p.kind == ParameterKind::integer && value != std::floor(value)) throw bad("not an integer:");
            if (value < p.min || value > p.max) throw bad("out of range:");
            return value;
        }
    }
    throw bad("unreadable value");
}

std::string ParameterTable::format_value(const Parameter& p, double value) {
    switch (p.kind) {
        case ParameterKind::boolean:
            return value != 0.0 ? "true" : "false";
        case ParameterKind::choice: {
            const auto i = static_cast<std::size_t>(std::lround(value));
            return i < p.choices.size() ? p.choices[i] : std::to_string(value);
        }
        case ParameterKind::integer:
            return std::to_string(std::lround(value));
        case ParameterKind::real:
            break;
    }
    std::ostringstream s;
    s.precision(9);
    s << value;
    return s.str();
}

double ParameterTable::apply(const Parameter& p, World& world, double value) {
    double v = std::isfinite(value) ? std::clamp(value, p.min, p.max) : p.get(world);
    if (p.kind != ParameterKind::real) v = std::round(v);
    p.set(world, v);
    return v;
}

void ParameterTable::set_pending(std::string_view key, double value) {
    const Parameter* p = find(key);
    if (p == nullptr) throw Error("unknown parameter '" + std::string(key) + "'");
    pending_[p->key] = value;
}

std::optional<double> ParameterTable::take_pending(const Parameter& p) {
    const auto it = pending_.find(p.key);
    if (it == pending_.end()) return std::nullopt;
    const double v = it->second;
    pending_.erase(it);
    return v;
}

}  // namespace weft::editor
