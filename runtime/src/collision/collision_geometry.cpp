// The collision index space shared by both backends (see collision_geometry.h).
#include "weft/backend/collision_geometry.h"

#include <algorithm>

#include "weft/error.h"

namespace weft::collision {

CollisionGeometry build_collision_geometry(const FlatModel& flat, const Model& model) {
    CollisionGeometry g;
    g.self = model.settings.collision.self_collision;
    g.cloth_vertices = flat.vertex_count;
    std::uint32_t kinematic = 0;
    for (std::size_t k = 0; k < model.colliders.size(); ++k) {
        const ColliderDesc& c = model.colliders[k];
        if (c.is_analytic()) continue;
        if (!c.mesh) throw Error("collider '" + c.name + "' is a mesh collider without a mesh");
        g.meshes.push_back({k, kinematic});
        kinematic += static_cast<std::uint32_t>(c.mesh->positions.size());
    }
    g.triangles = flat.triangles;
    g.triangle_group.resize(flat.triangle_count());
    for (std::size_t t = 0; t < flat.triangle_count(); ++t) g.triangle_group[t] = g.self ? flat.triangle_cloth[t] : 0;
    const std::size_t cloths = model.cloths.size();
    g.first_kinematic_group = static_cast<std::uint32_t>(cloths);
    for (std::size_t m = 0; m < g.meshes.size(); ++m) {
        const MeshData& mesh = *model.colliders[g.meshes[m].collider].mesh;
        const auto base = static_cast<std::uint32_t>(g.cloth_vertices) + g.meshes[m].first_vertex;
        for (const Triangle& tri : mesh.triangles) {
            g.triangles.push_back({{base + tri.v[0], base + tri.v[1], base + tri.v[2]}});
            g.triangle_group.push_back(static_cast<std::uint32_t>(cloths + m));
        }
        g.kinematic_local.insert(g.kinematic_local.end(), mesh.positions.begin(), mesh.positions.end());
    }
    g.edges = build_edges(g.triangles);

    const std::size_t n = g.vertex_count();
    g.inverse_mass.assign(n, 0.0);
    g.thickness.assign(n, 0.0);
    g.friction.assign(n, 0.0);
    for (std::size_t i = 0; i < g.cloth_vertices; ++i) {
        const bool pinned = flat.vertex_pin[i] >= 0;
        g.inverse_mass[i] = pinned || !(flat.mass[i] > 0.0) ? 0.0 : 1.0 / flat.mass[i];
        const Material& material = model.cloths[flat.vertex_cloth[i]].material;
        g.thickness[i] = material.contact_thickness;
        g.friction[i] = material.friction;
        g.max_thickness = std::max(g.max_thickness, material.contact_thickness);
    }
    g.rest = flat.initial_positions;
    g.vertex_cloth = flat.vertex_cloth;
    for (const CollisionGeometry::MeshCollider& mc : g.meshes) {
        const ColliderDesc& c = model.colliders[mc.collider];
        const std::size_t first = g.cloth_vertices + mc.first_vertex;
        std::fill_n(g.friction.begin() + static_cast<std::ptrdiff_t>(first), c.mesh->positions.size(),
                    c.friction >= 0.0 ? c.friction : 0.0);
    }
    return g;
}

void CollisionGeometry::place_kinematic(const Model& model, double t, std::span<Vec3d> out) const {
    for (std::size_t m = 0; m < meshes.size(); ++m) {
        const ColliderDesc& c = model.colliders[meshes[m].collider];
        const std::size_t last = m + 1 < meshes.size() ? meshes[m + 1].first_vertex : kinematic_local.size();
        if (plays_clip(c)) {  // a character: its clip bends the mesh before its motion places it
            collider_mesh_positions(c, t, out.subspan(meshes[m].first_vertex, last - meshes[m].first_vertex));
            continue;
        }
        const Transform frame = c.motion.at(t);
        for (std::size_t j = meshes[m].first_vertex; j < last; ++j) out[j] = frame.apply(kinematic_local[j]);
    }
}

}  // namespace weft::collision
