#pragma once
/// @file
/// The complete description a backend simulates: settings, cloths, colliders and motions. The
/// `World` owns one and hands it to its backend; backends never see the world itself.

#include <algorithm>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "weft/cloth.h"
#include "weft/collider.h"
#include "weft/grab.h"
#include "weft/settings.h"

namespace weft {

struct Model {
    WorldDesc settings{};
    std::vector<ClothDesc> cloths;
    std::vector<ColliderDesc> colliders;
    std::vector<Motion> motions;
    /// A spring pulling one vertex (an editor's drag): a parameter like wind, read every substep.
    std::optional<VertexGrab> grab;
    /// Incremented whenever something that a backend cooks changes (cloths, pins, colliders added or
    /// removed). Parameter edits (materials, settings, wind) do not change it: backends read them
    /// at every substep.
    std::uint64_t topology_version = 0;
};

/// True when `settings` and `colliders` ask for the cloth collision pipeline (docs/collisions.md):
/// self-collision, or a mesh collider. A backend without that pipeline refuses such a model instead
/// of silently letting cloth pass through itself.
[[nodiscard]] inline bool needs_cloth_collisions(const WorldDesc& settings, std::span<const ColliderDesc> colliders) {
    return settings.collision.self_collision ||
           std::any_of(colliders.begin(), colliders.end(), [](const ColliderDesc& c) { return !c.is_analytic(); });
}
[[nodiscard]] inline bool needs_cloth_collisions(const Model& m) { return needs_cloth_collisions(m.settings, m.colliders); }

}  // namespace weft
