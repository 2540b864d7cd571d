// Scene files: TOML text → validated SceneDesc. The format is documented key by key in
// docs/scene-format.md; keep the two in step. Every key is read through scene_toml::Table, which
// checks its type and range and reports unknown keys, so a typo never silently becomes a default.
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
#include "weft/scene.h"

namespace weft {
namespace {

using scene_toml::Range;
using scene_toml::Table;

constexpr double kHuge = 1e9;  // bound on lengths and speeds: finite, and far beyond any real scene

// Rotation from Euler angles in degrees [x, y, z]: about the world X axis first, then Y, then Z
// (R = Rz·Ry·Rx). Degrees because people type them; the angular *velocity* of a motion stays in rad/s.
Mat3d rotation_from_euler_degrees(Vec3d degrees) {
    const double k = std::numbers::pi / 180.0;
    const double cx = std::cos(degrees.x * k), sx = std::sin(degrees.x * k);
    const double cy = std::cos(degrees.y * k), sy = std::sin(degrees.y * k);
    const double cz = std::cos(degrees.z * k), sz = std::sin(degrees.z * k);
    Mat3d rx = Mat3d::identity(), ry = Mat3d::identity(), rz = Mat3d::identity();
    rx.m[1][1] = cx; rx.m[1][2] = -sx; rx.m[2][1] = sx; rx.m[2][2] = cx;
    ry.m[0][0] = cy; ry.m[0][2] = sy; ry.m[2][0] = -sy; ry.m[2][2] = cy;
    rz.m[0][0] = cz; rz.m[0][1] = -sz; rz.m[1][0] = sz; rz.m[1][1] = cz;
    return rz * (ry * rx);
}

// Reads `name`, requiring it to be unique among `seen` (names are how --set and pins refer to things).
std::string unique_name(Table& t, const std::string& fallback, std::set<std::string>& seen) {
    const toml::node* node = t.find("name");
    std::string name = t.optional_string("name").value_or(fallback);
    if (!seen.insert(name).second) t.fail("name", node, "duplicate name '" + name + "' (expected a unique name)");
    return name;
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
    std::string expected;
    for (const std::string& n : names) expected += (expected.empty() ? "'" : ", '") + n + "'";
    const std::string guess = scene_toml::closest(*name, names);
    t.fail("motion", node,
           "unknown motion '" + *name + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
               (names.empty() ? " (expected the name of a [[motion]]; the scene defines none)"
                              : " (expected one of " + expected + ")"));
}

void read_scene_section(Table& root, SceneDesc& scene) {
    auto t = root.table("scene");
    if (!t) return;
    if (auto name = t->optional_string("name")) scene.name = *name;
    scene.frames = t->integer("frames", scene.frames, 1, 10'000'000);
    t->finish();
}

void read_solver(Table& root, SolverSettings& s) {
    auto t = root.table("solver");
    if (!t) return;
    s.dt = t->number("dt", s.dt, {1e-5, 0.1});
    s.substeps = t->integer("substeps", s.substeps, 1, 1000);
    s.newton_iterations = t->integer("newton_iterations", s.newton_iterations, 1, 50);
    s.cg_tolerance = t->number("cg_tolerance", s.cg_tolerance, {1e-12, 1.0});
    s.cg_max_iterations = t->integer("cg_max_iterations", s.cg_max_iterations, 1, 100000);
    s.cg_warm_start = t->boolean("cg_warm_start", s.cg_warm_start);
    if (auto p = t->choice("precision", {"float", "double"})) s.precision = *p == 0 ? Precision::Float : Precision::Double;
    if (auto h = t->choice("hessian", {"fast", "projected"}))
        s.hessian = *h == 0 ? HessianMode::Fast : HessianMode::Projected;
    s.contact_stiffness = t->number("contact_stiffness", s.contact_stiffness, {0.0, 1e12});
    s.threads = t->integer("threads", s.threads, 0, 1024);
    t->finish();
}

void read_world(Table& root, WorldDesc& w) {
    if (auto t = root.table("world")) {
        w.gravity = t->vec3("gravity", w.gravity);
        if (math::length(w.gravity) > 1000.0)
            t->fail("gravity", t->find("gravity"), "magnitude is over 1000 m/s² (expected a vector of at most 1000 m/s²)");
        t->finish();
    }
    if (auto t = root.table("wind")) {
        WindDesc& wind = w.wind;
        wind.velocity = t->vec3("velocity", wind.velocity);
        if (math::length(wind.velocity) > 1000.0)
            t->fail("velocity", t->find("velocity"), "speed is over 1000 m/s (expected a vector of at most 1000 m/s)");
        wind.air_density = t->number("air_density", wind.air_density, {0.0, 100.0});
        wind.turbulence = t->number("turbulence", wind.turbulence, {0.0, 1000.0});
        wind.turbulence_frequency = t->number("turbulence_frequency", wind.turbulence_frequency, {0.0, 1000.0});
        wind.turbulence_scale = t->number("turbulence_scale", wind.turbulence_scale, {1e-3, 1e6});
        t->finish();
    }
}

void read_collision(Table& root, CollisionSettings& c) {
    auto t = root.table("collision");
    if (!t) return;
    c.self_collision = t->boolean("self", c.self_collision);
    c.continuous = t->boolean("continuous", c.continuous);
    if (auto k = t->choice("culling", {"normal_cone", "none"}))
        c.culling = *k == 0 ? CollisionCulling::NormalCone : CollisionCulling::None;
    c.cull_contacts = t->boolean("cull_contacts", c.cull_contacts);
    c.count_culled = t->boolean("count_culled", c.count_culled);
    c.rest_exclusion = t->number("rest_exclusion", c.rest_exclusion, {0.0, 10.0});
    c.thickness = t->number("thickness", c.thickness, {0.0, 0.1});
    c.stiffness = t->number("stiffness", c.stiffness, {0.0, 1e9});
    c.max_impact_iterations = t->integer("max_impact_iterations", c.max_impact_iterations, 1, 1000);
    c.impact_tolerance = t->number("impact_tolerance", c.impact_tolerance, {0.0, 0.5});
    c.max_impact_sweeps = t->integer("max_impact_sweeps", c.max_impact_sweeps, 0, 100000);
    c.check = t->boolean("check", c.check);
    t->finish();
}

void read_motions(Table& root, SceneDesc& scene) {
    std::set<std::string> names;
    for (Table& t : root.array_of_tables("motion")) {
        SceneMotion m;
        const toml::node* name_node = t.find("name");
        m.name = t.required_string("name", "a name that pins and colliders refer to");
        if (!names.insert(m.name).second)
            t.fail("name", name_node, "duplicate motion name '" + m.name + "' (expected a unique name)");
        m.motion.origin = t.vec3("origin", {});
        m.rotation_degrees = t.vec3("rotation", {});
        m.motion.initial_rotation = rotation_from_euler_degrees(m.rotation_degrees);
        m.motion.linear_velocity = t.vec3("linear_velocity", {});
        m.motion.angular_velocity = t.vec3("angular_velocity", {});
        m.motion.amplitude = t.vec3("amplitude", {});
        m.motion.frequency = t.number("frequency", 0.0, {0.0, 1000.0});
        m.motion.phase = t.number("phase", 0.0, {-kHuge, kHuge});
        t.finish();
        scene.motions.push_back(std::move(m));
    }
}

void read_material(Table& cloth, Material& m) {
    auto t = cloth.table("material");
    if (!t) return;
    m.stretch_stiffness = t->number("stretch_stiffness", m.stretch_stiffness, {1.0, 1e8});
    m.poisson_ratio = t->number("poisson_ratio", m.poisson_ratio, {0.0, 0.49});
    m.bending_stiffness = t->number("bending_stiffness", m.bending_stiffness, {0.0, 1.0});
    m.damping_mass = t->number("damping_mass", m.damping_mass, {0.0, 100.0});
    m.damping_stiffness = t->number("damping_stiffness", m.damping_stiffness, {0.0, 1.0});
    m.drag_coefficient = t->number("drag_coefficient", m.drag_coefficient, {0.0, 10.0});
    m.lift_coefficient = t->number("lift_coefficient", m.lift_coefficient, {0.0, 10.0});
    m.contact_thickness = t->number("contact_thickness", m.contact_thickness, {1e-5, 0.1});
    m.friction = t->number("friction", m.friction, {0.0, 10.0});
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
        src.width = grid->number("width", src.width, {0.0, 1000.0, true});
        src.height = grid->number("height", src.height, {0.0, 1000.0, true});
        if (const toml::node* cells = grid->find("cells")) {
            constexpr std::string_view cells_expected = "an array of 2 integers [nx, ny], each in [1, 4096]";
            const auto* a = cells->as_array();
            if (a == nullptr || a->size() != 2)
                grid->fail("cells", cells,
                           "got " + scene_toml::describe(*cells) +
                               (a != nullptr ? " of " + std::to_string(a->size()) + " elements" : "") + " (expected " +
                               std::string(cells_expected) + ")");
            int n[2] = {};
            for (std::size_t k = 0; k < 2; ++k) {
                const toml::node& e = (*a)[k];
                const auto* i = e.as_integer();
                if (i == nullptr || i->get() < 1 || i->get() > 4096)
                    grid->fail("cells", &e,
                               "element " + std::to_string(k) + " is " + scene_toml::describe(e) + " (expected " +
                                   std::string(cells_expected) + ")");
                n[k] = static_cast<int>(i->get());
            }
            src.cells_x = n[0];
            src.cells_y = n[1];
        }
        if (auto plane = grid->choice("plane", {"xy", "xz"})) src.plane = *plane == 0 ? GridPlane::XY : GridPlane::XZ;
        grid->finish();
    } else {
        src.kind = ClothSource::Kind::File;
        src.file = mesh_file(*mesh, "file", scene_path);
        src.scale = mesh->number("scale", src.scale, {0.0, 1e6, true});
    }
    mesh->finish();
}

PinSelection read_pin(Table& t, const ClothSource& src, const std::vector<SceneMotion>& motions) {
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
        const auto which = corners ? t.choice(key, {"top", "bottom", "left", "right", "all"})
                                   : t.choice(key, {"top", "bottom", "left", "right"});
        if (!grid)
            t.fail(key, n, std::string(key) + " pins need a grid mesh (expected vertices or box for a mesh file)");
        pin.kind = corners ? PinSelection::Kind::Corners : PinSelection::Kind::Edge;
        pin.edge = n->as_string()->get();
        (void)which;
    }
    pin.motion = motion_reference(t, motions);
    t.finish();
    return pin;
}

// `repeat = { count, offset, rotation_step }`: copies of one cloth for stacks of sheets at any count.
struct Repeat {
    int count = 1;
    Vec3d offset{};         // m, added once per copy
    Vec3d rotation_step{};  // degrees, added to the Euler angles once per copy
};

std::optional<Repeat> read_repeat(Table& cloth) {
    auto t = cloth.table("repeat");
    if (!t) return std::nullopt;
    Repeat r;
    if (!t->has("count"))
        t->fail_here("count", "missing required key (expected an integer in [1, 10000], the number of copies)");
    r.count = t->integer("count", r.count, 1, 10000);
    r.offset = t->vec3("offset", r.offset);
    r.rotation_step = t->vec3("rotation_step", r.rotation_step);
    t->finish();  // a misspelt offset is reported as such, not as a missing one
    if (r.count > 1 && r.offset == Vec3d{} && r.rotation_step == Vec3d{})
        t->fail("offset", t->find("offset"),
                "the copies would all lie on the first (expected a non-zero offset or rotation_step)");
    const Vec3d last = static_cast<double>(r.count - 1) * r.offset;
    if (!math::is_finite(last))
        t->fail("offset", t->find("offset"), "the last copy's offset is not finite (expected a smaller offset)");
    return r;
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
        const std::string name = unique_name(t, "cloth" + std::to_string(i), entry_names);
        read_mesh(t, c.source, scene.path);
        const Vec3d position = t.vec3("position", {});
        const Vec3d rotation = t.vec3("rotation", {});
        c.desc.initial_velocity = t.vec3("initial_velocity", {});
        c.fabric.density = t.number("density", c.fabric.density, {0.0, 100.0, true});
        c.fabric.flat_rest_bending = t.boolean("flat_rest_bending", c.fabric.flat_rest_bending);
        read_material(t, c.desc.material);
        for (Table& p : t.array_of_tables("pin")) c.pins.push_back(read_pin(p, c.source, scene.motions));
        const std::optional<Repeat> repeat = read_repeat(t);
        ClothPlacement placement;
        placement.name = name;
        placement.position = position;
        placement.rotation_degrees = rotation;
        if (repeat) {
            placement.repeat_count = repeat->count;
            placement.repeat_offset = repeat->offset;
            placement.repeat_rotation_step = repeat->rotation_step;
        }
        scene.cloth_placements.push_back(placement);
        // Copy k is named NAME<k> and placed at position + k·offset, turned by rotation + k·rotation_step;
        // a cloth without repeat is the single copy 0 under its own name.
        const int copies = repeat ? repeat->count : 1;
        for (int k = 0; k < copies; ++k) {
            SceneCloth copy = c;
            copy.desc.name = repeat ? name + std::to_string(k) : name;
            const double steps = static_cast<double>(k);
            copy.desc.transform.translation = repeat ? position + steps * repeat->offset : position;
            copy.desc.transform.rotation =
                rotation_from_euler_degrees(repeat ? rotation + steps * repeat->rotation_step : rotation);
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
        const auto shape = t.choice("shape", {"plane", "sphere", "capsule", "box", "mesh"});
        if (!shape)
            t.fail_here("shape",
                        "missing required key (expected one of \"plane\", \"sphere\", \"capsule\", \"box\", \"mesh\")");
        constexpr ColliderShape shapes[] = {ColliderShape::Plane, ColliderShape::Sphere, ColliderShape::Capsule,
                                            ColliderShape::Box, ColliderShape::Mesh};
        c.shape = shapes[*shape];
        const std::string shape_name = std::string(t.raw().get("shape")->as_string()->get());
        const bool round = c.shape == ColliderShape::Sphere || c.shape == ColliderShape::Capsule;
        if (round) c.radius = t.number("radius", c.radius, {1e-6, 1e6});
        else t.reject("radius", "a " + shape_name + " collider has no radius (expected radius only for sphere and capsule)");
        if (c.shape == ColliderShape::Capsule) c.half_height = t.number("half_height", c.half_height, {0.0, 1e6});
        else t.reject("half_height", "a " + shape_name + " collider has no half_height (expected half_height only for capsule)");
        if (c.shape == ColliderShape::Box) {
            c.half_extents = t.vec3("half_extents", c.half_extents);
            for (int k = 0; k < 3; ++k)
                if (!(c.half_extents[k] >= 1e-6 && c.half_extents[k] <= 1e6))
                    t.fail("half_extents", t.find("half_extents"),
                           "component " + std::to_string(k) + " is " + scene_toml::format_number(c.half_extents[k]) +
                               " (expected 3 numbers in [1e-6, 1e6], m)");
        } else {
            t.reject("half_extents", "a " + shape_name + " collider has no half_extents (expected half_extents only for box)");
        }
        if (c.shape == ColliderShape::Mesh) {
            // The triangles are read by build_world(), as a cloth's mesh file is; the file must exist now.
            mesh.file = mesh_file(t, "file", scene.path);
            mesh.scale = t.number("scale", mesh.scale, {0.0, 1e6, true});
        } else {
            t.reject("file", "a " + shape_name + " collider has no file (expected file only for shape = \"mesh\")");
            t.reject("scale", "a " + shape_name + " collider has no scale (expected scale only for shape = \"mesh\")");
        }
        if (auto f = t.optional_number("friction", {0.0, 10.0})) c.friction = *f;
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
            c.motion.origin = t.vec3("position", {});
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
    camera.position = t->vec3("position", camera.position);
    camera.target = t->vec3("target", camera.target);
    camera.fov_degrees = t->number("fov", camera.fov_degrees, {0.0, 180.0, true, true});
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
    read_solver(root, scene.world.solver);
    read_world(root, scene.world);
    read_collision(root, scene.world.collision);
    read_motions(root, scene);  // before cloths and colliders, which refer to motions by name
    read_cloths(root, scene);
    read_colliders(root, scene);
    read_camera(root, scene.camera);
    root.finish();
    return scene;
}

SceneDesc load_scene(const std::filesystem::path& path, std::span<const std::string> overrides) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path.string() + ": cannot open scene file");
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw Error(path.string() + ": cannot read scene file");
    return parse_scene(text.str(), path, overrides);
}

}  // namespace weft
