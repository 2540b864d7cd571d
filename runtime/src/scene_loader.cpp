// Scene files: TOML text → validated SceneDesc. The keys, their types and ranges are those of the
// parameter table (weft/parameters.h), which docs/scene-format.md is generated from; this file reads
// the table's values generically and handles by hand only what has structure (names, meshes, pins,
// references). Every key is read through scene_toml::Table, which checks its type and range and
// reports unknown keys, so a typo never silently becomes a default.
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>

#include "scene_overrides.h"
#include "scene_reader.h"
#include "weft/error.h"
#include "weft/world_limits.h"
#include "weft/parameters.h"
#include "weft/presets.h"
#include "weft/scene.h"

namespace weft {
namespace {

using scene_toml::Table;

// Reads parameter `p` from `t` into `owner` when the key is present, checking its type and range.
template <class Owner>
void read_value(Table& t, const Parameter& p, Owner& owner) {
    switch (p.type) {
        case ParameterType::Real:
            if (auto v = t.optional_number(p.name, p.range)) set_parameter_number(p, owner, *v);
            return;
        case ParameterType::Integer: {
            const auto current = static_cast<int>(std::lround(parameter_number(p, owner)));
            set_parameter_number(p, owner,
                                 t.integer(p.name, current, std::llround(p.range.lo), std::llround(p.range.hi)));
            return;
        }
        case ParameterType::Boolean:
            set_parameter_number(p, owner, t.boolean(p.name, parameter_number(p, owner) != 0.0) ? 1.0 : 0.0);
            return;
        case ParameterType::Choice:
            if (auto i = t.choice(p.name, p.choices)) set_parameter_number(p, owner, static_cast<double>(*i));
            return;
        case ParameterType::Vector: {
            const auto v = t.optional_vec3(p.name);
            if (!v) return;
            const std::string unit = p.unit.empty() ? std::string() : " " + std::string(p.unit);
            if (p.vector_bound == VectorBound::Length && !p.range.contains(math::length(*v))) {
                const std::string limit = scene_toml::format_number(p.range.hi) + unit;
                t.fail(p.name, t.find(p.name), "magnitude is over " + limit + " (expected a vector of at most " + limit + ")");
            }
            if (p.vector_bound == VectorBound::Components)
                for (int k = 0; k < 3; ++k)
                    if (!p.range.contains((*v)[k]))
                        t.fail(p.name, t.find(p.name),
                               "component " + std::to_string(k) + " is " + scene_toml::format_number((*v)[k]) +
                                   " (expected 3 numbers in " + p.range.text() + (p.unit.empty() ? "" : ", ") +
                                   std::string(p.unit) + ")");
            set_parameter_vector(p, owner, *v);
            return;
        }
        case ParameterType::CellCounts: {
            const toml::node* cells = t.find(p.name);
            if (cells == nullptr) return;
            const std::string expected = "an array of 2 integers [nx, ny], each in " + p.range.integer_text();
            const auto* a = cells->as_array();
            if (a == nullptr || a->size() != 2)
                t.fail(p.name, cells,
                       "got " + scene_toml::describe(*cells) +
                           (a != nullptr ? " of " + std::to_string(a->size()) + " elements" : "") + " (expected " +
                           expected + ")");
            Vec3d n{};
            for (std::size_t k = 0; k < 2; ++k) {
                const toml::node& e = (*a)[k];
                const auto* i = e.as_integer();
                if (i == nullptr || !p.range.contains(static_cast<double>(i->get())))
                    t.fail(p.name, &e,
                           "element " + std::to_string(k) + " is " + scene_toml::describe(e) + " (expected " + expected + ")");
                n[static_cast<int>(k)] = static_cast<double>(i->get());
            }
            set_parameter_vector(p, owner, n);
            return;
        }
        default: throw Error("parameter '" + p.key() + "' has a field but no reader for its type");
    }
}

// Reads every parameter of `section` that one of `owners` holds, in the table's order (so that the
// keys a table knows, and the first error in it, are found in that order). Keys without a field
// (names, meshes, pins) are left to the caller.
template <class... Owners>
void read_parameters(Table& t, std::string_view section, Owners&... owners) {
    for (const Parameter& p : parameter_table())
        if (p.section == section) (void)((holds<Owners>(p) ? (read_value(t, p, owners), true) : false) || ...);
}

// Reads `name`, requiring it to be unique among `seen` (names are how --set and pins refer to things).
std::string unique_name(Table& t, const std::string& fallback, std::set<std::string>& seen) {
    const toml::node* node = t.find("name");
    std::string name = t.optional_string("name").value_or(fallback);
    if (!seen.insert(name).second) t.fail("name", node, "duplicate name '" + name + "' (expected a unique name)");
    return name;
}

// Fails `key` for a name that is none of `names`: the closest one as a guess, and all of them (or
// `none`, the sentence for a scene without any).
[[noreturn]] void fail_unknown_name(Table& t, const char* key, const toml::node* node, const std::string& what,
                                    const std::string& name, const std::vector<std::string>& names,
                                    const std::string& none) {
    std::string expected;
    for (const std::string& n : names) expected += (expected.empty() ? "'" : ", '") + n + "'";
    const std::string guess = scene_toml::closest(name, names);
    t.fail(key, node,
           "unknown " + what + " '" + name + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
               (names.empty() ? " (" + none + ")" : " (expected one of " + expected + ")"));
}

// A reference to a `[[motion]]` by name.
std::string motion_reference(Table& t, const std::vector<SceneMotion>& motions) {
    const toml::node* node = t.find("motion");
    auto name = t.optional_string("motion");
    if (!name) return {};
    std::vector<std::string> names;
    for (const SceneMotion& m : motions) {
        if (m.name == *name) return *name;
        names.push_back(m.name);
    }
    fail_unknown_name(t, "motion", node, "motion", *name, names,
                      "expected the name of a [[motion]]; the scene defines none");
}

// `shape = "sphere" or "capsule"`: the collider shapes that have key `p`.
std::string shapes_having(const Parameter& p) {
    const auto names = parameter("collider", "shape").choices;
    std::vector<std::string_view> having;
    for (std::size_t s = 0; s < names.size(); ++s)
        if (p.applies_to(static_cast<ColliderShape>(s))) having.push_back(names[s]);
    std::string text = "shape = ";
    for (std::size_t k = 0; k < having.size(); ++k)
        text.append(k == 0 ? "\"" : k + 1 == having.size() ? " or \"" : ", \"").append(having[k]).append("\"");
    return text;
}

void read_scene_section(Table& root, SceneDesc& scene) {
    auto t = root.table("scene");
    if (!t) return;
    if (auto name = t->optional_string("name")) scene.name = *name;
    read_parameters(*t, "scene", scene);
    t->finish();
}

// `preset = "NAME"` in [solver]: the preset's values (weft/presets.h) into `w`.
void apply_solver_preset(Table& t, WorldDesc& w) {
    const toml::node* node = t.find("preset");
    const std::optional<std::string> name = t.optional_string("preset");
    if (!name) return;
    if (find_preset(solver_presets(), *name) == nullptr) {
        std::vector<std::string> names;
        for (const Preset& p : solver_presets()) names.push_back(p.name);
        const std::string guess = scene_toml::closest(*name, names);
        t.fail("preset", node,
               "unknown solver preset '" + *name + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
                   " (expected one of " + preset_names(solver_presets()) + ")");
    }
    apply_solver_preset(w, *name);
}

// [solver], [world], [wind] and [collision]: every key is a field of WorldDesc.
void read_world(Table& root, WorldDesc& w) {
    for (const std::string_view section : {"solver", "world", "wind", "collision"}) {
        if (auto t = root.table(section)) {
            if (section == "solver") apply_solver_preset(*t, w);  // first: the table's own keys win
            read_parameters(*t, section, w);
            t->finish();
        }
    }
}

void read_motions(Table& root, SceneDesc& scene) {
    std::set<std::string> names;
    for (Table& t : root.array_of_tables("motion")) {
        SceneMotion m;
        const toml::node* name_node = t.find("name");
        m.name = t.required_string("name", "a name that pins and colliders refer to");
        if (!names.insert(m.name).second)
            t.fail("name", name_node, "duplicate motion name '" + m.name + "' (expected a unique name)");
        read_parameters(t, "motion", m.motion, m);
        m.motion.initial_rotation = rotation_from_euler_degrees(m.rotation_degrees);
        t.finish();
        scene.motions.push_back(std::move(m));
    }
}

void read_material(Table& cloth, Material& m) {
    auto t = cloth.table("material");
    if (!t) return;
    read_parameters(*t, "cloth.material", m);
    t->finish();
}

// A mesh file named by `key`, resolved relative to the scene file; it must exist now, so that a typo
// in a path is reported with the line it is on rather than when the world is built.
std::filesystem::path mesh_file(Table& t, std::string_view key, const std::filesystem::path& scene_path) {
    const toml::node* node = t.find(key);
    const std::string file = t.required_string(key, "a mesh file path, relative to the scene file");
    std::filesystem::path p(file);
    if (p.is_relative()) p = scene_path.parent_path() / p;
    p = p.lexically_normal();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(p, ec))
        t.fail(key, node, "mesh file not found: " + p.string() + " (expected a path relative to the scene file)");
    return p;
}

void read_mesh(Table& cloth, ClothSource& src, const std::filesystem::path& scene_path) {
    constexpr std::string_view expected =
        "a table with either grid = { width, height, cells, plane } or file = \"mesh.obj\"";
    auto mesh = cloth.table("mesh");
    if (!mesh) cloth.fail_here("mesh", "missing required key (expected " + std::string(expected) + ")");
    const bool has_grid = mesh->has("grid");
    const bool has_file = mesh->has("file");
    if (has_grid == has_file)
        mesh->fail_here(has_grid ? "file" : "grid",
                        std::string(has_grid ? "both grid and file are given" : "neither grid nor file is given") +
                            " (expected " + std::string(expected) + ")");
    if (has_grid) {
        src.kind = ClothSource::Kind::Grid;
        mesh->reject("scale", "only applies to mesh files (expected no scale with grid)");
        auto grid = mesh->table("grid");
        read_parameters(*grid, "cloth.mesh.grid", src);
        grid->finish();
    } else {
        src.kind = ClothSource::Kind::File;
        src.file = mesh_file(*mesh, "file", scene_path);
        read_parameters(*mesh, "cloth.mesh", src);
    }
    mesh->finish();
}

// `follow = "NAME"`: a mesh collider of the scene (read before the cloths) whose skin the pins follow.
std::string follow_reference(Table& t, const std::vector<ColliderDesc>& colliders) {
    const toml::node* node = t.find("follow");
    auto name = t.optional_string("follow");
    if (!name) return {};
    if (t.has("motion"))
        t.fail("follow", node, "follow and motion together (expected one: a pin follows a motion or a collider's skin)");
    std::vector<std::string> meshes;
    for (const ColliderDesc& c : colliders) {
        if (c.name == *name && c.shape == ColliderShape::Mesh) return *name;
        if (c.name == *name)
            t.fail("follow", node, "collider '" + *name + "' is not a mesh (expected a mesh collider, whose vertices pins can follow)");
        if (c.shape == ColliderShape::Mesh) meshes.push_back(c.name);
    }
    fail_unknown_name(t, "follow", node, "collider", *name, meshes,
                      "expected the name of a mesh [[collider]]; the scene has none");
}

PinSelection read_pin(Table& t, const ClothSource& src, const SceneDesc& scene) {
    const std::vector<SceneMotion>& motions = scene.motions;
    constexpr std::string_view expected =
        "exactly one of vertices = [...], box = { min = [...], max = [...] }, edge = \"top\", corners = \"top\"";
    PinSelection pin;
    const char* kinds[] = {"vertices", "box", "edge", "corners"};
    int given = 0;
    for (const char* k : kinds) given += t.has(k) ? 1 : 0;
    if (given != 1)
        t.fail_here(given == 0 ? "vertices" : "edge",
                    std::string(given == 0 ? "no selection given" : "more than one selection given") + " (expected " +
                        std::string(expected) + ")");
    const bool grid = src.kind == ClothSource::Kind::Grid;
    const std::size_t grid_vertices =
        static_cast<std::size_t>(src.cells_x + 1) * static_cast<std::size_t>(src.cells_y + 1);
    if (const toml::node* n = t.find("vertices")) {
        pin.kind = PinSelection::Kind::Vertices;
        constexpr std::string_view vexpected = "a non-empty array of vertex indices";
        const auto* a = n->as_array();
        if (a == nullptr) t.fail("vertices", n, "wrong type: got " + scene_toml::describe(*n) + " (expected " + std::string(vexpected) + ")");
        if (a->empty()) t.fail("vertices", n, "empty array (expected " + std::string(vexpected) + ")");
        for (std::size_t i = 0; i < a->size(); ++i) {
            const toml::node& e = (*a)[i];
            const auto* v = e.as_integer();
            if (v == nullptr || v->get() < 0 || v->get() > 0xFFFFFFFE)
                t.fail("vertices", &e, "element " + std::to_string(i) + " is " + scene_toml::describe(e) + " (expected " + std::string(vexpected) + ")");
            if (grid && static_cast<std::size_t>(v->get()) >= grid_vertices)
                t.fail("vertices", &e,
                       "vertex " + std::to_string(v->get()) + " is out of range (expected an index below " +
                           std::to_string(grid_vertices) + ", the grid's vertex count)");
            pin.vertices.push_back(static_cast<std::uint32_t>(v->get()));
        }
    }
    if (auto box = t.table("box")) {
        pin.kind = PinSelection::Kind::Box;
        auto lo = box->optional_vec3("min");
        auto hi = box->optional_vec3("max");
        if (!lo) box->fail_here("min", "missing required key (expected an array of 3 numbers, the box's lower corner in m)");
        if (!hi) box->fail_here("max", "missing required key (expected an array of 3 numbers, the box's upper corner in m)");
        for (int k = 0; k < 3; ++k)
            if ((*lo)[k] > (*hi)[k])
                box->fail("max", box->find("max"), "max is below min on axis " + std::string(1, "xyz"[k]) + " (expected min <= max)");
        pin.box_min = *lo;
        pin.box_max = *hi;
        box->finish();
    }
    for (const char* key : {"edge", "corners"}) {
        const bool corners = std::string_view(key) == "corners";
        const toml::node* n = t.find(key);
        if (n == nullptr) continue;
        const auto which = t.choice(key, parameter("cloth.pin", key).choices);
        if (!grid)
            t.fail(key, n, std::string(key) + " pins need a grid mesh (expected vertices or box for a mesh file)");
        pin.kind = corners ? PinSelection::Kind::Corners : PinSelection::Kind::Edge;
        pin.edge = n->as_string()->get();
        (void)which;
    }
    pin.follow = follow_reference(t, scene.colliders);
    if (const toml::node* n = t.find("joint")) {
        const auto joint = t.optional_string("joint");
        if (pin.follow.empty())
            t.fail("joint", n, "joint without follow (expected follow = \"COLLIDER\" naming the character the joint belongs to)");
        if (joint->empty()) t.fail("joint", n, "empty joint name (expected the name of a joint of the character's skeleton)");
        pin.joint = *joint;  // checked against the skeleton when build_world loads the character
    }
    pin.motion = motion_reference(t, motions);
    t.finish();
    return pin;
}

// `repeat = { count, offset, rotation_step }`: copies of one cloth for stacks of sheets at any count,
// read into the cloth table's placement (repeat_count stays 0 without a repeat table).
void read_repeat(Table& cloth, ClothPlacement& r) {
    auto t = cloth.table("repeat");
    if (!t) return;
    if (!t->has("count"))
        t->fail_here("count", "missing required key (expected an integer in " +
                                  parameter("cloth.repeat", "count").range.integer_text() + ", the number of copies)");
    read_parameters(*t, "cloth.repeat", r);
    t->finish();  // a misspelt offset is reported as such, not as a missing one
    if (r.repeat_count > 1 && r.repeat_offset == Vec3d{} && r.repeat_rotation_step == Vec3d{})
        t->fail("offset", t->find("offset"),
                "the copies would all lie on the first (expected a non-zero offset or rotation_step)");
    const Vec3d last = static_cast<double>(r.repeat_count - 1) * r.repeat_offset;
    if (!math::is_finite(last))
        t->fail("offset", t->find("offset"), "the last copy's offset is not finite (expected a smaller offset)");
}

void read_cloths(Table& root, SceneDesc& scene) {
    std::set<std::string> entry_names;  // of the [[cloth]] tables: what `--set cloth.NAME…` selects
    std::set<std::string> cloth_names;  // of the cloths, the copies that repeat makes included
    auto tables = root.array_of_tables("cloth");
    if (tables.empty())
        root.fail_here("cloth", "the scene has no cloth (expected at least one [[cloth]] section)");
    for (std::size_t i = 0; i < tables.size(); ++i) {
        Table& t = tables[i];
        SceneCloth c;
        c.entry = i;
        ClothPlacement placement;
        placement.name = unique_name(t, "cloth" + std::to_string(i), entry_names);
        const std::string& name = placement.name;
        read_mesh(t, c.source, scene.path);
        read_parameters(t, "cloth", placement, c.desc, c.fabric);  // position … flat_rest_bending
        read_material(t, c.desc.material);
        for (Table& p : t.array_of_tables("pin")) c.pins.push_back(read_pin(p, c.source, scene));
        read_repeat(t, placement);
        scene.cloth_placements.push_back(placement);
        // Copy k is named NAME<k> and placed at position + k·offset, turned by rotation + k·rotation_step;
        // a cloth without repeat is the single copy 0 under its own name.
        const bool repeat = placement.repeat_count > 0;
        const int copies = repeat ? placement.repeat_count : 1;
        for (int k = 0; k < copies; ++k) {
            SceneCloth copy = c;
            copy.desc.name = repeat ? name + std::to_string(k) : name;
            const double steps = static_cast<double>(k);
            copy.desc.transform.translation =
                repeat ? placement.position + steps * placement.repeat_offset : placement.position;
            copy.desc.transform.rotation = rotation_from_euler_degrees(
                repeat ? placement.rotation_degrees + steps * placement.repeat_rotation_step : placement.rotation_degrees);
            if (!cloth_names.insert(copy.desc.name).second)
                t.fail("name", t.find("name"),
                       "duplicate name '" + copy.desc.name +
                           "' (expected a unique name; repeat names its copies NAME0, NAME1, …)");
            scene.cloths.push_back(std::move(copy));
        }
        t.finish();
    }
}

void read_colliders(Table& root, SceneDesc& scene) {
    std::set<std::string> names;
    auto tables = root.array_of_tables("collider");
    for (std::size_t i = 0; i < tables.size(); ++i) {
        Table& t = tables[i];
        ColliderDesc c;
        ColliderMeshSource mesh;
        c.name = unique_name(t, "collider" + std::to_string(i), names);
        const Parameter& shape_key = parameter("collider", "shape");
        const auto shape = t.choice("shape", shape_key.choices);
        if (!shape) t.fail_here("shape", "missing required key (expected one of " + parameter_range_text(shape_key) + ")");
        c.shape = static_cast<ColliderShape>(*shape);  // the choices are listed in the order of ColliderShape
        const std::string shape_name(shape_key.choices[*shape]);
        // The keys of the shape: its sizes, a mesh's file and scale, and friction. A key of another
        // shape is an error (a radius on a box) rather than ignored.
        for (const Parameter& p : parameter_table()) {
            if (p.section != "collider" || p.name == "name" || p.name == "shape" || p.name == "position" ||
                p.name == "rotation" || p.name == "motion")
                continue;
            if (!p.applies_to(c.shape)) {
                t.reject(p.name, "a " + shape_name + " collider has no " + std::string(p.name) + " (expected " +
                                     std::string(p.name) + " only for " + shapes_having(p) + ")");
            } else if (p.name == "file") {
                // The triangles are read by build_world(), as a cloth's mesh file is; the file must exist now.
                mesh.file = mesh_file(t, "file", scene.path);
            } else if (p.name == "clip") {
                mesh.clip = t.optional_string("clip").value_or("");
            } else if (holds<ColliderDesc>(p)) {
                read_value(t, p, c);
            } else if (holds<ColliderMeshSource>(p)) {
                read_value(t, p, mesh);
            }
        }
        const std::string motion = motion_reference(t, scene.motions);
        Vec3d rotation_degrees{};
        if (!motion.empty()) {
            const std::string why = "a collider that follows a motion takes its frame from it (expected either motion or " +
                                    std::string("position/rotation)");
            t.reject("position", why);
            t.reject("rotation", why);
            for (const SceneMotion& m : scene.motions)
                if (m.name == motion) c.motion = m.motion;
        } else {
            read_value(t, parameter("collider", "position"), c);
            rotation_degrees = t.vec3("rotation", {});
            c.motion.initial_rotation = rotation_from_euler_degrees(rotation_degrees);
        }
        t.finish();
        scene.collider_rotation_degrees.push_back(rotation_degrees);
        scene.colliders.push_back(std::move(c));
        scene.collider_motions.push_back(motion);
        scene.collider_meshes.push_back(std::move(mesh));
    }
}

void read_camera(Table& root, CameraDesc& camera) {
    auto t = root.table("camera");
    if (!t) return;
    read_parameters(*t, "camera", camera);
    if (camera.position == camera.target)
        t->fail("target", t->find("target"), "target equals position (expected a point the camera looks at)");
    t->finish();
}

}  // namespace

SceneDesc parse_scene(std::string_view toml_text, const std::filesystem::path& name,
                      std::span<const std::string> overrides) {
    const std::string file = name.string();
    toml::table document;
    try {
        document = toml::parse(toml_text, file);
    } catch (const toml::parse_error& e) {
        throw Error(scene_toml::location(e.source(), file) + "syntax error: " + std::string(e.description()));
    }
    scene_toml::apply_overrides(document, overrides);

    SceneDesc scene;
    scene.path = name;
    scene.name = name.stem().string();
    Table root(document, "", file);
    read_scene_section(root, scene);
    read_world(root, scene.world);
    read_motions(root, scene);    // before cloths and colliders, which refer to motions by name
    read_colliders(root, scene);  // before cloths, whose pins may follow a mesh collider by name
    read_cloths(root, scene);
    read_camera(root, scene.camera);
    root.finish();
    return scene;
}

SceneDesc load_scene(const std::filesystem::path& path, std::span<const std::string> overrides) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path.string() + ": cannot open scene file");
    check_file_size(path, kMaxTextFileBytes, "scene file");
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw Error(path.string() + ": cannot read scene file");
    return parse_scene(text.str(), path, overrides);
}

}  // namespace weft
