#pragma once
/// @file
/// The complete description a backend simulates: settings, cloths, colliders and motions. The
/// `World` owns one and hands it to its backend; backends never see the world itself.

#include <cstdint>
#include <vector>

#include "weft/cloth.h"
#include "weft/collider.h"
#include "weft/settings.h"

namespace weft {

struct Model {
    WorldDesc settings{};
    std::vector<ClothDesc> cloths;
    std::vector<ColliderDesc> colliders;
    std::vector<Motion> motions;
    /// Incremented whenever something that a backend cooks changes (cloths, pins, colliders added or
    /// removed). Parameter edits (materials, settings, wind) do not change it: backends read them
    /// at every substep.
    std::uint64_t topology_version = 0;
};

}  // namespace weft
