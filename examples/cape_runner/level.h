#pragma once
// The cape_runner's level: the ground, the runner (capsules or the rigged character) wearing a cape
// and a skirt, a flag on a pole and a banner across the way; and drive(), which tells the world
// where the runner goes each frame. The game (main.cpp) and the backend twin (backend_twin.cpp)
// build the same level from it.
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include "runner.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace cape_runner {

using weft::Vec3d;

inline constexpr double kShoulderHeight = 1.45;  // m above the feet: the cape's pinned edge
inline constexpr double kCapeHeight = 0.85;      // m

/// What the game keeps of the world it built: the runner's motion and body colliders, the cape.
struct Level {
    int runner_motion = -1;  // the cape's and the skirt's pins follow it (capsules)
    std::size_t body = 0, head = 0;
    std::optional<std::size_t> character;  // the rigged runner: a mesh collider playing clips
    std::size_t cape = 0;
};

/// The runner's skeleton joint called `name` (the pins hold on to the chest and the hips).
inline int joint_index(const weft::SkinnedMesh& skin, const char* name) {
    for (std::size_t j = 0; j < skin.joints.size(); ++j)
        if (skin.joints[j].name == name) return static_cast<int>(j);
    throw std::runtime_error(std::string("the character has no joint '") + name + "' (the runner's joints are expected)");
}

/// A static analytic collider.
inline weft::ColliderDesc collider(const char* name, weft::ColliderShape shape, Vec3d at) {
    weft::ColliderDesc c{.name = name, .shape = shape};
    c.motion.origin = at;
    return c;
}

/// A skirt: a truncated cone of `segments` × `rings` quads round the y axis, its waist (ring 0) at
/// `top` with radius `r_top`, its hem at `bottom` with radius `r_bottom`. Vertex (s, k) = k·segments + s.
inline weft::MeshData skirt_mesh(int segments, int rings, double top, double bottom, double r_top, double r_bottom) {
    weft::MeshData m;
    m.source = "cape_runner skirt";
    for (int k = 0; k <= rings; ++k) {
        const double f = static_cast<double>(k) / rings, r = r_top + f * (r_bottom - r_top), y = top + f * (bottom - top);
        for (int s = 0; s < segments; ++s) {
            const double a = 2.0 * std::numbers::pi * s / segments;
            m.positions.push_back({r * std::sin(a), y, r * std::cos(a)});
        }
    }
    const auto id = [&](int s, int k) { return static_cast<std::uint32_t>(k * segments + (s % segments)); };
    for (int k = 0; k < rings; ++k)
        for (int s = 0; s < segments; ++s) {  // outward-facing, alternating diagonals
            if ((s + k) % 2 == 0) {
                m.triangles.push_back({{id(s, k), id(s, k + 1), id(s + 1, k + 1)}});
                m.triangles.push_back({{id(s, k), id(s + 1, k + 1), id(s + 1, k)}});
            } else {
                m.triangles.push_back({{id(s, k), id(s, k + 1), id(s + 1, k)}});
                m.triangles.push_back({{id(s + 1, k), id(s, k + 1), id(s + 1, k + 1)}});
            }
        }
    return m;
}

inline Level build_level(weft::World& world, const Runner& runner, int detail, std::shared_ptr<const weft::SkinnedMesh> skin) {
    Level level;
    world.add_collider(collider("ground", weft::ColliderShape::Plane, {}));

    // The runner, on the motion the game rewrites every frame: the rigged character (its clips
    // chosen by drive()), or a capsule body and a sphere head.
    level.runner_motion = world.add_motion(runner.motion(0.0, 1.0));
    int chest = -1, hips = -1;
    if (skin) {
        weft::ColliderDesc character{.name = "runner", .shape = weft::ColliderShape::Mesh};
        character.motion = runner.motion(0.0, 1.0);
        character.skin = skin;
        character.friction = 0.1;  // the banner slides over the runner rather than being carried along
        level.character = world.add_collider(character);
        chest = joint_index(*skin, "chest");
        hips = joint_index(*skin, "hips");
    } else {
        auto body = collider("body", weft::ColliderShape::Capsule, {0.0, 0.95, 0.0});
        body.radius = 0.2;
        body.half_height = 0.35;
        body.friction = 0.1;
        level.body = world.add_collider(body);
        auto head = collider("head", weft::ColliderShape::Sphere, {0.0, 1.72, 0.0});
        head.radius = 0.14;
        head.friction = 0.1;
        level.head = world.add_collider(head);
    }
    // A pin held by the character's joint (it turns and bobs with the bone), or by the motion.
    const auto pin = [&](std::uint32_t vertex, int joint) {
        return level.character ? weft::PinDesc{.vertex = vertex, .collider = static_cast<int>(*level.character), .collider_joint = joint}
                               : weft::PinDesc{.vertex = vertex, .motion = level.runner_motion};
    };

    // The cape: hanging behind the back, its top row pinned to the runner's shoulders.
    const int cx = 14 * detail, cy = 20 * detail;
    weft::ClothDesc cape{.name = "cape", .fabric = weft::Fabric::cook(weft::make_grid(0.56, kCapeHeight, cx, cy), {.density = 0.25})};
    // Tilted so that it falls clear of the skirt: its top 2 cm behind the back, its hem 16 cm.
    // On the character, tilted further: its skirt flares wider (below).
    cape.transform.rotation = weft::rotation_from_vector({skin ? 0.4 : 0.165, 0.0, 0.0});
    cape.transform.translation = runner.position() + Vec3d{0.0, kShoulderHeight - kCapeHeight / 2, skin ? -0.31 : -0.29};
    for (int i = 0; i <= cx; ++i) cape.pins.push_back(pin(static_cast<std::uint32_t>(cy * (cx + 1) + i), chest));
    level.cape = world.add_cloth(cape);

    // The skirt: a cone round the hips, its waist pinned to the runner.
    const int segments = 28 * detail, rings = 6 * detail;
    weft::ClothDesc skirt{.name = "skirt",
                          .fabric = weft::Fabric::cook(skirt_mesh(segments, rings, skin ? 0.84 : 0.95, 0.5, skin ? 0.23 : 0.22, skin ? 0.44 : 0.30),
                                                       {.density = 0.2})};  // on the character: below its hands, wide for its knees
    skirt.transform.translation = runner.position();
    for (int s = 0; s < segments; ++s) skirt.pins.push_back(pin(static_cast<std::uint32_t>(s), hips));
    (void)world.add_cloth(skirt);

    // A flag on a pole beside the way, pinned along the pole.
    auto pole = collider("pole", weft::ColliderShape::Capsule, {2.5, 1.5, 6.0});
    pole.radius = 0.04;
    pole.half_height = 1.5;
    world.add_collider(pole);
    const int fx = 16 * detail, fy = 10 * detail;
    weft::ClothDesc flag{.name = "flag", .fabric = weft::Fabric::cook(weft::make_grid(1.2, 0.75, fx, fy), {.density = 0.12})};
    flag.transform.translation = {2.5 + 0.65, 2.55, 6.0};
    for (int j = 0; j <= fy; ++j) flag.pins.push_back({.vertex = static_cast<std::uint32_t>(j * (fx + 1))});
    (void)world.add_cloth(flag);

    // A banner across the way between two posts, pinned along its top: the runner goes through it.
    for (double x : {-1.05, 1.05}) {
        auto post = collider(x < 0 ? "post left" : "post right", weft::ColliderShape::Capsule, {x, 1.2, 9.0});
        post.radius = 0.05;
        post.half_height = 1.2;
        world.add_collider(post);
    }
    const int bx = 18 * detail, by = 9 * detail;
    weft::ClothDesc banner{.name = "banner", .fabric = weft::Fabric::cook(weft::make_grid(1.9, 0.9, bx, by), {.density = 0.15})};
    banner.material.stretch_stiffness = 2e4;  // N/m: a heavier weave than the cape's
    banner.transform.translation = {0.0, 2.25 - 0.45, 9.0};  // hangs to 1.35 m: the runner's head and shoulders meet it
    for (int i = 0; i <= bx; ++i) banner.pins.push_back({.vertex = static_cast<std::uint32_t>(by * (bx + 1) + i)});
    (void)world.add_cloth(banner);
    return level;
}

/// Before each step: the runner's motion for the frame [t, t + dt], for its pins and its body.
inline void drive(weft::World& world, const Level& level, const Runner& runner, double t, double dt) {
    const weft::Motion m = runner.motion(t, dt);
    world.motion(level.runner_motion) = m;
    if (level.character) {
        // The character's root is the runner's frame (feet at the origin, facing +z); its clip
        // follows what the runner does: in the air the jump (from its push-off, 0.3 s in), on the
        // ground the run at a pace that follows the speed, standing still its bind pose.
        weft::ColliderDesc& c = world.collider(*level.character);
        c.motion = m;
        const double speed = std::hypot(m.linear_velocity.x, m.linear_velocity.z);
        const std::string clip = !runner.on_ground() ? "jump" : speed > 0.1 ? "run" : "";
        const double pace = clip == "run" ? 0.5 + 0.5 * speed / Runner::kRunSpeed : 1.0;
        // A cut between two poses moves the body as far in one step as they differ: the skirt pinned
        // at its hips could not follow. The clips cross-fade, and the pace changes keep the clip
        // time continuous.
        constexpr double kClipFade = 0.15;  // s
        if (clip != c.clip)
            weft::switch_clip(c, clip, t, kClipFade, clip == "run", pace, clip == "jump" ? 0.3 : 0.0);
        else
            weft::set_clip_speed(c, t, pace);
        return;
    }
    // The body parts sit on the runner's vertical axis, which its turning leaves in place.
    world.collider(level.body).motion = m;
    world.collider(level.body).motion.origin += Vec3d{0.0, 0.95, 0.0};
    world.collider(level.head).motion = m;
    world.collider(level.head).motion.origin += Vec3d{0.0, 1.72, 0.0};
}

}  // namespace cape_runner
