// Scene → TOML text, the inverse of scene_loader.cpp (see scene.h). Every key of the parameter table
// (weft/parameters.h) is written, including those at their defaults, so that a saved scene says
// everything it means and does not change if a default does. Numbers use the shortest text that reads
// back to the same double (std::to_chars), so load → save → load is exact.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include "weft/backend/model.h"
#include "weft/atomic_file.h"
#include "weft/error.h"
#include "weft/parameters.h"
#include "weft/scene.h"

namespace weft {
namespace {

std::string number(double v) {
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
    std::string s(buffer, result.ptr);
    // A float in TOML needs a fraction or an exponent (2 would read as an integer, which the loader
    // accepts, but a float keeps the file's meaning plain).
    if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
    return s;
}

// Appended piecewise: GCC 12 warns (-Wrestrict, a false positive) on "literal" + string chains.
std::string vec3(Vec3d v) {
    std::string s("[");
    s.append(number(v.x)).append(", ").append(number(v.y)).append(", ").append(number(v.z)).append("]");
    return s;
}

std::string toml_string(std::string_view text) {
    std::string out(1, '"');
    for (const char c : text) {
        switch (c) {
            case '"': out += "\\\""; break;
            case '\\': out += "\\\\"; break;
            case '\n': out += "\\n"; break;
            case '\t': out += "\\t"; break;
            default:
                if (static_cast<unsigned char>(c) < 0x20) {
                    char code[8];
                    std::snprintf(code, sizeof code, "\\u%04x", static_cast<unsigned>(c));
                    out += code;
                } else {
                    out += c;
                }
        }
    }
    out += '"';
    return out;
}

std::string boolean(bool b) { return b ? "true" : "false"; }

// A mesh path as the loader resolves it: relative to the folder the scene is saved in.
std::string mesh_path(const std::filesystem::path& file, const std::filesystem::path& directory) {
    std::error_code ec;
    const std::filesystem::path base = directory.empty() ? std::filesystem::current_path(ec) : directory;
    std::filesystem::path relative = std::filesystem::relative(file, base, ec);
    if (ec || relative.empty()) relative = std::filesystem::absolute(file, ec);
    return relative.generic_string();
}

// The value of parameter `p` in `owner` as the loader reads it back.
template <class Owner>
std::string value_text(const Parameter& p, const Owner& owner) {
    switch (p.type) {
        case ParameterType::Real: return number(parameter_number(p, owner));
        case ParameterType::Integer: return std::to_string(std::llround(parameter_number(p, owner)));
        case ParameterType::Boolean: return boolean(parameter_number(p, owner) != 0.0);
        case ParameterType::Choice: {
            const double index = parameter_number(p, owner);  // -1: a value the names do not list
            if (!(index >= 0.0 && index < static_cast<double>(p.choices.size())))
                throw Error("save scene: " + p.key() + " holds a value that has no name");
            return toml_string(p.choices[static_cast<std::size_t>(index)]);
        }
        case ParameterType::Vector: return vec3(parameter_vector(p, owner));
        case ParameterType::CellCounts: {
            const Vec3d n = parameter_vector(p, owner);
            std::string s("[");
            s.append(std::to_string(std::llround(n.x))).append(", ").append(std::to_string(std::llround(n.y))).append("]");
            return s;
        }
        default: throw Error("save scene: parameter '" + p.key() + "' has a field but no writer for its type");
    }
}

// `key = value` for every parameter of `section` that one of `owners` holds, in the table's order
// (the loader's), joined by `separator`. Keys without a field (names, meshes, pins) are the caller's.
template <class... Owners>
std::string fields(std::string_view section, std::string_view separator, const Owners&... owners) {
    std::string out;
    const auto write = [&](const Parameter& p, const auto& owner) {
        if (p.unset_when_negative && parameter_number(p, owner) < 0.0) return;
        if (!out.empty()) out.append(separator);
        out.append(p.name).append(" = ").append(value_text(p, owner));
    };
    for (const Parameter& p : parameter_table())
        if (p.section == section) (void)((holds<Owners>(p) ? (write(p, owners), true) : false) || ...);
    return out;
}

// A `[section]` table's keys, one a line.
template <class... Owners>
std::string lines(std::string_view section, const Owners&... owners) {
    std::string text = fields(section, "\n", owners...);
    return text.empty() ? text : text + "\n";
}

bool same_material(const Material& a, const Material& b) {
    for (const Parameter& p : parameter_table())
        if (holds<Material>(p) && parameter_number(p, a) != parameter_number(p, b)) return false;
    return true;
}

void write_pin(std::ostream& out, const PinSelection& pin) {
    out << "\n[[cloth.pin]]\n";
    switch (pin.kind) {
        case PinSelection::Kind::Vertices: {
            out << "vertices = [";
            for (std::size_t i = 0; i < pin.vertices.size(); ++i) out << (i ? ", " : "") << pin.vertices[i];
            out << "]\n";
            break;
        }
        case PinSelection::Kind::Box:
            out << "box = { min = " << vec3(pin.box_min) << ", max = " << vec3(pin.box_max) << " }\n";
            break;
        case PinSelection::Kind::Edge: out << "edge = " << toml_string(pin.edge) << "\n"; break;
        case PinSelection::Kind::Corners: out << "corners = " << toml_string(pin.edge) << "\n"; break;
    }
    if (!pin.motion.empty()) out << "motion = " << toml_string(pin.motion) << "\n";
    if (!pin.follow.empty()) out << "follow = " << toml_string(pin.follow) << "\n";
    if (!pin.joint.empty()) out << "joint = " << toml_string(pin.joint) << "\n";
}

void write_cloth(std::ostream& out, const SceneDesc& scene, std::size_t entry, const std::filesystem::path& directory) {
    const SceneCloth* first = nullptr;
    for (const SceneCloth& c : scene.cloths) {
        if (c.entry != entry) continue;
        if (first == nullptr) {
            first = &c;
        } else if (!same_material(c.desc.material, first->desc.material)) {
            throw Error("save scene: cloths '" + first->desc.name + "' and '" + c.desc.name +
                        "' come from one [[cloth]] table (repeat) but have different materials; a scene file "
                        "gives all copies one material");
        }
    }
    if (first == nullptr) return;
    const ClothPlacement& p = scene.cloth_placements[entry];
    const ClothSource& src = first->source;
    out << "\n[[cloth]]\nname = " << toml_string(p.name) << "\n";
    if (src.kind == ClothSource::Kind::Grid) {
        out << "mesh = { grid = { " << fields("cloth.mesh.grid", ", ", src) << " } }\n";
    } else {
        out << "mesh = { file = " << toml_string(mesh_path(src.file, directory)) << ", " << fields("cloth.mesh", ", ", src)
            << " }\n";
    }
    out << lines("cloth", p, first->desc, first->fabric);  // position … flat_rest_bending
    if (p.repeat_count > 0) out << "repeat = { " << fields("cloth.repeat", ", ", p) << " }\n";
    out << "\n[cloth.material]\n" << lines("cloth.material", first->desc.material);
    for (const PinSelection& pin : first->pins) write_pin(out, pin);
}

void write_collider(std::ostream& out, const SceneDesc& scene, std::size_t k, const std::filesystem::path& directory) {
    const ColliderDesc& c = scene.colliders[k];
    const ColliderMeshSource& mesh = scene.collider_meshes[k];
    const Parameter& shape = parameter("collider", "shape");
    out << "\n[[collider]]\nname = " << toml_string(c.name)
        << "\nshape = " << toml_string(shape.choices[static_cast<std::size_t>(c.shape)]) << "\n";
    // The keys of its shape in the table's order; where it is, below, depends on whether it follows a motion.
    for (const Parameter& p : parameter_table()) {
        if (p.section != "collider" || !p.applies_to(c.shape) || p.name == "position" || p.name == "rotation") continue;
        if (p.name == "file") {
            out << "file = " << toml_string(mesh_path(mesh.file, directory)) << "\n";
        } else if (p.name == "clip") {
            if (!mesh.clip.empty()) out << "clip = " << toml_string(mesh.clip) << "\n";
        } else if (holds<ColliderDesc>(p)) {
            if (!(p.unset_when_negative && parameter_number(p, c) < 0.0)) out << p.name << " = " << value_text(p, c) << "\n";
        } else if (holds<ColliderMeshSource>(p)) {
            out << p.name << " = " << value_text(p, mesh) << "\n";
        }
    }
    const std::string& motion = scene.collider_motions[k];
    if (!motion.empty()) {
        out << "motion = " << toml_string(motion) << "\n";
    } else {
        out << "position = " << value_text(parameter("collider", "position"), c) << "\n";
        out << "rotation = " << vec3(scene.collider_rotation_degrees[k]) << "\n";
    }
}

}  // namespace

std::string scene_to_toml(const SceneDesc& scene, const std::filesystem::path& directory) {
    if (scene.collider_motions.size() != scene.colliders.size() || scene.collider_meshes.size() != scene.colliders.size() ||
        scene.collider_rotation_degrees.size() != scene.colliders.size())
        throw Error("save scene: the collider lists differ in size (a SceneDesc not made by load_scene)");
    for (const SceneCloth& c : scene.cloths)
        if (c.entry >= scene.cloth_placements.size())
            throw Error("save scene: cloth '" + c.desc.name + "' has no [[cloth]] placement (a SceneDesc not made by load_scene)");
    std::ostringstream out;
    out << "# Saved by weft (scene format: docs/scene-format.md).\n";
    out << "\n[scene]\nname = " << toml_string(scene.name) << "\n" << lines("scene", scene);
    for (const std::string_view section : {"solver", "world", "wind", "collision"})
        out << "\n[" << section << "]\n" << lines(section, scene.world);
    for (const SceneMotion& m : scene.motions)
        out << "\n[[motion]]\nname = " << toml_string(m.name) << "\n" << lines("motion", m.motion, m);
    for (std::size_t entry = 0; entry < scene.cloth_placements.size(); ++entry) write_cloth(out, scene, entry, directory);
    for (std::size_t k = 0; k < scene.colliders.size(); ++k) write_collider(out, scene, k, directory);
    out << "\n[camera]\n" << lines("camera", scene.camera);
    return out.str();
}

void save_scene(const SceneDesc& scene, const std::filesystem::path& path) {
    const std::string text = scene_to_toml(scene, path.parent_path());
    write_file_atomically(path, text);  // a failed save leaves the scene file as it was
}

void update_scene_from_world(SceneDesc& scene, const World& world) {
    const Model& model = world.model();
    if (model.cloths.size() != scene.cloths.size())
        throw Error("update scene: the world has " + std::to_string(model.cloths.size()) + " cloths, the scene " +
                    std::to_string(scene.cloths.size()));
    scene.world = model.settings;
    for (std::size_t i = 0; i < scene.cloths.size(); ++i) {
        if (model.cloths[i].name != scene.cloths[i].desc.name)
            throw Error("update scene: cloth " + std::to_string(i) + " is '" + model.cloths[i].name + "' in the world and '" +
                        scene.cloths[i].desc.name + "' in the scene");
        scene.cloths[i].desc.material = model.cloths[i].material;
    }
    // Motions are live too (World::motion). The file's rotation stays as written: the editor does
    // not change a motion's initial rotation.
    if (model.motions.size() != scene.motions.size())
        throw Error("update scene: the world has " + std::to_string(model.motions.size()) + " motions, the scene " +
                    std::to_string(scene.motions.size()));
    for (std::size_t i = 0; i < scene.motions.size(); ++i) scene.motions[i].motion = model.motions[i];

    // Colliders: what World::collider lets a user change live. A collider that follows a motion keeps
    // the motion's frame (the motion was copied above); the rest keep their file rotation.
    if (model.colliders.size() != scene.colliders.size())
        throw Error("update scene: the world has " + std::to_string(model.colliders.size()) + " colliders, the scene " +
                    std::to_string(scene.colliders.size()));
    for (std::size_t k = 0; k < scene.colliders.size(); ++k) {
        const ColliderDesc& live = model.colliders[k];
        ColliderDesc& saved = scene.colliders[k];
        if ((live.shape != saved.shape && !(live.is_analytic() && saved.is_analytic())) || live.name != saved.name)
            throw Error("update scene: collider " + std::to_string(k) + " is '" + live.name + "' in the world and '" +
                        saved.name + "' in the scene");
        saved.shape = live.shape;  // an analytic shape changed live (World::set_collider_shape)
        const bool follows = k < scene.collider_motions.size() && !scene.collider_motions[k].empty();
        for (const Parameter& p : parameter_table()) {
            if (!holds<ColliderDesc>(p) || p.effect != ParameterEffect::Live) continue;
            if ((p.name == "position" || p.name == "rotation") && follows) continue;  // the motion's frame, copied above
            if (p.access.number != nullptr) set_parameter_number(p, saved, parameter_number(p, live));
            if (p.access.vector != nullptr) set_parameter_vector(p, saved, parameter_vector(p, live));
        }
        // The file's Euler angles, unless the rotation is still theirs (no round trip through the
        // matrix, which would rewrite 30 as 30.000000000000004).
        if (!follows && k < scene.collider_rotation_degrees.size()) {
            Vec3d& degrees = scene.collider_rotation_degrees[k];
            const Mat3d file = rotation_from_euler_degrees(degrees);
            double change = 0.0;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) change = std::max(change, std::abs(file.m[i][j] - live.motion.initial_rotation.m[i][j]));
            if (change > 1e-12) degrees = euler_degrees_from_rotation(live.motion.initial_rotation);
        }
    }

    // Pins: the scene's rules while they still say what the world pins, vertex lists once pins were
    // added or removed live (World::pin/unpin).
    using PinKey = std::tuple<std::uint32_t, int, int, int>;  // vertex, motion, collider and joint indices
    const auto pin_set = [](const std::vector<PinDesc>& pins) {
        std::vector<PinKey> keys;
        for (const PinDesc& p : pins) keys.emplace_back(p.vertex, p.motion, p.collider, p.collider >= 0 ? p.collider_joint : -1);
        std::sort(keys.begin(), keys.end());
        return keys;
    };
    std::vector<std::vector<PinKey>> live_pins(scene.cloths.size());
    for (std::size_t i = 0; i < scene.cloths.size(); ++i) {
        live_pins[i] = pin_set(model.cloths[i].pins);
        if (i > 0 && scene.cloths[i - 1].entry == scene.cloths[i].entry && live_pins[i] != live_pins[i - 1])
            throw Error("update scene: cloths '" + scene.cloths[i - 1].desc.name + "' and '" + scene.cloths[i].desc.name +
                        "' come from one [[cloth]] table (repeat) but have different pins; a scene file gives all "
                        "copies one pin set");
    }
    for (std::size_t i = 0; i < scene.cloths.size(); ++i) {
        SceneCloth& cloth = scene.cloths[i];
        if (pin_set(scene_pins(scene, i, *model.cloths[i].fabric, model.colliders)) == live_pins[i]) continue;
        cloth.desc.pins.clear();
        cloth.pins.clear();
        // One vertex list per motion or followed collider. A vertex that follows a collider is written
        // with `follow`, which pins it again to the skin vertex nearest to where it starts.
        for (const auto& [vertex, motion, collider, joint] : live_pins[i]) {
            const std::string name =
                motion >= 0 && static_cast<std::size_t>(motion) < scene.motions.size() ? scene.motions[motion].name : "";
            const ColliderDesc* followed =
                collider >= 0 && static_cast<std::size_t>(collider) < model.colliders.size() ? &model.colliders[collider] : nullptr;
            const std::string follow = followed ? followed->name : "";
            const std::string joint_name = followed && followed->skin && joint >= 0 &&
                                                   static_cast<std::size_t>(joint) < followed->skin->joints.size()
                                               ? followed->skin->joints[static_cast<std::size_t>(joint)].name
                                               : "";
            auto rule = std::find_if(cloth.pins.begin(), cloth.pins.end(), [&](const PinSelection& s) {
                return s.motion == name && s.follow == follow && s.joint == joint_name;
            });
            if (rule == cloth.pins.end()) {
                PinSelection s;
                s.kind = PinSelection::Kind::Vertices;
                s.motion = name;
                s.follow = follow;
                s.joint = joint_name;
                rule = cloth.pins.insert(cloth.pins.end(), std::move(s));
            }
            rule->vertices.push_back(vertex);  // ascending: live_pins is sorted
        }
    }
}

}  // namespace weft
