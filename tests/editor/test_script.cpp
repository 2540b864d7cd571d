// Editor scripts (weft/editor/script.h) and the parameter table they go through
// (weft/editor/parameters.h): parsing, the errors that name the line, ranges, and that a pending
// value reaches the world only through the panel code's take_pending + apply.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "weft/editor/parameters.h"
#include "weft/editor/script.h"
#include "weft/editor/vertex_picking.h"
#include "weft/error.h"
#include "weft/fabric.h"
#include "weft/mesh.h"
#include "weft/parameters.h"
#include "weft/world.h"

namespace weft::editor {
namespace {

std::string error_of(const std::string& text) {
    try {
        (void)parse_script(text, "s.txt");
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

std::unique_ptr<World> small_world() {
    auto world = std::make_unique<World>(WorldDesc{}, "cpu");
    world->add_cloth({.name = "sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, 2, 2))});
    return world;
}

TEST(Script, ParsesEveryCommand) {
    const Script s = parse_script(
        "# comment\n\nframe 3\nset solver.substeps 4   # trailing comment\nexpect solver.substeps 4\npause\nplay\n"
        "step\nreset\ntimescale 0.5\nscreenshot out/a.png\nframe 9\nquit",
        "s.txt");
    ASSERT_EQ(s.commands.size(), 11U);
    using K = ScriptCommand::Kind;
    EXPECT_EQ(s.commands[0].kind, K::frame);
    EXPECT_EQ(s.commands[0].frame, 3);
    EXPECT_EQ(s.commands[0].line, 3);
    EXPECT_EQ(s.commands[1].kind, K::set);
    EXPECT_EQ(s.commands[1].key, "solver.substeps");
    EXPECT_EQ(s.commands[1].text, "4");
    EXPECT_EQ(s.commands[7].kind, K::timescale);
    EXPECT_DOUBLE_EQ(s.commands[7].number, 0.5);
    EXPECT_EQ(s.commands[8].text, "out/a.png");
    EXPECT_EQ(s.commands[10].kind, K::quit);
    EXPECT_EQ(s.commands[10].line, 13);

    const Script r = parse_script("record out/rec\nstop\n", "r.txt");
    ASSERT_EQ(r.commands.size(), 2U);
    EXPECT_EQ(r.commands[0].kind, K::record);
    EXPECT_EQ(r.commands[0].text, "out/rec");
    EXPECT_EQ(r.commands[1].kind, K::stop);
    EXPECT_THROW((void)parse_script("record\n", "r.txt"), Error) << "record takes the folder";

    const Script c = parse_script("cells flag 80 48\n", "c.txt");
    ASSERT_EQ(c.commands.size(), 1U);
    EXPECT_EQ(c.commands[0].kind, K::cells);
    EXPECT_EQ(c.commands[0].key, "flag");
    EXPECT_EQ(c.commands[0].cells_x, 80);
    EXPECT_EQ(c.commands[0].cells_y, 48);
    EXPECT_THROW((void)parse_script("cells flag 0 48\n", "c.txt"), Error) << "at least one cell";
    EXPECT_THROW((void)parse_script("cells flag 80\n", "c.txt"), Error) << "two counts";

    const Script m = parse_script("grab 10 20.5\ndrag 30 40\nheld 0.05\nrelease\npin 7 8\n", "m.txt");
    ASSERT_EQ(m.commands.size(), 5U);
    EXPECT_EQ(m.commands[0].kind, K::grab);
    EXPECT_DOUBLE_EQ(m.commands[0].x, 10.0);
    EXPECT_DOUBLE_EQ(m.commands[0].y, 20.5);
    EXPECT_EQ(m.commands[1].kind, K::drag);
    EXPECT_EQ(m.commands[2].kind, K::held);
    EXPECT_DOUBLE_EQ(m.commands[2].x, 0.05);
    EXPECT_EQ(m.commands[3].kind, K::release);
    EXPECT_EQ(m.commands[4].kind, K::pin);
    EXPECT_EQ(error_of("grab -1 5\n"), "s.txt:1: grab expects picture pixels x y in [0, 16384], got '-1'");
    EXPECT_EQ(error_of("held far\n"), "s.txt:1: held expects a distance in [0, 100] m, got 'far'");
    EXPECT_EQ(error_of("pin 5\n"), "s.txt:1: 'pin' takes 2 arguments, got 1");

    const Script k = parse_script("cook flag density 0.3\ncook shirt scale 0.01\ncook flag flat_rest_bending on\n"
                                  "preset solver fast\npreset flag silk\nshow wireframe on\nshow pins off\n",
                                  "k.txt");
    ASSERT_EQ(k.commands.size(), 7U);
    EXPECT_EQ(k.commands[0].kind, K::cook);
    EXPECT_EQ(k.commands[0].key, "flag");
    EXPECT_EQ(k.commands[0].text, "density");
    EXPECT_DOUBLE_EQ(k.commands[0].number, 0.3);
    EXPECT_EQ(k.commands[1].text, "scale");
    EXPECT_DOUBLE_EQ(k.commands[2].number, 1.0);
    EXPECT_EQ(k.commands[3].kind, K::preset);
    EXPECT_EQ(k.commands[3].key, "solver");
    EXPECT_EQ(k.commands[4].text, "silk");
    EXPECT_EQ(k.commands[5].kind, K::show);
    EXPECT_EQ(k.commands[5].key, "wireframe");
    EXPECT_DOUBLE_EQ(k.commands[5].number, 1.0);
    EXPECT_DOUBLE_EQ(k.commands[6].number, 0.0);
    EXPECT_EQ(error_of("cook flag density 0\n"), "s.txt:1: cook density expects kg/m\u00b2 in (0, 100], got '0'");
    EXPECT_EQ(error_of("cook flag colour 3\n"),
              "s.txt:1: cook: unknown field 'colour' (fields: density, scale, flat_rest_bending; cells has its own command)");
    EXPECT_EQ(error_of("show grid on\n"), "s.txt:1: show: unknown display 'grid' (wireframe, normals, contacts, pins)");
    EXPECT_EQ(error_of("show normals maybe\n"), "s.txt:1: show normals expects on or off, got 'maybe'");
}

TEST(Script, ErrorsNameTheLine) {
    EXPECT_EQ(error_of("frame 1\njump 3\n"),
              "s.txt:2: unknown command 'jump' (commands: frame, set, expect, pause, play, step, reset, timescale, "
              "open, record, stop, cells, cook, preset, show, screenshot, save, grab, drag, held, release, pin, quit)");
    EXPECT_EQ(error_of("set solver.substeps\n"), "s.txt:1: 'set' takes 2 arguments, got 1");
    EXPECT_EQ(error_of("pause now\n"), "s.txt:1: 'pause' takes 0 arguments, got 1");
    EXPECT_EQ(error_of("\nframe ten\n"), "s.txt:2: frame expects a frame count in [1, 100000000], got 'ten'");
    EXPECT_EQ(error_of("frame 5\nframe 5\n"), "s.txt:2: frame 5 does not come after frame 5");
    EXPECT_EQ(error_of("timescale 1000\n"), "s.txt:1: timescale expects a number in [0.01, 100], got '1000'");
}

TEST(Script, CheckNamesBadKeysAndValues) {
    const std::unique_ptr<World> owned = small_world();
    const ParameterTable table(*owned);
    auto check_error = [&](const std::string& text) {
        Script s = parse_script(text, "s.txt");
        try {
            check_script(s, table);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_EQ(check_error("frame 1\nset solver.substepz 4\n"),
              "s.txt:2: unknown parameter 'solver.substepz' (the keys are listed in docs/editor.md)");
    EXPECT_EQ(check_error("set solver.substeps 5000\n"),
              "s.txt:1: 'solver.substeps': out of range: '5000' (expected an integer in [1, 1000])");
    EXPECT_EQ(check_error("set solver.substeps 2.5\n"),
              "s.txt:1: 'solver.substeps': not an integer: '2.5' (expected an integer in [1, 1000])");
    EXPECT_EQ(check_error("expect solver.cg_warm_start maybe\n"),
              "s.txt:1: 'solver.cg_warm_start': not a boolean: 'maybe' (expected true or false)");
    EXPECT_EQ(check_error("set solver.precision quad\n"),
              "s.txt:1: 'solver.precision': unknown choice 'quad' (expected one of float, double)");
    EXPECT_EQ(check_error("set cloth.sheet.material.poisson_ratio 0.7\n"),
              "s.txt:1: 'cloth.sheet.material.poisson_ratio': out of range: '0.7' (expected a number in [0, 0.49])");
    Script good = parse_script("set cloth.0.material.friction 0.5\nexpect solver.precision float\n", "s.txt");
    check_script(good, table);
    EXPECT_DOUBLE_EQ(good.commands[0].number, 0.5);
    EXPECT_DOUBLE_EQ(good.commands[1].number, 0.0);  // the index of "float"
}

// After `open`, the keys belong to the scene opened: check_script leaves them to check_command,
// which the editor calls when they run, with the same messages.
TEST(Script, KeysAfterAnOpenAreCheckedWhenTheyRun) {
    const std::unique_ptr<World> owned = small_world();
    const ParameterTable table(*owned);
    Script s = parse_script("set solver.substeps 3\nopen layers\nset cloth.sheets.material.friction 0.2\n", "s.txt");
    ASSERT_EQ(s.commands.size(), 3U);
    EXPECT_EQ(s.commands[1].kind, ScriptCommand::Kind::open);
    EXPECT_EQ(s.commands[1].text, "layers");
    EXPECT_NO_THROW(check_script(s, table)) << "a key of the other scene is not checked against this one";
    EXPECT_TRUE(s.commands[0].checked);
    EXPECT_FALSE(s.commands[2].checked);
    try {
        check_command(s.name, s.commands[2], table);
        ADD_FAILURE() << "the key is not in this scene";
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()),
                  "s.txt:3: unknown parameter 'cloth.sheets.material.friction' (the keys are listed in docs/editor.md)");
    }
    EXPECT_THROW((void)parse_script("open\n", "s.txt"), Error) << "open takes the scene";
}

TEST(Parameters, PendingValuesReachTheWorldThroughApply) {
    const std::unique_ptr<World> owned = small_world();
    World& world = *owned;
    ParameterTable table(world);
    const Parameter* substeps = table.find("solver.substeps");
    const Parameter* stretch = table.find("cloth.0.material.stretch_stiffness");  // the index alias
    ASSERT_NE(substeps, nullptr);
    ASSERT_NE(stretch, nullptr);
    EXPECT_EQ(stretch->key, "cloth.sheet.material.stretch_stiffness");
    EXPECT_EQ(stretch->unit, "N/m");

    table.set_pending("solver.substeps", 4.0);
    EXPECT_EQ(world.settings().solver.substeps, 1) << "a pending value is not applied by itself";
    const std::optional<double> v = table.take_pending(*substeps);
    ASSERT_TRUE(v);
    EXPECT_FALSE(table.take_pending(*substeps)) << "taken once";
    ParameterTable::apply(*substeps, world, *v);
    EXPECT_EQ(world.settings().solver.substeps, 4);
    EXPECT_EQ(world.step().substeps, 4) << "the next step uses it";

    // The widgets' clamp: out of range goes to the nearest end, integers are rounded.
    EXPECT_DOUBLE_EQ(ParameterTable::apply(*stretch, world, 1e12), 1e8);
    EXPECT_DOUBLE_EQ(world.material(0).stretch_stiffness, 1e8);
    EXPECT_DOUBLE_EQ(ParameterTable::apply(*substeps, world, 2.6), 3.0);
    EXPECT_THROW(table.set_pending("no.such.key", 1.0), Error);
}

TEST(Parameters, VectorsKeepTheirLengthInRange) {
    const std::unique_ptr<World> owned = small_world();
    World& world = *owned;
    const ParameterTable table(world);
    const Parameter* gx = table.find("world.gravity.x");
    ASSERT_NE(gx, nullptr);
    ParameterTable::apply(*gx, world, 1000.0);
    const Vec3d g = world.settings().gravity;
    EXPECT_NEAR(std::sqrt(g.x * g.x + g.y * g.y + g.z * g.z), 1000.0, 1e-9);
}

// Motions are in the table by their scene names (and by index), and what a pin following one does
// changes at the next step.
TEST(Parameters, MotionsAreLiveAndNamed) {
    auto world = std::make_unique<World>(WorldDesc{}, "cpu");
    const int spin = world->add_motion(Motion{});
    world->add_cloth({.name = "sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, 2, 2)), .pins = {{0, spin}}});
    const std::string names[] = {"carrier"};
    ParameterTable table(*world, names);
    const Parameter* vx = table.find("motion.carrier.linear_velocity.x");
    ASSERT_NE(vx, nullptr);
    EXPECT_EQ(table.find("motion.0.linear_velocity.x"), vx) << "the index alias";
    EXPECT_EQ(vx->panel, "motions");
    EXPECT_EQ(vx->group, "motion carrier");
    EXPECT_EQ(vx->unit, "m/s");
    for (const char* key : {"motion.carrier.origin.y", "motion.carrier.angular_velocity.z", "motion.carrier.amplitude.x",
                            "motion.carrier.frequency", "motion.carrier.phase"})
        EXPECT_NE(table.find(key), nullptr) << key;

    const double x0 = world->positions(0)[0].x;
    ParameterTable::apply(*vx, *world, 2.0);
    EXPECT_EQ(world->motion(spin).linear_velocity.x, 2.0);
    (void)world->step();
    EXPECT_NEAR(world->positions(0)[0].x - x0, 2.0 * world->time(), 1e-9) << "the pinned vertex follows the motion";

    // A table without names keys motions by index.
    const ParameterTable unnamed(*world);
    EXPECT_NE(unnamed.find("motion.0.frequency"), nullptr);
}

// Every collision knob of docs/scene-format.md is in the table, reaching the world's settings.
TEST(Parameters, EveryCollisionKnobIsEditable) {
    const std::unique_ptr<World> owned = small_world();
    World& world = *owned;
    ParameterTable table(world);
    for (const char* key : {"collision.self", "collision.continuous", "collision.culling", "collision.cull_contacts",
                            "collision.thickness", "collision.stiffness", "collision.rest_exclusion",
                            "collision.max_impact_iterations", "collision.impact_tolerance",
                            "collision.max_impact_sweeps", "collision.count_culled", "collision.check"})
        EXPECT_NE(table.find(key), nullptr) << key;
    ParameterTable::apply(*table.find("collision.impact_tolerance"), world, 0.9);  // clamped to its range
    EXPECT_DOUBLE_EQ(world.settings().collision.impact_tolerance, 0.5);
    ParameterTable::apply(*table.find("collision.max_impact_sweeps"), world, 64.0);
    EXPECT_EQ(world.settings().collision.max_impact_sweeps, 64);
    ParameterTable::apply(*table.find("collision.check"), world, 1.0);
    EXPECT_TRUE(world.settings().collision.check);
}

// The editor's rows are the runtime's parameter table (weft/parameters.h): every live scene key of the
// world's settings and of a material has a widget with the table's label, unit and range, and a
// key that needs a rebuild (threads) has none.
TEST(Parameters, TheRowsComeFromTheRuntimeTable) {
    const std::unique_ptr<World> owned = small_world();
    const ParameterTable table(*owned);
    int live = 0;
    for (const weft::Parameter& row : parameter_table()) {
        if (!holds<WorldDesc>(row) && !holds<Material>(row)) continue;
        const std::string key = holds<Material>(row) ? "cloth.sheet.material." + std::string(row.name) : row.key();
        const bool vector = row.type == ParameterType::Vector;
        const Parameter* p = table.find(vector ? key + ".x" : key);
        if (row.effect != ParameterEffect::Live) {
            EXPECT_EQ(p, nullptr) << key << " needs a rebuild: no live widget";
            continue;
        }
        ++live;
        ASSERT_NE(p, nullptr) << key;
        EXPECT_EQ(p->panel, row.panel) << key;
        EXPECT_EQ(p->unit, row.unit) << key;
        EXPECT_EQ(p->hint, row.doc) << key;
        EXPECT_EQ(p->label, vector ? std::string(row.label) + " x" : std::string(row.label)) << key;
        if (row.type == ParameterType::Real || row.type == ParameterType::Integer) {
            EXPECT_EQ(p->min, row.range.lo) << key;
            EXPECT_EQ(p->max, row.range.hi) << key;
        }
    }
    EXPECT_GT(live, 30);
    EXPECT_EQ(table.find("solver.threads"), nullptr);
}

TEST(Script, SaveNeedsAPath) {
    const Script s = parse_script("frame 1\nsave out/tuned.toml\n", "s.txt");
    ASSERT_EQ(s.commands.size(), 2U);
    EXPECT_EQ(s.commands[1].kind, ScriptCommand::Kind::save);
    EXPECT_EQ(s.commands[1].text, "out/tuned.toml");
    EXPECT_THROW((void)parse_script("save\n", "s.txt"), Error);
}

// Picking is geometry on the renderers' camera: the pixel a vertex is drawn at gives a ray through
// it, picks it (the nearer of two in line), and a drag keeps it at its depth.
TEST(VertexPicking, TheRayThroughAVertexPicksItAndDragsKeepItsDepth) {
    auto world = small_world();  // a 1 m sheet in the XY plane at the origin, 3×3 vertices
    render::Camera camera;
    camera.position = {0.0F, 0.0F, 3.0F};
    camera.target = {0.0F, 0.0F, 0.0F};
    const int w = 640, h = 480;
    // The centre pixel looks down −z through the middle vertex (4).
    const CursorRay ray = cursor_ray(camera, w, h, 320.0, 240.0);
    EXPECT_NEAR(ray.direction.z, -1.0, 1e-9);
    const std::optional<VertexPick> middle = pick_vertex(*world, camera, w, h, 320.0, 240.0);
    ASSERT_TRUE(middle);
    EXPECT_EQ(middle->vertex, 4U);
    EXPECT_LT(middle->pixels, 1e-6);
    // The top-right corner (0.5, 0.5, 0): up and right on the picture (rows run down).
    const std::optional<VertexPick> corner = pick_vertex(*world, camera, w, h, 320.0 + 96.0, 240.0 - 96.0, 40.0);
    ASSERT_TRUE(corner);
    EXPECT_EQ(corner->vertex, 8U);
    EXPECT_FALSE(pick_vertex(*world, camera, w, h, 5.0, 5.0)) << "nothing drawn there";

    // A second sheet in front of the first: the pick takes the nearer one.
    ClothDesc front{.name = "front", .fabric = Fabric::cook(make_grid(1.0, 1.0, 2, 2))};
    front.transform.translation = {0.0, 0.0, 1.0};
    world->add_cloth(front);
    const std::optional<VertexPick> nearer = pick_vertex(*world, camera, w, h, 320.0, 240.0);
    ASSERT_TRUE(nearer);
    EXPECT_EQ(nearer->cloth, 1U);

    // Dragging: the target stays on the plane through the picked point that faces the camera.
    const Vec3d target = drag_target(camera, w, h, 400.0, 200.0, nearer->position);
    EXPECT_NEAR(target.z, 1.0, 1e-9);
    EXPECT_GT(target.x, 0.0);
    EXPECT_GT(target.y, 0.0);
    const Vec3d back = drag_target(camera, w, h, 320.0, 240.0, nearer->position);
    EXPECT_NEAR(math::length(back - nearer->position), 0.0, 1e-9);
}

}  // namespace
}  // namespace weft::editor
