// The parameter table (weft/parameters.h): every shipped scene (and the complete example of
// docs/scene-format.md, which has the shapes no shipped scene uses) loads, saves and reloads with
// every table value the same bit for bit; every key documented in docs/scene-format.md is in the
// table and every table key is documented; rows are consistent with the fields they reach; defaults
// come from the structs and lie in range; the loader and World refuse what the table's ranges refuse.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "scene_test_util.h"
#include "weft/parameters.h"
#include "weft/scene.h"
#include "weft/world.h"

namespace weft {
namespace {

using test::expect_error;

std::string read_text(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

std::filesystem::path scene_format_doc() { return test::source_dir() / "docs" / "scene-format.md"; }

// The `toml` block under "## Complete example" of docs/scene-format.md.
std::string documented_example() {
    const std::string text = read_text(scene_format_doc());
    const auto heading = text.find("## Complete example");
    const auto begin = text.find("```toml\n", heading);
    const auto end = text.find("```", begin + 8);
    if (heading == std::string::npos || begin == std::string::npos || end == std::string::npos) return {};
    return text.substr(begin + 8, end - begin - 8);
}

// Compares every table value held by `a` and `b` (structs of one type) bit for bit; counts the rows
// compared in `seen`.
template <class Owner>
void expect_same_values(const Owner& a, const Owner& b, const std::string& where, std::map<std::string, int>& seen,
                        std::optional<ColliderShape> shape = std::nullopt) {
    for (const Parameter& p : parameter_table()) {
        if (!holds<Owner>(p) || (shape && !p.applies_to(*shape))) continue;
        ++seen[p.key()];
        if (p.access.number != nullptr) {
            const double x = parameter_number(p, a), y = parameter_number(p, b);
            EXPECT_EQ(std::memcmp(&x, &y, sizeof x), 0) << where << ": " << p.key() << " " << x << " became " << y;
        } else {
            const Vec3d x = parameter_vector(p, a), y = parameter_vector(p, b);
            EXPECT_EQ(std::memcmp(&x, &y, sizeof x), 0)
                << where << ": " << p.key() << " [" << x.x << ", " << x.y << ", " << x.z << "] became [" << y.x << ", "
                << y.y << ", " << y.z << "]";
        }
    }
}

void expect_same_table_values(const SceneDesc& a, const SceneDesc& b, std::map<std::string, int>& seen) {
    const std::string file = a.path.filename().string();
    expect_same_values(a, b, file, seen);
    expect_same_values(a.world, b.world, file, seen);
    expect_same_values(a.camera, b.camera, file, seen);
    ASSERT_EQ(a.cloths.size(), b.cloths.size()) << file;
    for (std::size_t i = 0; i < a.cloths.size(); ++i) {
        const std::string where = file + " cloth " + a.cloths[i].desc.name;
        expect_same_values(a.cloths[i].desc, b.cloths[i].desc, where, seen);
        expect_same_values(a.cloths[i].desc.material, b.cloths[i].desc.material, where, seen);
        expect_same_values(a.cloths[i].fabric, b.cloths[i].fabric, where, seen);
        // A grid has width, height, cells and plane; a mesh file its scale.
        const bool grid = a.cloths[i].source.kind == ClothSource::Kind::Grid;
        for (const Parameter& p : parameter_table()) {
            if (!holds<ClothSource>(p) || (p.section == "cloth.mesh.grid") != grid) continue;
            ++seen[p.key()];
            const Vec3d x = p.access.vector != nullptr ? parameter_vector(p, a.cloths[i].source)
                                                       : Vec3d{parameter_number(p, a.cloths[i].source), 0.0, 0.0};
            const Vec3d y = p.access.vector != nullptr ? parameter_vector(p, b.cloths[i].source)
                                                       : Vec3d{parameter_number(p, b.cloths[i].source), 0.0, 0.0};
            EXPECT_EQ(std::memcmp(&x, &y, sizeof x), 0) << where << ": " << p.key();
        }
    }
    ASSERT_EQ(a.cloth_placements.size(), b.cloth_placements.size()) << file;
    for (std::size_t e = 0; e < a.cloth_placements.size(); ++e) {
        // The repeat keys only where the table has a repeat.
        if (a.cloth_placements[e].repeat_count > 0) {
            expect_same_values(a.cloth_placements[e], b.cloth_placements[e], file + " " + a.cloth_placements[e].name, seen);
        } else {
            for (const std::string_view key : {"position", "rotation"}) {
                const Parameter& p = parameter("cloth", key);
                ++seen[p.key()];
                const Vec3d x = parameter_vector(p, a.cloth_placements[e]), y = parameter_vector(p, b.cloth_placements[e]);
                EXPECT_EQ(std::memcmp(&x, &y, sizeof x), 0) << file << ": " << p.key();
            }
            EXPECT_EQ(b.cloth_placements[e].repeat_count, 0) << file;
        }
    }
    ASSERT_EQ(a.motions.size(), b.motions.size()) << file;
    for (std::size_t m = 0; m < a.motions.size(); ++m) {
        expect_same_values(a.motions[m], b.motions[m], file + " motion " + a.motions[m].name, seen);
        expect_same_values(a.motions[m].motion, b.motions[m].motion, file + " motion " + a.motions[m].name, seen);
    }
    ASSERT_EQ(a.colliders.size(), b.colliders.size()) << file;
    for (std::size_t k = 0; k < a.colliders.size(); ++k) {
        const ColliderDesc& c = a.colliders[k];
        const std::string where = file + " collider " + c.name;
        EXPECT_EQ(c.shape, b.colliders[k].shape) << where;
        expect_same_values(c, b.colliders[k], where, seen, c.shape);
        if (c.shape == ColliderShape::Mesh)
            expect_same_values(a.collider_meshes[k], b.collider_meshes[k], where, seen, c.shape);
    }
}

// load → save → load keeps every value the table lists, bit for bit, for every shipped scene and
// the documented example; between them they reach every row that has a field.
TEST(ParameterTable, RoundTripsEveryShippedScene) {
    const auto scenes = test::source_dir() / "assets" / "scenes";
    std::map<std::string, int> seen;
    int count = 0;
    for (const auto& entry : std::filesystem::directory_iterator(scenes)) {
        if (entry.path().extension() != ".toml") continue;
        SCOPED_TRACE(entry.path().filename().string());
        const SceneDesc original = load_scene(entry.path());
        const SceneDesc reloaded = parse_scene(scene_to_toml(original, scenes), scenes / entry.path().filename());
        expect_same_table_values(original, reloaded, seen);
        ++count;
    }
    EXPECT_GE(count, 10);
    const std::string example = documented_example();
    ASSERT_FALSE(example.empty()) << "no complete example in docs/scene-format.md";
    const SceneDesc original = parse_scene(example, scene_format_doc());
    const SceneDesc reloaded = parse_scene(scene_to_toml(original, scene_format_doc().parent_path()), scene_format_doc());
    expect_same_table_values(original, reloaded, seen);

    for (const Parameter& p : parameter_table()) {
        if (p.access.owner != ParameterOwner::None) {
            EXPECT_GT(seen[p.key()], 0) << p.key() << " was compared in no scene: add a scene that sets it";
        }
    }
}

// The saved text names every table key that applies: a scene file says everything it means.
TEST(ParameterTable, TheWriterWritesEveryKeyWithAField) {
    const SceneDesc scene = parse_scene(documented_example(), scene_format_doc());
    const std::string text = scene_to_toml(scene, scene_format_doc().parent_path());
    for (const Parameter& p : parameter_table()) {
        if (p.access.owner == ParameterOwner::None || p.section.starts_with("cloth.repeat") || p.name == "scale" ||
            p.name.starts_with("clip") || p.unset_when_negative)
            continue;  // no repeat in the example, a grid cloth and no mesh collider, friction set on two colliders
        const std::string assignment = std::string(p.name) + " = ";  // a line's key, or one in an inline table
        EXPECT_TRUE(text.find("\n" + assignment) != std::string::npos || text.find(" " + assignment) != std::string::npos)
            << p.key();
    }
}

// The key tables of docs/scene-format.md are the table's, section by section (the text itself is
// compared in tests/cli/test_scene_keys_doc.cpp, where the generator lives), and none is written by hand.
TEST(ParameterTable, CoversEveryKeyOfTheSceneFormatDoc) {
    std::istringstream doc(read_text(scene_format_doc()));
    const std::string begin = "<!-- generated table: ";
    std::string section;
    bool in_block = false;
    std::set<std::string> documented;
    int line_number = 0;
    for (std::string line; std::getline(doc, line);) {
        ++line_number;
        if (line.starts_with(begin)) {
            section = line.substr(begin.size(), line.find(' ', begin.size()) - begin.size());
            in_block = true;
            continue;
        }
        if (line.starts_with("<!-- end of generated table")) {
            in_block = false;
            continue;
        }
        if (!in_block) {
            EXPECT_FALSE(line.starts_with("| key |"))
                << "scene-format.md:" << line_number << ": a key table outside the generated ones";
            continue;
        }
        if (!line.starts_with("| `")) continue;
        const std::string name = line.substr(3, line.find('`', 3) - 3);
        const std::string key = section + "." + name;
        EXPECT_NE(find_parameter(key), nullptr) << "scene-format.md:" << line_number << ": '" << key
                                                << "' is documented but not in the parameter table";
        EXPECT_TRUE(documented.insert(key).second) << key << " is documented twice";
    }
    for (const Parameter& p : parameter_table())
        EXPECT_TRUE(documented.contains(p.key())) << p.key() << " is in the parameter table but not in scene-format.md";
}

// Each row's type agrees with the field it reaches, and what the editor shows can be set live.
TEST(ParameterTable, RowsAgreeWithTheirFields) {
    std::set<std::string> keys;
    // The loader and writer map a collider's shape to its choice index and back.
    const auto shapes = parameter("collider", "shape").choices;
    for (const auto& [shape, name] : {std::pair{ColliderShape::Plane, "plane"}, std::pair{ColliderShape::Sphere, "sphere"},
                                     std::pair{ColliderShape::Capsule, "capsule"}, std::pair{ColliderShape::Box, "box"},
                                     std::pair{ColliderShape::Mesh, "mesh"}})
        EXPECT_EQ(shapes[static_cast<std::size_t>(shape)], name);
    for (const Parameter& p : parameter_table()) {
        SCOPED_TRACE(p.key());
        EXPECT_TRUE(keys.insert(p.key()).second) << "declared twice";
        EXPECT_EQ(find_parameter(p.key()), &p);
        EXPECT_FALSE(p.doc.empty());
        const bool numeric = p.type == ParameterType::Real || p.type == ParameterType::Integer ||
                             p.type == ParameterType::Boolean || p.type == ParameterType::Choice;
        const bool vector = p.type == ParameterType::Vector || p.type == ParameterType::CellCounts;
        if (p.access.owner == ParameterOwner::None) {
            EXPECT_TRUE(p.access.number == nullptr && p.access.vector == nullptr);
            EXPECT_TRUE(p.label.empty() || p.effect != ParameterEffect::Live) << "a live widget needs a field";
            continue;
        }
        EXPECT_TRUE(numeric || vector) << "a field of a type the loader cannot read";
        EXPECT_EQ(p.access.number != nullptr, numeric);
        EXPECT_EQ(p.access.set_number != nullptr, numeric);
        EXPECT_EQ(p.access.vector != nullptr, vector);
        EXPECT_EQ(p.access.set_vector != nullptr, vector);
        EXPECT_EQ(p.access.integral, p.type != ParameterType::Real && p.type != ParameterType::Vector)
            << "an integer row on a floating-point field, or the other way round";
        if (p.type == ParameterType::Choice) {
            EXPECT_FALSE(p.choices.empty());
        }
        if (p.type == ParameterType::Real || p.type == ParameterType::Integer || p.vector_bound != VectorBound::Finite) {
            EXPECT_TRUE(std::isfinite(p.range.lo) && std::isfinite(p.range.hi) && p.range.lo <= p.range.hi);
        }
        if (!p.panel.empty()) {
            EXPECT_FALSE(p.label.empty());
        }
    }
}

// Defaults are the default-constructed structs' values, and they are valid values.
TEST(ParameterTable, DefaultsComeFromTheStructsAndLieInRange) {
    const Parameter* dt = find_parameter("solver.dt");
    ASSERT_NE(dt, nullptr);
    EXPECT_EQ(parameter_default_number(*dt), SolverSettings{}.dt);
    EXPECT_EQ(parameter_default_number(*find_parameter("cloth.material.friction")), Material{}.friction);
    EXPECT_EQ(parameter_default_number(*find_parameter("cloth.density")), FabricDesc{}.density);
    EXPECT_EQ(parameter_default_vector(*find_parameter("world.gravity")), WorldDesc{}.gravity);
    EXPECT_EQ(parameter_default_number(*find_parameter("collision.culling")), 0.0) << "normal_cone";
    EXPECT_EQ(parameter_default_text(*find_parameter("solver.precision")), "\"double\"");
    EXPECT_EQ(parameter_default_text(*find_parameter("cloth.mesh.grid.cells")), "[32, 32]");
    for (const Parameter& p : parameter_table()) {
        SCOPED_TRACE(p.key());
        if (p.access.owner == ParameterOwner::None || !p.default_text.empty()) continue;
        if (p.type == ParameterType::Real || p.type == ParameterType::Integer) {
            EXPECT_TRUE(p.range.contains(parameter_default_number(p))) << parameter_default_number(p);
        }
        if (p.type == ParameterType::Vector && p.vector_bound == VectorBound::Length) {
            EXPECT_TRUE(p.range.contains(math::length(parameter_default_vector(p))));
        }
        EXPECT_FALSE(parameter_default_text(p).empty());
    }
}

// A scene value just outside a row's range is refused by the loader, naming the key and the range,
// and a World refuses the same value handed to it through the API.
TEST(ParameterTable, LoaderAndWorldRefuseWhatTheRangesRefuse) {
    for (const Parameter& p : parameter_table()) {
        const bool integer = p.type == ParameterType::Integer;
        if (!(holds<WorldDesc>(p) || holds<Material>(p)) || !(integer || p.type == ParameterType::Real)) continue;
        SCOPED_TRACE(p.key());
        const double above = integer ? p.range.hi + 1.0 : p.range.hi + std::max(1.0, std::abs(p.range.hi));
        const std::string range = integer ? p.range.integer_text() : p.range.text();
        // In the file: [solver] dt = …, or a cloth's [cloth.material].
        std::ostringstream value;
        value.precision(17);
        if (integer)
            value << std::llround(above);
        else
            value << above;
        const bool material = holds<Material>(p);
        const std::string text = material ? test::kSheet + "[cloth.material]\n" + std::string(p.name) + " = " + value.str() + "\n"
                                          : "[" + std::string(p.section) + "]\n" + std::string(p.name) + " = " +
                                                value.str() + "\n" + test::kSheet;
        expect_error([&] { (void)parse_scene(text, "range.toml"); },
                     {"range.toml:", std::string("'") + (material ? "cloth[0].material" : std::string(p.section)) + "." +
                                         std::string(p.name) + "'",
                      "is out of range", range});
        // Through the API.
        if (material) {
            Material m;
            set_parameter_number(p, m, above);
            World world({}, "cpu");
            expect_error([&] { (void)world.add_cloth({.name = "q", .fabric = Fabric::cook(make_grid(1.0, 1.0, 2, 2)),
                                                       .material = m}); },
                         {"cloth 'q' material", std::string(p.name), "is outside " + range});
        } else {
            WorldDesc desc;
            set_parameter_number(p, desc, above);
            expect_error([&] { World world(desc, "cpu"); },
                         {std::string(p.section) + ": " + std::string(p.name), "is outside " + range});
        }
    }
    // Vectors bounded by their length, and the sizes of a collider's shape.
    WorldDesc fast_wind;
    fast_wind.wind.velocity = {2000.0, 0.0, 0.0};
    expect_error([&] { World world(fast_wind, "cpu"); }, {"wind: velocity", "magnitude outside [0, 1000]"});
    World world({}, "cpu");
    ColliderDesc box{.name = "crate", .shape = ColliderShape::Box};
    box.half_extents = {0.5, 0.0, 0.5};
    expect_error([&] { (void)world.add_collider(box); }, {"collider 'crate'", "half_extents", "[1e-6, 1e6]"});
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
    ball.half_extents = {0.0, 0.0, 0.0};  // not a sphere's key: not checked
    EXPECT_NO_THROW((void)world.add_collider(ball));
}

}  // namespace
}  // namespace weft
