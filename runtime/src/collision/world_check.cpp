// Exact intersection check of a world state (see world_check.h).
#include "collision/world_check.h"

#include <string>

#include "weft/error.h"

namespace weft::collision {

namespace {

/// Every cloth's triangles then every mesh collider's at time t, in one soup, with where each came
/// from.
struct Soup {
    std::vector<Vec3d> positions;
    std::vector<Triangle> triangles;
    std::size_t cloth_triangles = 0;
    std::vector<std::size_t> owner;       ///< per triangle: its cloth, or its collider's index
    std::vector<std::uint32_t> local;     ///< per triangle: its index in that cloth or collider
};

Soup world_soup(const Model& model, std::span<const std::vector<Vec3d>> cloth_positions, double t) {
    Soup s;
    for (std::size_t c = 0; c < model.cloths.size(); ++c) {
        const auto base = static_cast<std::uint32_t>(s.positions.size());
        s.positions.insert(s.positions.end(), cloth_positions[c].begin(), cloth_positions[c].end());
        std::uint32_t k = 0;
        for (const Triangle& tri : model.cloths[c].fabric->triangles()) {
            s.triangles.push_back({{base + tri.v[0], base + tri.v[1], base + tri.v[2]}});
            s.owner.push_back(c);
            s.local.push_back(k++);
        }
    }
    s.cloth_triangles = s.triangles.size();
    for (std::size_t i = 0; i < model.colliders.size(); ++i) {
        const ColliderDesc& c = model.colliders[i];
        if (c.is_analytic() || !c.mesh) continue;
        const auto base = static_cast<std::uint32_t>(s.positions.size());
        s.positions.resize(base + c.mesh->positions.size());
        collider_mesh_positions(c, t, std::span<Vec3d>(s.positions).subspan(base));
        std::uint32_t k = 0;
        for (const Triangle& tri : c.mesh->triangles) {
            s.triangles.push_back({{base + tri.v[0], base + tri.v[1], base + tri.v[2]}});
            s.owner.push_back(i);
            s.local.push_back(k++);
        }
    }
    return s;
}

}  // namespace

std::vector<IntersectingTriangles> list_world_intersections(const Model& model, std::span<const std::vector<Vec3d>> cloth_positions,
                                                            double t, std::size_t max_pairs) {
    if (cloth_positions.size() != model.cloths.size())
        throw Error("list_world_intersections: " + std::to_string(cloth_positions.size()) + " position arrays for " +
                    std::to_string(model.cloths.size()) + " cloths");
    const Soup s = world_soup(model, cloth_positions, t);
    // The examples are the smallest pairs by (a, b), and the cloth triangles come first: every pair
    // with a cloth triangle sorts before every pair of two collider triangles, so the first
    // max_pairs examples with a cloth triangle are the ones asked for.
    IntersectionCheckOptions options;
    options.max_examples = max_pairs;
    const IntersectionReport report = check_intersections(s.positions, s.triangles, options);
    std::vector<IntersectingTriangles> out;
    for (const IntersectingPair& p : report.examples) {
        if (p.a >= s.cloth_triangles) break;
        out.push_back({s.owner[p.a], s.local[p.a], p.b >= s.cloth_triangles, s.owner[p.b], s.local[p.b]});
    }
    return out;
}

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
