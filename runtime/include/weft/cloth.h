#pragma once
/// @file
/// A cloth instance: a shared `Fabric` placed in the world with its own material, pins and state.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "weft/fabric.h"
#include "weft/material.h"
#include "weft/motion.h"

namespace weft {

/// A hard positional constraint on one vertex (filtered out of the solve, Baraff & Witkin 1998 §5).
/// With `motion < 0` the vertex stays where it starts; otherwise it is carried rigidly by
/// `World::motions()[motion]` (a cape pinned to a moving shoulder).
struct PinDesc {
    std::uint32_t vertex = 0;
    int motion = -1;
    /// Or follow vertex `collider_vertex` of mesh collider `collider` (an animated character's skin,
    /// weft/skinning.h), keeping the world offset it had from that vertex at time 0 (translation
    /// only: the offset does not turn with the body, so pin at or near the skin). −1: no collider.
    /// Not together with `motion`.
    int collider = -1;
    std::uint32_t collider_vertex = 0;
    /// Or, with `collider`, follow joint `collider_joint` of the collider's skin (a bone) rigidly: the
    /// pin keeps its place in the joint's frame from time 0, so it turns with the bone (a cape held
    /// at the shoulders as the chest leans). −1: follow `collider_vertex` instead.
    int collider_joint = -1;
    /// Where the pin holds the vertex (m, world; for a pin that follows a motion, where it is at
    /// time 0). Unset: where the vertex starts (the fabric's rest shape placed by the transform).
    /// World::pin sets it to where the vertex is when pinned.
    std::optional<Vec3d> position;
};

struct ClothDesc {
    std::string name;
    std::shared_ptr<const Fabric> fabric;
    Transform transform{};        ///< places the fabric's rest shape in the world
    Material material{};
    std::vector<PinDesc> pins;
    Vec3d initial_velocity{};     ///< m/s, every vertex
};

}  // namespace weft
