// The editor's parameter table (see parameters.h): a row per live parameter of the runtime's table
// (weft/parameters.h), which gives the key, label, unit, range and doc, for the world's settings, each
// cloth's material, each motion and each analytic collider.
#include "weft/editor/parameters.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>

#include "weft/backend/model.h"
#include "weft/error.h"
#include "weft/parameters.h"

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

// "cloth.flag.material.friction": a key of the runtime table's `section` with the entry (a cloth,
// motion or collider name or index) after the section's first word; `component` for one axis of a vector.
std::string entry_key(const weft::Parameter& row, const std::string& entry, std::string_view component = {}) {
    const std::string_view section = row.section;
    const auto dot = section.find('.');
    std::string key(section.substr(0, dot));
    if (!entry.empty()) key.append(".").append(entry);
    if (dot != std::string_view::npos) key.append(section.substr(dot));
    key.append(".").append(row.name);
    if (!component.empty()) key.append(".").append(component);
    return key;
}

// Whether the editor shows a widget for `row`: a live parameter with a label.
bool shown(const weft::Parameter& row) {
    return row.effect == ParameterEffect::Live && !row.label.empty() && !row.panel.empty();
}

// The editor's rows for one runtime parameter `row` of the struct `owner(world)` returns: one row for
// a number, a flag or a choice, one a component for a vector. Each is added to `out` and its key
// (and `alias`, the same key by index, when not empty) passed to `added`.
template <class Owner>
void add_rows(std::vector<Parameter>& out, const weft::Parameter& row, const std::string& entry, const std::string& alias,
              const std::string& group, const std::function<Owner&(World&)>& owner,
              const std::function<void(const std::string& alias)>& added) {
    Parameter p;
    p.panel = std::string(row.panel);
    p.group = group;
    p.unit = std::string(row.unit);
    p.hint = std::string(row.doc);
    p.log_scale = row.log_scale;
    const ParameterRange range = row.slider.value_or(row.range);
    const auto push = [&](Parameter&& q, const std::string& alias_key) {
        out.push_back(std::move(q));
        added(alias_key);
    };
    // The getters take a const world; the owner accessor needs a mutable one to hand out a reference.
    const auto mutable_world = [](const World& w) -> World& { return const_cast<World&>(w); };
    if (row.type != ParameterType::Vector) {
        p.key = entry_key(row, entry);
        p.label = std::string(row.label);
        switch (row.type) {
            case ParameterType::Integer: p.kind = ParameterKind::integer; break;
            case ParameterType::Boolean: p.kind = ParameterKind::boolean; break;
            case ParameterType::Choice:
                p.kind = ParameterKind::choice;
                p.choices.assign(row.choices.begin(), row.choices.end());
                break;
            default: p.kind = ParameterKind::real; break;
        }
        if (p.kind == ParameterKind::choice) {
            p.min = 0.0;
            p.max = static_cast<double>(p.choices.size() - 1);
        } else if (p.kind != ParameterKind::boolean) {
            p.min = range.lo;
            p.max = range.hi;
        }
        p.get = [&row, owner, mutable_world](const World& w) { return parameter_number(row, owner(mutable_world(w))); };
        p.set = [&row, owner](World& w, double v) { set_parameter_number(row, owner(w), v); };
        push(std::move(p), alias.empty() ? alias : entry_key(row, alias));
        return;
    }
    // A vector, by component. Each is a slider of its own within the range (a box's half extents),
    // or, where the range bounds the length (gravity, wind) or a slider range caps it (a motion's
    // origin), within ± that bound, the length kept within it by scaling all three components together.
    const bool each = row.vector_bound == VectorBound::Components;
    const double max = row.vector_bound == VectorBound::Length ? row.range.hi : range.hi;
    constexpr const char* kAxes[] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
        Parameter c = p;
        c.key = entry_key(row, entry, kAxes[a]);
        c.label = std::string(row.label) + " " + kAxes[a];
        c.kind = ParameterKind::real;
        c.min = each ? range.lo : -max;
        c.max = each ? range.hi : max;
        c.log_scale = each && row.log_scale;
        c.get = [&row, owner, mutable_world, a](const World& w) {
            return parameter_vector(row, owner(mutable_world(w)))[a];
        };
        c.set = [&row, owner, a, each, max](World& w, double v) {
            Vec3d vec = parameter_vector(row, owner(w));
            vec[a] = v;
            const double length = std::sqrt(vec.x * vec.x + vec.y * vec.y + vec.z * vec.z);
            if (!each && length > max) {
                const double s = max / length;
                vec = Vec3d{vec.x * s, vec.y * s, vec.z * s};
            }
            set_parameter_vector(row, owner(w), vec);
        };
        push(std::move(c), alias.empty() ? alias : entry_key(row, alias, kAxes[a]));
    }
}

}  // namespace

ParameterTable::ParameterTable(const World& world, std::span<const std::string> motion_names,
                               std::span<const std::string> collider_motions) {
    auto& P = parameters_;
    const auto no_alias = [](const std::string&) {};

    // ---- solver, collision, gravity and wind: the world's settings
    for (const weft::Parameter& row : parameter_table()) {
        if (!shown(row) || !holds<WorldDesc>(row)) continue;
        add_rows<WorldDesc>(P, row, "", "", "", [](World& w) -> WorldDesc& { return w.settings(); }, no_alias);
        if (row.key() == "solver.substeps")
            P.back().observed = [](const StepStats& s) -> std::optional<double> { return s.substeps; };
    }

    // ---- materials, per cloth
    const std::vector<ClothDesc>& cloths = world.model().cloths;
    for (std::size_t i = 0; i < cloths.size(); ++i) {
        const std::string name = cloths[i].name.empty() ? std::to_string(i) : cloths[i].name;
        const auto alias = [&](const std::string& key) { aliases_.emplace(key, P.size() - 1); };
        for (const weft::Parameter& row : parameter_table())
            if (shown(row) && holds<Material>(row))
                add_rows<Material>(P, row, name, std::to_string(i), "cloth " + name,
                                   [i](World& w) -> Material& { return w.material(i); }, alias);
    }

    // ---- motions: live (World::motion), what pins and colliders following them do from the next
    // step on. The initial rotation is left to the file (the table says it needs a rebuild):
    // changing it mid-run would turn everything that follows the motion about its origin at once.
    for (std::size_t i = 0; i < world.model().motions.size(); ++i) {
        const int index = static_cast<int>(i);
        const std::string name = i < motion_names.size() && !motion_names[i].empty() ? motion_names[i] : std::to_string(i);
        // A collider that follows this motion holds a copy of it (ColliderDesc::motion): the copy
        // is updated with the motion, so that pins and colliders keep moving together.
        std::vector<std::size_t> followers;
        for (std::size_t k = 0; k < collider_motions.size() && k < world.model().colliders.size(); ++k)
            if (!collider_motions[k].empty() && i < motion_names.size() && collider_motions[k] == motion_names[i])
                followers.push_back(k);
        const auto follow = [&](const std::string& key) {
            aliases_.emplace(key, P.size() - 1);
            Parameter& p = P.back();
            auto base = p.set;
            p.set = [base, index, followers](World& w, double v) {
                base(w, v);
                for (const std::size_t k : followers) w.collider(k).motion = w.motion(index);
            };
        };
        for (const weft::Parameter& row : parameter_table())
            if (shown(row) && holds<Motion>(row))
                add_rows<Motion>(P, row, name, std::to_string(i), "motion " + name,
                                 [index](World& w) -> Motion& { return w.motion(index); }, follow);
    }

    // ---- colliders: sizes (analytic shapes), friction and (for one that follows no motion) position,
    // read at every substep (World::collider). A mesh collider's triangles are cooked, but where they
    // are is its frame, placed at every substep (collision_geometry.cpp): it gets friction and position.
    // An analytic collider's shape is a row too (World::set_collider_shape rebuilds the world at the
    // next step), so it has the sizes of every analytic shape, each shown while its shape is.
    const weft::Parameter& shape_row = weft::parameter("collider", "shape");
    const auto shape_names = shape_row.choices;
    const auto analytic_size = [](const weft::Parameter& row) {
        return row.shapes != 0 && (row.applies_to(ColliderShape::Sphere) || row.applies_to(ColliderShape::Capsule) ||
                                   row.applies_to(ColliderShape::Box));
    };
    for (std::size_t k = 0; k < world.model().colliders.size(); ++k) {
        const ColliderDesc& c = world.model().colliders[k];
        const std::string name = c.name.empty() ? std::to_string(k) : c.name;
        const std::string group = "collider " + name + (c.is_analytic() ? std::string()
                                                                         : " (" + std::string(shape_names[static_cast<std::size_t>(c.shape)]) + ")");
        const bool follows = k < collider_motions.size() && !collider_motions[k].empty();
        const auto alias = [&](const std::string& key) { aliases_.emplace(key, P.size() - 1); };
        if (c.is_analytic()) {
            Parameter p;
            p.key = "collider." + name + ".shape";
            p.panel = "colliders";
            p.group = group;
            p.label = "shape";
            p.hint = std::string(shape_row.doc) + " (a mesh comes from a file: not here)";
            p.kind = ParameterKind::choice;
            // The analytic shapes, in ColliderShape's order (the runtime's choices end with "mesh").
            for (int s = 0; s <= static_cast<int>(ColliderShape::Box); ++s)
                p.choices.emplace_back(shape_names[static_cast<std::size_t>(s)]);
            p.min = 0.0;
            p.max = static_cast<double>(p.choices.size() - 1);
            p.get = [k](const World& w) { return static_cast<double>(w.model().colliders[k].shape); };
            p.set = [k](World& w, double v) { w.set_collider_shape(k, static_cast<ColliderShape>(std::lround(v))); };
            P.push_back(std::move(p));
            alias("collider." + std::to_string(k) + ".shape");
        }
        for (const weft::Parameter& row : parameter_table()) {
            if (!shown(row) || !holds<ColliderDesc>(row)) continue;
            const bool size_of_a_shape = c.is_analytic() && analytic_size(row);  // shown while its shape is
            if (!row.applies_to(c.shape) && !size_of_a_shape) continue;
            if ((row.name == "position" || row.name == "rotation") && follows) continue;  // the motion's frame
            const std::size_t first = P.size();
            add_rows<ColliderDesc>(P, row, name, std::to_string(k), group,
                                   [k](World& w) -> ColliderDesc& { return w.collider(k); }, alias);
            if (size_of_a_shape)
                for (std::size_t i = first; i < P.size(); ++i)
                    P[i].shown = [k, &row](const World& w) { return row.applies_to(w.model().colliders[k].shape); };
        }
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
