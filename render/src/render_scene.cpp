// The API-neutral scene both renderers draw (see render_scene.h).
#include "weft/backend/model.h"
#include "weft/render/render_scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "weft/error.h"
#include "weft/physics/vec.h"

namespace weft::render {
namespace {

// Cloth colours by cloth index (linear RGB): saturated fronts, paler backs of a different hue, so
// that a fold showing the back reads at once.
struct Palette {
    glm::vec3 front, back;
};
constexpr std::array<Palette, 6> kPalette{{
    {{0.70F, 0.16F, 0.10F}, {0.80F, 0.72F, 0.45F}},  // brick / sand
    {{0.10F, 0.32F, 0.65F}, {0.75F, 0.78F, 0.80F}},  // blue / grey
    {{0.15F, 0.50F, 0.22F}, {0.85F, 0.80F, 0.60F}},  // green / cream
    {{0.60F, 0.40F, 0.05F}, {0.40F, 0.25F, 0.45F}},  // ochre / plum
    {{0.45F, 0.12F, 0.45F}, {0.80F, 0.80F, 0.55F}},  // purple / straw
    {{0.08F, 0.45F, 0.50F}, {0.85F, 0.60F, 0.50F}},  // teal / salmon
}};

constexpr float kGroundHalfSize = 50.0F;  // m
constexpr float kGridSpacing = 0.25F;     // m

glm::vec3 to_glm(Vec3d v) { return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)}; }

RenderVertex vertex(glm::vec3 p, glm::vec3 n) { return RenderVertex{{p.x, p.y, p.z}, {n.x, n.y, n.z}}; }

glm::mat4 to_matrix(const Transform& t) {
    glm::mat4 m(1.0F);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) m[c][r] = static_cast<float>(t.rotation(r, c));  // glm is column-major
    m[3] = glm::vec4(to_glm(t.translation), 1.0F);
    return m;
}

void grow(glm::vec3& lo, glm::vec3& hi, glm::vec3 p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
}

// A sphere swept along local Y by ±half_height (half_height 0: a sphere).
RenderMesh swept_sphere(float radius, float half_height, int slices, int stacks) {
    RenderMesh m;
    stacks += stacks % 2;  // an even count puts a ring on the equator, where the cylinder is cut in
    for (int i = 0; i <= stacks; ++i) {
        const float theta = std::numbers::pi_v<float> * static_cast<float>(i) / static_cast<float>(stacks);
        const float y = std::cos(theta), r = std::sin(theta);
        // The upper half sits at +half_height, the lower at −half_height; the equator ring appears
        // twice (once per half), so the cylinder between them is a quad strip of its own.
        const int copies = (i == stacks / 2 && half_height > 0.0F) ? 2 : 1;
        for (int copy = 0; copy < copies; ++copy) {
            const float shift = (i < stacks / 2 || (i == stacks / 2 && copy == 0)) ? half_height : -half_height;
            for (int j = 0; j <= slices; ++j) {
                const float phi = 2.0F * std::numbers::pi_v<float> * static_cast<float>(j) / static_cast<float>(slices);
                const glm::vec3 n(r * std::cos(phi), y, -r * std::sin(phi));
                m.vertices.push_back(vertex(radius * n + glm::vec3(0.0F, shift, 0.0F), n));
            }
        }
    }
    const auto rings = static_cast<std::uint32_t>(m.vertices.size() / static_cast<std::size_t>(slices + 1));
    const auto row = static_cast<std::uint32_t>(slices + 1);
    for (std::uint32_t i = 0; i + 1 < rings; ++i)
        for (std::uint32_t j = 0; j < static_cast<std::uint32_t>(slices); ++j) {
            const std::uint32_t a = i * row + j, b = a + row;
            // Counter-clockwise seen from outside (phi runs clockwise seen from +Y).
            m.indices.insert(m.indices.end(), {a, b, a + 1, a + 1, b, b + 1});
        }
    return m;
}

}  // namespace

RenderMesh sphere_mesh(float radius, int slices, int stacks) { return swept_sphere(radius, 0.0F, slices, stacks); }

RenderMesh capsule_mesh(float radius, float half_height, int slices, int stacks) {
    return swept_sphere(radius, half_height, slices, stacks);
}

RenderMesh box_mesh(glm::vec3 h) {
    RenderMesh m;
    // Per face: normal axis and the two in-plane axes ordered so that u × v = n (counter-clockwise).
    for (int axis = 0; axis < 3; ++axis)
        for (const float sign : {1.0F, -1.0F}) {
            glm::vec3 n(0.0F);
            n[axis] = sign;
            glm::vec3 u(0.0F), v(0.0F);
            u[(axis + 1) % 3] = 1.0F;
            v[(axis + 2) % 3] = 1.0F;
            if (sign < 0.0F) std::swap(u, v);
            const auto base = static_cast<std::uint32_t>(m.vertices.size());
            const glm::vec3 c = n * h;
            const glm::vec3 du = u * h, dv = v * h;
            m.vertices.push_back(vertex(c - du - dv, n));
            m.vertices.push_back(vertex(c + du - dv, n));
            m.vertices.push_back(vertex(c + du + dv, n));
            m.vertices.push_back(vertex(c - du + dv, n));
            m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
        }
    return m;
}

RenderMesh plane_mesh(float s) {
    RenderMesh m;
    const glm::vec3 n(0.0F, 1.0F, 0.0F);
    m.vertices = {vertex({-s, 0.0F, -s}, n), vertex({-s, 0.0F, s}, n), vertex({s, 0.0F, s}, n), vertex({s, 0.0F, -s}, n)};
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

namespace {

/// `mesh`'s triangles over `positions` as render vertices with smooth, area-weighted normals.
void smooth_mesh_vertices(const MeshData& mesh, std::span<const Vec3d> positions, std::vector<RenderVertex>& out) {
    std::vector<glm::vec3> normals(positions.size(), glm::vec3(0.0F));
    for (const Triangle& t : mesh.triangles) {
        const glm::vec3 a = to_glm(positions[t.v[0]]), b = to_glm(positions[t.v[1]]), d = to_glm(positions[t.v[2]]);
        const glm::vec3 n = glm::cross(b - a, d - a);
        for (const std::uint32_t v : t.v) normals[v] += n;
    }
    out.clear();
    for (std::size_t v = 0; v < normals.size(); ++v) {
        const float len = glm::length(normals[v]);
        out.push_back(vertex(to_glm(positions[v]), len > 0.0F ? normals[v] / len : glm::vec3(0.0F, 1.0F, 0.0F)));
    }
}

}  // namespace

RenderScene make_render_scene(const World& world, const CameraDesc& camera) {
    const Model& model = world.model();
    RenderScene scene;
    glm::vec3 lo(1e30F), hi(-1e30F);
    std::uint32_t first = 0;
    for (std::size_t c = 0; c < model.cloths.size(); ++c) {
        const ClothDesc& cloth = model.cloths[c];
        ClothDraw draw;
        draw.name = cloth.name;
        draw.first_vertex = first;
        draw.vertex_count = static_cast<std::uint32_t>(cloth.fabric->vertex_count());
        draw.first_index = static_cast<std::uint32_t>(scene.cloth_indices.size());
        for (const Triangle& t : cloth.fabric->triangles())
            for (const std::uint32_t v : t.v) scene.cloth_indices.push_back(first + v);
        draw.index_count = static_cast<std::uint32_t>(scene.cloth_indices.size()) - draw.first_index;
        const Palette& p = kPalette[c % kPalette.size()];
        draw.front_colour = p.front;
        draw.back_colour = p.back;
        for (const Vec3d& r : cloth.fabric->rest_positions()) grow(lo, hi, to_glm(cloth.transform.apply(r)));
        first += draw.vertex_count;
        scene.cloths.push_back(std::move(draw));
    }
    scene.cloth_vertices = first;
    scene.cloth_edges = edge_indices(scene.cloth_indices);

    bool has_ground = false;
    for (std::size_t k = 0; k < model.colliders.size(); ++k) {
        const ColliderDesc& c = model.colliders[k];
        ColliderDraw draw;
        draw.name = c.name;
        draw.collider = k;
        switch (c.shape) {
            case ColliderShape::Sphere: draw.mesh = sphere_mesh(static_cast<float>(c.radius)); break;
            case ColliderShape::Capsule:
                draw.mesh = capsule_mesh(static_cast<float>(c.radius), static_cast<float>(c.half_height));
                break;
            case ColliderShape::Box: draw.mesh = box_mesh(to_glm(c.half_extents)); break;
            case ColliderShape::Plane:
                draw.mesh = plane_mesh(kGroundHalfSize);
                draw.grid_spacing = kGridSpacing;
                draw.colour = {0.55F, 0.55F, 0.52F};
                has_ground = true;
                break;
            case ColliderShape::Mesh: {
                if (!c.mesh) throw Error("collider '" + c.name + "': a mesh collider without a mesh");
                // A character playing a clip is drawn as placed (world space, pose at t = 0 until a
                // frame brings its vertices); a rigid mesh in its own frame, moved by its model matrix.
                draw.deforms = c.skin != nullptr;  // a clip may start later
                std::vector<Vec3d> placed(c.mesh->positions);
                if (draw.deforms) {
                    collider_mesh_positions(c, 0.0, placed);
                    draw.first_deforming_vertex = scene.deforming_vertices;
                    scene.deforming_vertices += static_cast<std::uint32_t>(placed.size());
                }
                smooth_mesh_vertices(*c.mesh, placed, draw.mesh.vertices);
                for (const Triangle& t : c.mesh->triangles) draw.mesh.indices.insert(draw.mesh.indices.end(), {t.v[0], t.v[1], t.v[2]});
                draw.colour = {0.62F, 0.58F, 0.55F};
                break;
            }
        }
        if (c.shape != ColliderShape::Plane) {
            const glm::mat4 m = draw.deforms ? glm::mat4(1.0F) : to_matrix(c.motion.at(0.0));
            for (const RenderVertex& v : draw.mesh.vertices)
                grow(lo, hi, glm::vec3(m * glm::vec4(v.position[0], v.position[1], v.position[2], 1.0F)));
        }
        scene.colliders.push_back(std::move(draw));
    }
    if (!has_ground) {
        ColliderDraw ground;
        ground.name = "ground";
        ground.mesh = plane_mesh(kGroundHalfSize);
        ground.grid_spacing = kGridSpacing;
        ground.colour = {0.55F, 0.55F, 0.52F};
        scene.colliders.push_back(std::move(ground));
    }
    if (lo.x > hi.x) lo = hi = glm::vec3(0.0F);
    // Shadows fall on the ground below the cloth: the box reaches down to y = 0.
    lo.y = std::min(lo.y, 0.0F);
    const glm::vec3 centre = 0.5F * (lo + hi), half = 0.75F * (hi - lo) + glm::vec3(0.05F);
    scene.bounds_min = centre - half;
    scene.bounds_max = centre + half;

    scene.camera.position = to_glm(camera.position);
    scene.camera.target = to_glm(camera.target);
    scene.camera.fov_degrees = static_cast<float>(camera.fov_degrees);
    return scene;
}

std::vector<glm::mat4> collider_models(const RenderScene& scene, const Model& model, double t) {
    std::vector<glm::mat4> out;
    out.reserve(scene.colliders.size());
    for (const ColliderDraw& c : scene.colliders)
        out.push_back(c.collider < model.colliders.size() && !c.deforms ? to_matrix(model.colliders[c.collider].motion.at(t))
                                                                        : glm::mat4(1.0F));
    return out;
}

void deforming_collider_vertices(const RenderScene& scene, const Model& model, double t, std::vector<RenderVertex>& out) {
    out.resize(scene.deforming_vertices);
    std::vector<Vec3d> placed;
    std::vector<RenderVertex> one;
    for (const ColliderDraw& c : scene.colliders) {
        if (!c.deforms) continue;
        if (c.collider >= model.colliders.size() || !model.colliders[c.collider].mesh)
            throw Error("render: collider '" + c.name + "' is not in the model (rebuild the render scene after a topology change)");
        const ColliderDesc& desc = model.colliders[c.collider];
        placed.resize(desc.mesh->positions.size());
        if (c.first_deforming_vertex + placed.size() > out.size())
            throw Error("render: collider '" + c.name + "' has " + std::to_string(placed.size()) +
                        " vertices, more than the scene made room for (rebuild the render scene after a topology change)");
        collider_mesh_positions(desc, t, placed);
        smooth_mesh_vertices(*desc.mesh, placed, one);
        std::copy(one.begin(), one.end(), out.begin() + c.first_deforming_vertex);
    }
}

void cloth_vertices(const World& world, const RenderScene& scene, std::vector<RenderVertex>& out) {
    out.resize(scene.cloth_vertices);
    std::vector<glm::vec3> normals;
    for (std::size_t c = 0; c < scene.cloths.size(); ++c) {
        const ClothDraw& draw = scene.cloths[c];
        const std::vector<Vec3d> x = world.positions(c);
        if (x.size() != draw.vertex_count)
            throw Error("render: cloth '" + draw.name + "' has " + std::to_string(x.size()) + " vertices, the scene " +
                        std::to_string(draw.vertex_count) + " (rebuild the render scene after a topology change)");
        normals.assign(x.size(), glm::vec3(0.0F));
        for (std::uint32_t k = draw.first_index; k < draw.first_index + draw.index_count; k += 3) {
            const std::uint32_t a = scene.cloth_indices[k] - draw.first_vertex;
            const std::uint32_t b = scene.cloth_indices[k + 1] - draw.first_vertex;
            const std::uint32_t d = scene.cloth_indices[k + 2] - draw.first_vertex;
            const glm::vec3 n = glm::cross(to_glm(x[b] - x[a]), to_glm(x[d] - x[a]));
            normals[a] += n;
            normals[b] += n;
            normals[d] += n;
        }
        for (std::size_t i = 0; i < x.size(); ++i) {
            const float len = glm::length(normals[i]);
            out[draw.first_vertex + i] = vertex(to_glm(x[i]), len > 0.0F ? normals[i] / len : glm::vec3(0.0F, 1.0F, 0.0F));
        }
    }
}

std::vector<std::uint32_t> edge_indices(std::span<const std::uint32_t> triangles) {
    if (triangles.size() % 3 != 0)
        throw Error("edge_indices: " + std::to_string(triangles.size()) + " indices are not whole triangles");
    std::vector<std::uint64_t> seen;  // (smaller << 32 | larger), sorted below to find repeats
    seen.reserve(triangles.size());
    for (std::size_t k = 0; k < triangles.size(); k += 3)
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t a = triangles[k + e], b = triangles[k + (e + 1) % 3];
            seen.push_back(std::uint64_t{std::min(a, b)} << 32 | std::max(a, b));
        }
    // Keep each edge at its first appearance: sort a copy, then walk the original order.
    std::vector<std::uint64_t> sorted = seen;
    std::sort(sorted.begin(), sorted.end());
    std::vector<bool> taken(sorted.size(), false);
    std::vector<std::uint32_t> out;
    out.reserve(seen.size());
    for (const std::uint64_t key : seen) {
        const auto at = static_cast<std::size_t>(std::lower_bound(sorted.begin(), sorted.end(), key) - sorted.begin());
        if (taken[at]) continue;
        taken[at] = true;
        out.push_back(static_cast<std::uint32_t>(key >> 32));
        out.push_back(static_cast<std::uint32_t>(key & 0xFFFFFFFFU));
    }
    return out;
}

}  // namespace weft::render
