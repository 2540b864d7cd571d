// The editor's session without a window: re-cooking what the live world cannot take (timed, keeping
// what was tuned), presets through the parameter table, colliders in the table (and moving with the
// motion they follow), what a reset keeps, and the View panel's overlay geometry.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <cmath>
#include <filesystem>
#include <memory>
#include <numeric>
#include <string>

#include "weft/backend/model.h"
#include "weft/error.h"
#include "weft/scene.h"

#include "weft/editor/parameters.h"
#include "weft/editor/presets.h"
#include "weft/editor/session.h"
#include "weft/editor/viewport_overlay.h"

#if WEFT_TEST_HAVE_ASSETS
#include "weft/assets/assimp_loader.h"
#endif

namespace weft::editor {
namespace {

const std::filesystem::path kScenes = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes";

std::unique_ptr<Session> open_session(const std::string& scene_name, std::span<const std::string> overrides = {}) {
    SceneDesc scene = load_scene(kScenes / (scene_name + ".toml"), overrides);
    auto world = build_world(scene);
    return std::make_unique<Session>(std::move(scene), "cpu", BackendOptions{}, std::move(world), 1.0);
}

double total_mass(World& world, std::size_t cloth) {
    const auto m = world.model().cloths.at(cloth).fabric->masses();
    return std::accumulate(m.begin(), m.end(), 0.0);
}

std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "no error";
}

const std::string kSmallFlag[] = {"cloth.flag.mesh.grid.cells=[8,6]"};

// A re-cook changes what is cooked (here the density, so the masses), rebuilds the world keeping the
// tuned material, and says what it did and how long it took.
TEST(Session, RecookChangesTheFabricAndKeepsWhatWasTuned) {
    auto session = open_session("flag", kSmallFlag);
    const double area = 2.0 * 1.2;  // flag.toml's grid, m²
    ASSERT_NEAR(total_mass(session->world(), 0), session->scene().cloths[0].fabric.density * area, 1e-9);
    session->apply(*session->parameters().find("cloth.flag.material.stretch_stiffness"), 1234.0);
    const double density = session->scene().cloths[0].fabric.density;
    ClothRecook change;
    change.density = 0.45;
    const double ms = session->recook("flag", change);
    EXPECT_GE(ms, 0.0);
    EXPECT_NEAR(total_mass(session->world(), 0), 0.45 * area, 1e-9) << "the masses come from the new density";
    EXPECT_EQ(session->world().material(0).stretch_stiffness, 1234.0) << "the tuned material survives";
    EXPECT_EQ(session->scene().cloths[0].fabric.density, 0.45);
    char said[64];
    std::snprintf(said, sizeof said, "density %g -> 0.45 kg/m", density);
    EXPECT_NE(session->message().find(said), std::string::npos) << session->message();
    EXPECT_NE(session->message().find(" ms"), std::string::npos) << session->message();

    ClothRecook flat;
    flat.flat_rest_bending = true;
    (void)session->recook("flag", flat);
    EXPECT_TRUE(session->scene().cloths[0].fabric.flat_rest_bending);

    // Errors name what is wrong and leave the session as it was.
    ClothRecook scale;
    scale.scale = 2.0;
    EXPECT_EQ(error_of([&] { (void)session->recook("flag", scale); }),
              "re-cook: cloth 'flag' is a grid: its size is its width and height, not a scale");
    ClothRecook heavy;
    heavy.density = 500.0;
    EXPECT_NE(error_of([&] { (void)session->recook("flag", heavy); }).find("outside (0, 100]"), std::string::npos);
    EXPECT_EQ(error_of([&] { (void)session->recook("nosuch", change); }), "re-cook: no cloth 'nosuch' in the scene");
    EXPECT_NEAR(total_mass(session->world(), 0), 0.45 * area, 1e-9);
}

// A mesh file's scale is cooked: the rest shape grows with it; cells are refused for it.
TEST(Session, RecookScalesAMeshFile) {
#if WEFT_TEST_HAVE_ASSETS
    weft::assets::install_mesh_loader();
#else
    GTEST_SKIP() << "mesh import not built (WEFT_ASSETS off): the skirt is an OBJ file";
#endif
    auto session = open_session("skirt");
    const auto extent = [&] {
        const auto rest = session->world().model().cloths[0].fabric->rest_positions();
        double lo = rest[0].x, hi = rest[0].x;
        for (const Vec3d& p : rest) {
            lo = std::min(lo, p.x);
            hi = std::max(hi, p.x);
        }
        return hi - lo;
    };
    const double before = extent();
    const std::string name = session->scene().cloth_placements[0].name;
    ClothRecook change;
    change.scale = 1.5;
    (void)session->recook(name, change);
    EXPECT_NEAR(extent(), 1.5 * before, 1e-9 * before);
    ClothRecook cells;
    cells.cells = std::array<int, 2>{4, 4};
    EXPECT_NE(error_of([&] { (void)session->recook(name, cells); }).find("comes from a mesh file"), std::string::npos);
}

// Presets go through the parameter table; a material preset covers every copy of a repeated table
// and asks for a re-cook when its density differs.
TEST(Session, PresetsApplyThroughTheTable) {
    auto session = open_session("layers");
    session->apply_preset("solver", "accurate");
    const SolverSettings& s = session->world().settings().solver;
    EXPECT_EQ(s.newton_iterations, 3);
    EXPECT_EQ(s.cg_tolerance, 1e-6);
    EXPECT_EQ(s.precision, Precision::Double);
    EXPECT_EQ(s.substeps, 4);
    EXPECT_EQ(s.hessian, HessianMode::Fast) << "the accurate preset keeps the cheap Hessians (docs/results.md)";
    session->apply_preset("solver", "interactive");
    EXPECT_EQ(session->world().settings().solver.precision, Precision::Float);
    // "piled" switches the contact mode, live, and every other solver preset switches it back.
    session->apply_preset("solver", "piled");
    EXPECT_EQ(session->world().settings().collision.mode, CollisionMode::Offset);
    EXPECT_EQ(session->world().settings().solver.precision, Precision::Double);
    session->world().settings().collision.check = true;
    bool offset_ran = false;
    for (int frame = 0; frame < 3; ++frame) {
        const StepStats& stats = session->world().step();
        ASSERT_FALSE(stats.non_finite);
        ASSERT_EQ(stats.collision.remaining_intersections, 0) << "frame " << frame;
        offset_ran = offset_ran || stats.collision.query_radius_max > 0.0;
    }
    EXPECT_TRUE(offset_ran) << "the offset bounds never ran after the preset";
    session->apply_preset("solver", "balanced");
    EXPECT_EQ(session->world().settings().collision.mode, CollisionMode::CcdZones);

    const Preset* denim = find_preset(material_presets(), "denim");
    ASSERT_NE(denim, nullptr);
    const std::string table = session->scene().cloth_placements[0].name;
    session->apply_preset(table, "denim");
    ASSERT_GE(session->world().model().cloths.size(), 2U);
    for (std::size_t i = 0; i < session->world().model().cloths.size(); ++i)
        EXPECT_EQ(session->world().material(i).bending_stiffness, 1e-4) << "copy " << i;
    ASSERT_TRUE(session->requests().recook.has_value()) << "denim is heavier than the scene's fabric";
    EXPECT_EQ(session->requests().recook->change.density, denim->density);
    EXPECT_NE(session->message().find("re-cooking"), std::string::npos) << session->message();

    EXPECT_EQ(error_of([&] { session->apply_preset("solver", "slow"); }),
              "unknown solver preset 'slow' (presets: interactive, game, balanced, accurate, piled)");
    EXPECT_NE(error_of([&] { session->apply_preset(table, "velvet"); }).find("cotton, silk, denim, leather, rubber"),
              std::string::npos);
    EXPECT_NE(error_of([&] { session->apply_preset("nosuch", "silk"); }).find("no cloth 'nosuch'"), std::string::npos);
}

// Colliders are in the table by name: sizes for their shape, friction, and a position only for one
// that follows no motion; a motion's change moves the colliders that follow it.
TEST(Parameters, CollidersAreLiveAndMoveWithTheirMotion) {
    auto session = open_session("sphere");
    ParameterTable& table = session->parameters();
    World& world = session->world();
    const Parameter* radius = table.find("collider.ball.radius");
    ASSERT_NE(radius, nullptr);
    EXPECT_EQ(table.find("collider.0.radius"), radius);
    EXPECT_EQ(radius->group, "collider ball");
    EXPECT_EQ(table.find("collider.ball.position.x"), nullptr) << "the ball follows the motion 'spin'";
    const Parameter* half_height = table.find("collider.ball.half_height");
    ASSERT_NE(half_height, nullptr) << "every analytic size is a row, for a change of shape";
    ASSERT_TRUE(half_height->shown && radius->shown);
    EXPECT_FALSE(half_height->shown(world)) << "a sphere has no half height to show";
    EXPECT_TRUE(radius->shown(world));
    ASSERT_NE(table.find("collider.floor.position.y"), nullptr);
    session->apply(*radius, 0.35);
    EXPECT_EQ(world.collider(0).radius, 0.35);
    session->apply(*table.find("collider.floor.position.y"), -0.1);
    EXPECT_EQ(world.collider(1).motion.origin.y, -0.1);
    session->apply(*table.find("collider.ball.friction"), -5.0);  // clamped: -1 means the cloth's own
    EXPECT_EQ(world.collider(0).friction, -1.0);

    session->apply(*table.find("motion.spin.angular_velocity.y"), 4.0);
    EXPECT_EQ(world.motion(0).angular_velocity.y, 4.0);
    EXPECT_EQ(world.collider(0).motion.angular_velocity.y, 4.0) << "the ball spins with its motion";
}

// An analytic collider's shape is a row (World::set_collider_shape): the ball becomes a box of its
// size, the panel shows the box's sizes instead of the ball's, the world steps on, and Save writes
// the box.
TEST(Parameters, AColliderChangesShapeLiveAndSaveWritesIt) {
    auto session = open_session("sphere");
    ParameterTable& table = session->parameters();
    const Parameter* shape = table.find("collider.ball.shape");
    ASSERT_NE(shape, nullptr);
    EXPECT_EQ(table.find("collider.0.shape"), shape);
    EXPECT_EQ(table.find("collider.floor.shape")->choices,
              (std::vector<std::string>{"plane", "sphere", "capsule", "box"})) << "no mesh: it comes from a file";
    EXPECT_EQ(ParameterTable::format_value(*shape, shape->get(session->world())), "sphere");
    const double radius = session->world().collider(0).radius;
    session->apply(*shape, ParameterTable::parse_value(*shape, "box"));
    const ColliderDesc& ball = session->world().collider(0);
    EXPECT_EQ(ball.shape, ColliderShape::Box);
    EXPECT_EQ(ball.half_extents.y, radius) << "the box takes the ball's size";
    EXPECT_FALSE(table.find("collider.ball.radius")->shown(session->world()));
    EXPECT_TRUE(table.find("collider.ball.half_extents.x")->shown(session->world()));
    for (int i = 0; i < 3; ++i) EXPECT_FALSE(session->world().step().non_finite);

    const std::filesystem::path saved = std::filesystem::temp_directory_path() / "weft_test_shape_saved.toml";
    session->save(saved);
    const SceneDesc back = load_scene(saved);
    std::filesystem::remove(saved);
    EXPECT_EQ(back.colliders.at(0).shape, ColliderShape::Box);
    EXPECT_EQ(back.colliders.at(0).half_extents.x, radius);
}

// A mesh collider is in the table too: its friction, and its position when it follows no motion
// (its triangles are cooked; where they are is read at every substep), which moves it in the world.
TEST(Parameters, AMeshColliderHasFrictionAndAPositionLive) {
#if WEFT_TEST_HAVE_ASSETS
    weft::assets::install_mesh_loader();
#else
    GTEST_SKIP() << "mesh import not built (WEFT_ASSETS off): the garment's body is an OBJ file";
#endif
    auto moving = open_session("garment");
    const Parameter* friction = moving->parameters().find("collider.body.friction");
    ASSERT_NE(friction, nullptr);
    EXPECT_EQ(friction->group, "collider body (mesh)");
    EXPECT_EQ(moving->parameters().find("collider.body.position.x"), nullptr) << "the body follows the motion 'body'";
    EXPECT_EQ(moving->parameters().find("collider.body.radius"), nullptr) << "a mesh has no radius";

    // The same body standing still: its position is a row, and moves the collider's frame.
    SceneDesc scene = load_scene(kScenes / "garment.toml");
    scene.collider_motions.at(0).clear();
    scene.colliders.at(0).motion = Motion{};
    auto world = build_world(scene);
    Session still(std::move(scene), "cpu", BackendOptions{}, std::move(world), 1.0);
    const Parameter* x = still.parameters().find("collider.body.position.x");
    ASSERT_NE(x, nullptr);
    still.apply(*x, 0.25);
    EXPECT_EQ(still.world().collider(0).motion.origin.x, 0.25);
    EXPECT_NO_THROW((void)still.world().step());  // the collision stages place the moved triangles
}

// A reset goes back to the start with what was tuned: pins made live, colliders, motions.
TEST(Session, ResetKeepsPinsCollidersAndMotions) {
    auto session = open_session("flag", kSmallFlag);
    const std::uint32_t corner = 8;  // bottom-right of the 9×7 grid: not on the pinned left edge
    ASSERT_FALSE(session->world().is_pinned(0, corner));
    EXPECT_TRUE(session->toggle_pin(0, corner));
    session->apply(*session->parameters().find("collider.pole.radius"), 0.05);
    for (int i = 0; i < 5; ++i) (void)session->world().step();
    session->reset();
    EXPECT_EQ(session->world().time(), 0.0);
    EXPECT_TRUE(session->world().is_pinned(0, corner));
    EXPECT_TRUE(session->world().is_pinned(0, 0)) << "the file's pins stay";
    EXPECT_EQ(session->world().collider(0).radius, 0.05);
    EXPECT_EQ(session->resets(), 1);
    // A density keeps the vertices, so the pins made live stay; new cells drop them (they name the old
    // mesh's vertices), and the message says so.
    ClothRecook density;
    density.density = 0.3;
    (void)session->recook("flag", density);
    EXPECT_TRUE(session->world().is_pinned(0, corner)) << session->message();
    ClothRecook cells;
    cells.cells = std::array<int, 2>{10, 6};
    (void)session->recook("flag", cells);
    EXPECT_NE(session->message().find("dropped"), std::string::npos) << session->message();
    EXPECT_EQ(session->world().model().cloths[0].pins.size(), 7U) << "the left edge of 10x6 cells";
}

// Cloth against cloth: the backend's proximity pairs (World::contact_vertices) become magenta
// marks; a sheet alone has none; a cloth index that does not exist is an error.
TEST(ViewportOverlay, MarksTheVerticesInClothContacts) {
    WorldDesc desc;
    desc.collision.self_collision = true;
    World world(desc, "cpu");
    // Two 4×4-cell sheets in XY planes 2 mm apart (inside the contact thickness), facing the camera.
    world.add_cloth({.name = "back", .fabric = Fabric::cook(make_grid(0.4, 0.4, 4, 4))});
    ClothDesc front{.name = "front", .fabric = Fabric::cook(make_grid(0.4, 0.4, 4, 4))};
    front.transform.translation = {0.0, 0.0, 0.002};
    world.add_cloth(front);
    ASSERT_TRUE(world.contact_vertices(0).has_value()) << "the cpu backend reports its contacts";
    EXPECT_TRUE(world.contact_vertices(0)->empty()) << "nothing stepped yet";
    (void)world.step();
    const std::optional<std::vector<std::uint32_t>> back = world.contact_vertices(0), ahead = world.contact_vertices(1);
    ASSERT_TRUE(back && ahead);
    EXPECT_GT(back->size(), 10U) << "most of the back sheet touches the front one";
    EXPECT_GT(ahead->size(), 10U);
    EXPECT_TRUE(std::is_sorted(back->begin(), back->end()));
    for (const std::uint32_t v : *back) EXPECT_LT(v, 25U) << "cloth-local ids";
    EXPECT_THROW((void)world.contact_vertices(2), std::exception);

    render::Camera camera;
    camera.position = {0.0F, 0.0F, 2.0F};
    camera.target = {0.0F, 0.0F, 0.0F};
    DisplayOptions contacts{.contacts = true};
    const ViewportOverlay o = build_viewport_overlay(world, camera, 640, 480, contacts);
    EXPECT_TRUE(o.cloth_contacts_reported);
    EXPECT_EQ(o.cloth_contacts, back->size() + ahead->size());
    EXPECT_EQ(o.contacts, 0U) << "no analytic collider";
    // The renderer's magenta marks: the back sheet's vertices, then the front's after its 25.
    ASSERT_EQ(o.points.size(), 1U);
    EXPECT_EQ(o.points[0].vertices.size(), back->size() + ahead->size());
    EXPECT_EQ(o.points[0].vertices.front(), back->front());
    EXPECT_EQ(o.points[0].vertices.back(), 25U + ahead->back()) << "the cloth buffer holds the back sheet first";
    EXPECT_EQ(build_viewport_overlay(world, camera, 640, 480, DisplayOptions{}).cloth_contacts, 0U) << "toggle off";
}

// The View panel: marks for a sheet facing the camera, and the lines the renderer draws.
TEST(ViewportOverlay, MarksContactsAndPinsAndGivesTheRendererItsLines) {
    World world(WorldDesc{}, "cpu");
    // 2×2 cells in the XY plane, 1 m, at z = 0; pinned at vertex 0.
    world.add_cloth({.name = "sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, 2, 2)), .pins = {{0, -1}}});
    const std::vector<Vec3d> x = world.positions(0);
    // A sphere touching vertex 4 (the centre) from behind, within the contact thickness.
    const double thickness = world.model().cloths[0].material.contact_thickness;
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
    ball.radius = 0.2;
    ball.motion.origin = x[4] + Vec3d{0.0, 0.0, -0.2 - 0.5 * thickness};
    world.add_collider(ball);
    render::Camera camera;
    camera.position = {static_cast<float>(x[4].x), static_cast<float>(x[4].y), 3.0F};
    camera.target = {static_cast<float>(x[4].x), static_cast<float>(x[4].y), 0.0F};

    DisplayOptions nothing;
    EXPECT_TRUE(build_viewport_overlay(world, camera, 640, 480, nothing).segments.empty());
    DisplayOptions all{.wireframe = true, .normals = true, .contacts = true, .pins = true};
    EXPECT_EQ(build_viewport_overlay(world, camera, 640, 480, all).contacts, 0U) << "no substep yet: no contact found";
    (void)world.step();  // the marks are the contacts the solver found active
    const ViewportOverlay o = build_viewport_overlay(world, camera, 640, 480, all);
    EXPECT_TRUE(o.collider_contacts_reported);
    EXPECT_EQ(o.contacts, 1U) << "only the centre touches the ball";
    EXPECT_EQ(o.pins, 1U);
    EXPECT_TRUE(o.segments.empty()) << "wireframe and normals are the renderer's lines now";
    // The renderer's lines (drawn from the cloth buffer): the wireframe, and normals 1.5 mean rest
    // edges long (edges of 0.5 m and diagonals of 0.71 m here).
    EXPECT_FALSE(overlay_lines(world, nothing).wireframe);
    EXPECT_EQ(overlay_lines(world, nothing).normal_length, 0.0F);
    const render::OverlayLines lines = overlay_lines(world, all);
    EXPECT_TRUE(lines.wireframe);
    EXPECT_NEAR(lines.normal_length, 1.5 * (0.5 + 0.5 + std::sqrt(0.5)) / 3.0, 1e-6);
    // The renderer's marks: the centre touching the ball (orange), the pin (blue), as cloth buffer
    // indices, drawn from the solver's buffer and depth-tested (render tests: OverlayPoints).
    ASSERT_EQ(o.points.size(), 2U);
    EXPECT_EQ(o.points[0].vertices, (std::vector<std::uint32_t>{4}));
    EXPECT_EQ(o.points[1].vertices, (std::vector<std::uint32_t>{0}));
    EXPECT_GT(o.points[0].colour.r, o.points[0].colour.b) << "contacts orange";
    EXPECT_GT(o.points[1].colour.b, o.points[1].colour.r) << "pins blue";
    EXPECT_TRUE(build_viewport_overlay(world, camera, 640, 480, nothing).points.empty());

    world.set_grab({.cloth = 0, .vertex = 8, .target = x[8] + Vec3d{0.0, 0.0, 0.5}, .stiffness = 100.0, .damping = 1.0});
    const ViewportOverlay grabbed = build_viewport_overlay(world, camera, 640, 480, nothing);
    EXPECT_TRUE(grabbed.grab) << "a grab is always drawn";
    // The grabbed vertex's dot at its place in the picture (the camera looks straight at the centre,
    // the grid's 0.5 m cells put vertex 8 up and right of it).
    const auto dot = std::find_if(grabbed.marks.begin(), grabbed.marks.end(), [](const OverlayMark& m) {
        return m.shape == OverlayMark::Shape::dot;
    });
    ASSERT_NE(dot, grabbed.marks.end());
    EXPECT_GT(dot->x, 320.0F);
    EXPECT_LT(dot->y, 240.0F);

    // Behind the camera the grab is not drawn.
    camera.position.z = -3.0F;
    camera.target = {camera.position.x, camera.position.y, -6.0F};
    const ViewportOverlay behind = build_viewport_overlay(world, camera, 640, 480, all);
    EXPECT_TRUE(behind.marks.empty());
}

}  // namespace
}  // namespace weft::editor
