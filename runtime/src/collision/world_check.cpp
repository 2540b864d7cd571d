// Exact intersection check of a world state (see world_check.h).
#include "collision/world_check.h"

#include <string>

#include "weft/error.h"

namespace weft::collision {

WorldIntersections check_world_intersections(const Model& model, std::span<const std::vector<Vec3d>> cloth_positions,
                                             double t) {
    if (cloth_positions.size() != model.cloths.size())
        throw Error("check_world_intersections: " + std::to_string(cloth_positions.size()) + " position arrays for " +
                    std::to_string(model.cloths.size()) + " cloths");
    std::vector<Vec3d> positions;
    std::vector<Triangle> triangles;
    for (std::size_t c = 0; c < model.cloths.size(); ++c) {
        const auto base = static_cast<std::uint32_t>(positions.size());
        positions.insert(positions.end(), cloth_positions[c].begin(), cloth_positions[c].end());
        for (const Triangle& tri : model.cloths[c].fabric->triangles())
            triangles.push_back({{base + tri.v[0], base + tri.v[1], base + tri.v[2]}});
    }
    // Mesh colliders at time t, in their own index range.
    std::vector<Vec3d> collider_positions;
    std::vector<Triangle> collider_triangles;
    for (const ColliderDesc& c : model.colliders) {
        if (c.is_analytic() || !c.mesh) continue;
        const auto base = static_cast<std::uint32_t>(collider_positions.size());
        collider_positions.resize(base + c.mesh->positions.size());
        collider_mesh_positions(c, t, std::span<Vec3d>(collider_positions).subspan(base));
        for (const Triangle& tri : c.mesh->triangles)
            collider_triangles.push_back({{base + tri.v[0], base + tri.v[1], base + tri.v[2]}});
    }
    IntersectionCheckOptions options;
    options.max_examples = 0;
    WorldIntersections out;
    out.cloth_with_cloth = check_intersections(positions, triangles, options).intersecting_pairs;
    if (collider_triangles.empty()) return out;

    // Pairs are counted additively: (all) − (collider with collider) − (cloth with cloth) leaves the
    // pairs of a cloth triangle with a collider's.
    const auto shift = static_cast<std::uint32_t>(positions.size());
    positions.insert(positions.end(), collider_positions.begin(), collider_positions.end());
    for (const Triangle& tri : collider_triangles)
        triangles.push_back({{shift + tri.v[0], shift + tri.v[1], shift + tri.v[2]}});
    const std::size_t all = check_intersections(positions, triangles, options).intersecting_pairs;
    const std::size_t colliders_only = check_intersections(collider_positions, collider_triangles, options).intersecting_pairs;
    out.cloth_with_collider = all - colliders_only - out.cloth_with_cloth;
    return out;
}

}  // namespace weft::collision
