// Scene → TOML text, the inverse of scene_loader.cpp (see scene.h). Every key is written, including
// those at their defaults, so that a saved scene says everything it means and does not change if a
// default does. Numbers use the shortest text that reads back to the same double (std::to_chars), so
// load → save → load is exact.
#include <algorithm>
#include <charconv>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include "weft/backend/model.h"
#include "weft/error.h"
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

bool same_material(const Material& a, const Material& b) {
    return a.stretch_stiffness == b.stretch_stiffness && a.poisson_ratio == b.poisson_ratio &&
           a.bending_stiffness == b.bending_stiffness && a.damping_mass == b.damping_mass &&
           a.damping_stiffness == b.damping_stiffness && a.drag_coefficient == b.drag_coefficient &&
           a.lift_coefficient == b.lift_coefficient && a.contact_thickness == b.contact_thickness &&
           a.friction == b.friction;
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
        out << "mesh = { grid = { width = " << number(src.width) << ", height = " << number(src.height) << ", cells = ["
            << src.cells_x << ", " << src.cells_y << "], plane = " << (src.plane == GridPlane::XY ? "\"xy\"" : "\"xz\"")
            << " } }\n";
    } else {
        out << "mesh = { file = " << toml_string(mesh_path(src.file, directory)) << ", scale = " << number(src.scale) << " }\n";
    }
    out << "position = " << vec3(p.position) << "\n";
    out << "rotation = " << vec3(p.rotation_degrees) << "\n";
    out << "initial_velocity = " << vec3(first->desc.initial_velocity) << "\n";
    out << "density = " << number(first->fabric.density) << "\n";
    out << "flat_rest_bending = " << boolean(first->fabric.flat_rest_bending) << "\n";
    if (p.repeat_count > 0)
        out << "repeat = { count = " << p.repeat_count << ", offset = " << vec3(p.repeat_offset)
            << ", rotation_step = " << vec3(p.repeat_rotation_step) << " }\n";
    const Material& m = first->desc.material;
    out << "\n[cloth.material]\n";
    out << "stretch_stiffness = " << number(m.stretch_stiffness) << "\n";
    out << "poisson_ratio = " << number(m.poisson_ratio) << "\n";
    out << "bending_stiffness = " << number(m.bending_stiffness) << "\n";
    out << "damping_mass = " << number(m.damping_mass) << "\n";
    out << "damping_stiffness = " << number(m.damping_stiffness) << "\n";
    out << "drag_coefficient = " << number(m.drag_coefficient) << "\n";
    out << "lift_coefficient = " << number(m.lift_coefficient) << "\n";
    out << "contact_thickness = " << number(m.contact_thickness) << "\n";
    out << "friction = " << number(m.friction) << "\n";
    for (const PinSelection& pin : first->pins) write_pin(out, pin);
}

constexpr const char* kShapeNames[] = {"plane", "sphere", "capsule", "box", "mesh"};

void write_collider(std::ostream& out, const SceneDesc& scene, std::size_t k, const std::filesystem::path& directory) {
    const ColliderDesc& c = scene.colliders[k];
    out << "\n[[collider]]\nname = " << toml_string(c.name) << "\nshape = \"" << kShapeNames[static_cast<int>(c.shape)]
        << "\"\n";
    if (c.shape == ColliderShape::Sphere || c.shape == ColliderShape::Capsule) out << "radius = " << number(c.radius) << "\n";
    if (c.shape == ColliderShape::Capsule) out << "half_height = " << number(c.half_height) << "\n";
    if (c.shape == ColliderShape::Box) out << "half_extents = " << vec3(c.half_extents) << "\n";
    if (c.shape == ColliderShape::Mesh) {
        const ColliderMeshSource& mesh = scene.collider_meshes[k];
        out << "file = " << toml_string(mesh_path(mesh.file, directory)) << "\nscale = " << number(mesh.scale) << "\n";
    }
    if (c.friction >= 0.0) out << "friction = " << number(c.friction) << "\n";
    const std::string& motion = scene.collider_motions[k];
    if (!motion.empty()) {
        out << "motion = " << toml_string(motion) << "\n";
    } else {
        out << "position = " << vec3(c.motion.origin) << "\n";
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
    out << "\n[scene]\nname = " << toml_string(scene.name) << "\nframes = " << scene.frames << "\n";

    const SolverSettings& s = scene.world.solver;
    out << "\n[solver]\n";
    out << "dt = " << number(s.dt) << "\nsubsteps = " << s.substeps << "\nnewton_iterations = " << s.newton_iterations
        << "\ncg_tolerance = " << number(s.cg_tolerance) << "\ncg_max_iterations = " << s.cg_max_iterations
        << "\ncg_warm_start = " << boolean(s.cg_warm_start)
        << "\nprecision = " << (s.precision == Precision::Float ? "\"float\"" : "\"double\"")
        << "\nhessian = " << (s.hessian == HessianMode::Fast ? "\"fast\"" : "\"projected\"")
        << "\ncontact_stiffness = " << number(s.contact_stiffness) << "\nthreads = " << s.threads << "\n";

    out << "\n[world]\ngravity = " << vec3(scene.world.gravity) << "\n";
    const WindDesc& w = scene.world.wind;
    out << "\n[wind]\nvelocity = " << vec3(w.velocity) << "\nair_density = " << number(w.air_density)
        << "\nturbulence = " << number(w.turbulence) << "\nturbulence_frequency = " << number(w.turbulence_frequency)
        << "\nturbulence_scale = " << number(w.turbulence_scale) << "\n";

    const CollisionSettings& c = scene.world.collision;
    out << "\n[collision]\nself = " << boolean(c.self_collision) << "\ncontinuous = " << boolean(c.continuous)
        << "\nculling = " << (c.culling == CollisionCulling::NormalCone ? "\"normal_cone\"" : "\"none\"")
        << "\ncull_contacts = " << boolean(c.cull_contacts) << "\ncount_culled = " << boolean(c.count_culled)
        << "\nrest_exclusion = " << number(c.rest_exclusion) << "\nthickness = " << number(c.thickness)
        << "\nstiffness = " << number(c.stiffness) << "\nmax_impact_iterations = " << c.max_impact_iterations
        << "\nimpact_tolerance = " << number(c.impact_tolerance) << "\nmax_impact_sweeps = " << c.max_impact_sweeps
        << "\ncheck = " << boolean(c.check) << "\n";

    for (const SceneMotion& m : scene.motions) {
        out << "\n[[motion]]\nname = " << toml_string(m.name) << "\norigin = " << vec3(m.motion.origin)
            << "\nrotation = " << vec3(m.rotation_degrees) << "\nlinear_velocity = " << vec3(m.motion.linear_velocity)
            << "\nangular_velocity = " << vec3(m.motion.angular_velocity) << "\namplitude = " << vec3(m.motion.amplitude)
            << "\nfrequency = " << number(m.motion.frequency) << "\nphase = " << number(m.motion.phase) << "\n";
    }
    for (std::size_t entry = 0; entry < scene.cloth_placements.size(); ++entry) write_cloth(out, scene, entry, directory);
    for (std::size_t k = 0; k < scene.colliders.size(); ++k) write_collider(out, scene, k, directory);
    out << "\n[camera]\nposition = " << vec3(scene.camera.position) << "\ntarget = " << vec3(scene.camera.target)
        << "\nfov = " << number(scene.camera.fov_degrees) << "\n";
    return out.str();
}

void save_scene(const SceneDesc& scene, const std::filesystem::path& path) {
    const std::string text = scene_to_toml(scene, path.parent_path());
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(path.string() + ": cannot open for writing the scene");
    out << text;
    out.flush();
    if (!out) throw Error(path.string() + ": writing the scene failed (disk full?)");
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
        if (live.shape != saved.shape || live.name != saved.name)
            throw Error("update scene: collider " + std::to_string(k) + " is '" + live.name + "' in the world and '" +
                        saved.name + "' in the scene");
        saved.radius = live.radius;
        saved.half_height = live.half_height;
        saved.half_extents = live.half_extents;
        saved.friction = live.friction;
        if (k >= scene.collider_motions.size() || scene.collider_motions[k].empty()) saved.motion.origin = live.motion.origin;
    }

    // Pins: the scene's rules while they still say what the world pins, vertex lists once pins were
    // added or removed live (World::pin/unpin).
    using PinKey = std::pair<std::uint32_t, int>;  // vertex, motion index
    const auto pin_set = [](const std::vector<PinDesc>& pins) {
        std::vector<PinKey> keys;
        for (const PinDesc& p : pins) keys.emplace_back(p.vertex, p.motion);
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
        if (pin_set(scene_pins(scene, i, *model.cloths[i].fabric)) == live_pins[i]) continue;
        cloth.desc.pins.clear();
        cloth.pins.clear();
        for (const auto& [vertex, motion] : live_pins[i]) {
            const std::string name =
                motion >= 0 && static_cast<std::size_t>(motion) < scene.motions.size() ? scene.motions[motion].name : "";
            auto rule = std::find_if(cloth.pins.begin(), cloth.pins.end(),
                                     [&](const PinSelection& s) { return s.motion == name; });
            if (rule == cloth.pins.end()) {
                PinSelection s;
                s.kind = PinSelection::Kind::Vertices;
                s.motion = name;
                rule = cloth.pins.insert(cloth.pins.end(), std::move(s));
            }
            rule->vertices.push_back(vertex);  // ascending: live_pins is sorted
        }
    }
}

}  // namespace weft
