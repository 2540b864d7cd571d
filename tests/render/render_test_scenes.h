#pragma once
// Scenes the renderer tests draw, shared by the Vulkan, EGL and capture tests: small, fixed and
// without simulation, so that every pixel is reproducible.
#include <memory>
#include <vector>

#include "weft/mesh.h"
#include "weft/render/render_scene.h"
#include "weft/skinning.h"
#include "weft/world.h"

namespace weft::render::test {

/// A world and the scene and frame drawn from it. The world is kept because the scene refers to
/// its cloths by index.
struct TestScene {
    std::unique_ptr<World> world;
    RenderScene scene;
    std::vector<RenderVertex> vertices;
    RenderFrame frame;
};

/// The scene, vertices and frame of `t`'s world seen as sheet_over_ball sees it (from the front and
/// above): again after a test adds to the world.
inline void make_sheet_over_ball_view(TestScene& t) {
    CameraDesc camera;
    camera.position = {0.0, 1.6, 2.6};
    camera.target = {0.0, 0.5, 0.0};
    camera.fov_degrees = 45.0;
    t.scene = make_render_scene(*t.world, camera);
    cloth_vertices(*t.world, t.scene, t.vertices);
    t.frame.cloth = t.vertices;
    t.frame.collider_models = collider_models(t.scene, t.world->model(), 0.0);
}

/// A 1 m square sheet tilted 30° about X above a ball resting on the ground plane, seen from the
/// front and above: the image shows the sheet's front (upper) side, the ball, the ball's and the
/// sheet's shadows on the ground grid, and the sky colour above the horizon.
/// With `show_back`, the sheet is turned over (rotated 180° about X): the camera sees its back.
inline TestScene sheet_over_ball(bool show_back = false) {
    TestScene t;
    t.world = std::make_unique<World>();
    const auto fabric = Fabric::cook(make_grid(1.0, 1.0, 16, 16, GridPlane::XZ), {.density = 0.2});
    ClothDesc cloth{.name = "sheet", .fabric = fabric};
    const double angle = (show_back ? 3.141592653589793 : 0.0) + 0.5235987755982988;
    cloth.transform.rotation = rotation_from_vector({angle, 0.0, 0.0});
    cloth.transform.translation = {0.0, 0.9, 0.0};
    t.world->add_cloth(cloth);
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
    ball.radius = 0.3;
    ball.motion.origin = {0.3, 0.3, 0.2};
    t.world->add_collider(ball);
    t.world->add_collider(ColliderDesc{.name = "floor", .shape = ColliderShape::Plane});
    make_sheet_over_ball_view(t);
    return t;
}

/// A 0.4 m cube standing on the ground, as a character of one joint whose clip "slide" carries it
/// from x = −0.5 m (t = 0) to x = +0.5 m (t = 1 s): a collider the renderer must draw from each
/// frame's vertices (RenderFrame::collider_vertices), not from its mesh and a model matrix.
/// `frame` holds the pose at t = 0.
inline TestScene sliding_box() {
    auto skin = std::make_shared<SkinnedMesh>();
    skin->mesh.source = "sliding box";
    for (int k = 0; k < 8; ++k)  // vertex k: x, y, z from its bits 0, 1, 2
        skin->mesh.positions.push_back({(k & 1) ? 0.2 : -0.2, (k & 2) ? 0.4 : 0.0, (k & 4) ? 0.2 : -0.2});
    skin->mesh.triangles = {{{0, 4, 6}}, {{0, 6, 2}}, {{1, 3, 7}}, {{1, 7, 5}}, {{0, 1, 5}}, {{0, 5, 4}},
                            {{2, 6, 7}}, {{2, 7, 3}}, {{0, 2, 3}}, {{0, 3, 1}}, {{4, 5, 7}}, {{4, 7, 6}}};  // outward
    skin->vertex_joints.assign(8, {0, 0, 0, 0});
    skin->vertex_weights.assign(8, {1.0, 0.0, 0.0, 0.0});
    skin->joints = {Joint{.name = "root"}};
    AnimationClip slide{.name = "slide", .duration = 1.0};
    slide.tracks.push_back({.joint = 0, .translation_times = {0.0, 1.0}, .translations = {{-0.5, 0.0, 0.0}, {0.5, 0.0, 0.0}}});
    skin->clips.push_back(slide);
    TestScene t;
    t.world = std::make_unique<World>();
    ColliderDesc box{.name = "box", .shape = ColliderShape::Mesh};
    box.mesh = std::make_shared<const MeshData>(skin->mesh);
    box.skin = skin;
    box.clip = "slide";
    box.clip_loop = false;
    t.world->add_collider(box);
    t.world->add_collider(ColliderDesc{.name = "floor", .shape = ColliderShape::Plane});
    CameraDesc camera;
    camera.position = {0.0, 1.2, 2.4};
    camera.target = {0.0, 0.2, 0.0};
    camera.fov_degrees = 45.0;
    t.scene = make_render_scene(*t.world, camera);
    t.frame.collider_models = collider_models(t.scene, t.world->model(), 0.0);
    return t;
}

}  // namespace weft::render::test
