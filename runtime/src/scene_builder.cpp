// build_world: a validated SceneDesc → meshes → cooked fabrics → pins → a World.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>

#include "weft/error.h"
#include "weft/scene.h"
#include "weft/world_limits.h"

namespace weft {
namespace {

/// Every scaled coordinate within the scene's extent (weft/world_limits.h), else an error naming
/// the vertex and its coordinate.
void check_extent(const MeshData& mesh, const std::string& where) {
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        const Vec3d& p = mesh.positions[i];
        for (int k = 0; k < 3; ++k)
            if (!(std::abs(p[k]) <= kWorldExtent)) {
                char value[32];
                std::snprintf(value, sizeof(value), "%g", p[k]);
                throw Error(where + ": vertex " + std::to_string(i) + " has coordinate " + value +
                            " m after the mesh's scale, beyond the ±" + std::to_string(static_cast<long long>(kWorldExtent)) +
                            " m a scene may use (float keeps about 8 mm there)");
            }
    }
}

MeshData make_mesh(const SceneCloth& cloth) {
    const ClothSource& src = cloth.source;
    if (src.kind == ClothSource::Kind::Grid) {
        MeshData mesh = make_grid(src.width, src.height, src.cells_x, src.cells_y, src.plane);
        mesh.source = "cloth '" + cloth.desc.name + "' (" + mesh.source + ")";
        return mesh;
    }
    MeshData mesh = load_mesh_file(src.file);
    if (src.scale != 1.0)
        for (Vec3d& p : mesh.positions) p = src.scale * p;
    check_extent(mesh, src.file.string());
    return mesh;
}

std::uint32_t grid_index(const ClothSource& src, int i, int j) {
    return static_cast<std::uint32_t>(j * (src.cells_x + 1) + i);
}

// Vertex indices of one pin selection on the cooked fabric (rest coordinates, before the cloth's
// transform). Edge and corner rules use the grid index layout of make_grid (mesh.h); cooking keeps
// that layout because a grid has no degenerate triangles or unreferenced vertices (checked).
std::vector<std::uint32_t> select(const PinSelection& pin, const SceneCloth& cloth, const Fabric& fabric,
                                  const std::string& where) {
    std::vector<std::uint32_t> out;
    const ClothSource& src = cloth.source;
    switch (pin.kind) {
        case PinSelection::Kind::Vertices:
            for (std::uint32_t v : pin.vertices) {
                if (v >= fabric.vertex_count())
                    throw Error(where + ": vertex " + std::to_string(v) + " is out of range (the cooked mesh has " +
                                std::to_string(fabric.vertex_count()) + " vertices)");
                out.push_back(v);
            }
            break;
        case PinSelection::Kind::Box: {
            const auto rest = fabric.rest_positions();
            for (std::size_t v = 0; v < rest.size(); ++v) {
                const Vec3d p = rest[v];
                if (p.x >= pin.box_min.x && p.x <= pin.box_max.x && p.y >= pin.box_min.y && p.y <= pin.box_max.y &&
                    p.z >= pin.box_min.z && p.z <= pin.box_max.z)
                    out.push_back(static_cast<std::uint32_t>(v));
            }
            break;
        }
        case PinSelection::Kind::Edge:
        case PinSelection::Kind::Corners: {
            if (src.kind != ClothSource::Kind::Grid) throw Error(where + ": edge and corner pins need a grid mesh");
            const std::size_t expected = static_cast<std::size_t>(src.cells_x + 1) * static_cast<std::size_t>(src.cells_y + 1);
            if (fabric.vertex_count() != expected)
                throw Error(where + ": the cooked grid has " + std::to_string(fabric.vertex_count()) +
                            " vertices instead of " + std::to_string(expected) + "; cannot resolve edge pins");
            const int nx = src.cells_x, ny = src.cells_y;
            const std::string& e = pin.edge;
            if (pin.kind == PinSelection::Kind::Edge) {
                if (e == "top" || e == "bottom")
                    for (int i = 0; i <= nx; ++i) out.push_back(grid_index(src, i, e == "top" ? ny : 0));
                else if (e == "left" || e == "right")
                    for (int j = 0; j <= ny; ++j) out.push_back(grid_index(src, e == "left" ? 0 : nx, j));
                else
                    throw Error(where + ": unknown edge '" + e + "'");
            } else {
                const bool all = e == "all";
                if (all || e == "top" || e == "left") out.push_back(grid_index(src, 0, ny));
                if (all || e == "top" || e == "right") out.push_back(grid_index(src, nx, ny));
                if (all || e == "bottom" || e == "left") out.push_back(grid_index(src, 0, 0));
                if (all || e == "bottom" || e == "right") out.push_back(grid_index(src, nx, 0));
                if (out.empty()) throw Error(where + ": unknown corners '" + e + "'");
            }
            break;
        }
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    if (out.empty()) throw Error(where + ": the selection pins no vertex (check the box against the mesh's rest coordinates)");
    return out;
}

// The triangles of a mesh collider in its local frame: the file's coordinates times `scale`. Unlike a
// cloth, whose cooking drops zero-area triangles and reports them, a collider mesh is taken as it is
// or refused: its triangles are the surface the cloth is kept out of, a zero-area one has no normal
// to push along, and a collider has no cook report through which a dropped triangle would be seen.
std::shared_ptr<const MeshData> load_collider_mesh(const ColliderMeshSource& src, const std::string& where) {
    MeshData mesh;
    try {
        mesh = load_mesh_file(src.file);
    } catch (const Error& e) {
        throw Error(where + ": " + e.what());
    }
    const std::string file = src.file.string();
    if (mesh.triangles.empty()) throw Error(where + ": " + file + ": the mesh has no triangles");
    for (Vec3d& p : mesh.positions) {
        p = src.scale * p;
        if (!math::is_finite(p)) throw Error(where + ": " + file + ": a vertex position is not finite");
    }
    check_extent(mesh, where + ": " + file);
    std::size_t degenerate = 0, first = 0;
    for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
        const Triangle& t = mesh.triangles[k];
        if (t.v[0] >= mesh.positions.size() || t.v[1] >= mesh.positions.size() || t.v[2] >= mesh.positions.size())
            throw Error(where + ": " + file + ": triangle " + std::to_string(k) + " has a vertex index out of range");
        const Vec3d a = mesh.positions[t.v[0]], b = mesh.positions[t.v[1]], c = mesh.positions[t.v[2]];
        // The rule Fabric::cook uses: twice the area against the longest edge squared (scale-free).
        const double area2 = math::length(math::cross(b - a, c - a));
        const double longest = std::max({math::length_squared(b - a), math::length_squared(c - b),
                                         math::length_squared(a - c)});
        if (t.v[0] == t.v[1] || t.v[1] == t.v[2] || t.v[0] == t.v[2] || longest == 0.0 || !(area2 > 1e-10 * longest)) {
            if (degenerate == 0) first = k;
            ++degenerate;
        }
    }
    if (degenerate > 0)
        throw Error(where + ": " + file + ": " + std::to_string(degenerate) + " of " +
                    std::to_string(mesh.triangles.size()) + " triangles have zero area, the first is triangle " +
                    std::to_string(first) +
                    " (expected a collider mesh without degenerate triangles: remove them where the mesh is made)");
    mesh.source = file;
    return std::make_shared<const MeshData>(std::move(mesh));
}

}  // namespace

std::vector<PinDesc> scene_pins(const SceneDesc& scene, std::size_t cloth_index, const Fabric& fabric,
                                std::span<const ColliderDesc> colliders) {
    const SceneCloth& cloth = scene.cloths.at(cloth_index);
    const std::string where =
        scene.path.string() + ": cloth[" + std::to_string(cloth.entry) + "] '" + cloth.desc.name + "'";
    std::vector<PinDesc> pins = cloth.desc.pins;
    // A vertex selected by several rules keeps the first rule's motion.
    std::set<std::uint32_t> pinned;
    for (const PinDesc& p : pins) pinned.insert(p.vertex);
    for (std::size_t k = 0; k < cloth.pins.size(); ++k) {
        const std::string pin_where = where + " pin[" + std::to_string(k) + "]";
        int motion = -1;
        if (const std::string& name = cloth.pins[k].motion; !name.empty()) {
            // build_world adds the scene's motions in order, so a motion's index is its place in the list.
            const auto it = std::find_if(scene.motions.begin(), scene.motions.end(),
                                         [&](const SceneMotion& m) { return m.name == name; });
            if (it == scene.motions.end()) throw Error(pin_where + ": unknown motion '" + name + "'");
            motion = static_cast<int>(it - scene.motions.begin());
        }
        const std::vector<std::uint32_t> selected = select(cloth.pins[k], cloth, fabric, pin_where);
        if (const std::string& name = cloth.pins[k].follow; !name.empty()) {
            // A character's skin: each vertex follows the skin vertex nearest to where it starts.
            const auto it = std::find_if(colliders.begin(), colliders.end(), [&](const ColliderDesc& c) { return c.name == name; });
            if (it == colliders.end() || !it->mesh)
                throw Error(pin_where + ": follows collider '" + name + "', whose mesh is not loaded (build_world loads it)");
            const int collider = static_cast<int>(it - colliders.begin());
            if (const std::string& joint = cloth.pins[k].joint; !joint.empty()) {  // a bone: rigidly
                if (!it->skin) throw Error(pin_where + ": joint '" + joint + "' of collider '" + name + "', which has no skeleton");
                std::string names;
                int index = -1;
                for (std::size_t j = 0; j < it->skin->joints.size(); ++j) {
                    if (it->skin->joints[j].name == joint) index = static_cast<int>(j);
                    names += (j > 0 ? ", '" : "'") + it->skin->joints[j].name + "'";
                }
                if (index < 0)
                    throw Error(pin_where + ": unknown joint '" + joint + "' of collider '" + name + "' (expected one of " +
                                names + ")");
                for (std::uint32_t v : selected)
                    if (pinned.insert(v).second) pins.push_back({.vertex = v, .collider = collider, .collider_joint = index});
                continue;
            }
            std::vector<Vec3d> skin(it->mesh->positions.size());
            collider_mesh_positions(*it, 0.0, skin);
            const auto rest = fabric.rest_positions();
            for (std::uint32_t v : selected) {
                if (!pinned.insert(v).second) continue;
                const Vec3d start = cloth.desc.transform.apply(rest[v]);
                std::uint32_t nearest = 0;
                double best = std::numeric_limits<double>::infinity();
                for (std::uint32_t j = 0; j < skin.size(); ++j)
                    if (const double d = length_squared(skin[j] - start); d < best) {
                        best = d;
                        nearest = j;
                    }
                pins.push_back({.vertex = v, .collider = collider, .collider_vertex = nearest});
            }
            continue;
        }
        for (std::uint32_t v : selected)
            if (pinned.insert(v).second) pins.push_back({v, motion});
    }
    return pins;
}

std::unique_ptr<World> build_world(const SceneDesc& scene, std::string_view backend, const BackendOptions& options) {
    const std::string file = scene.path.string();
    auto world = std::make_unique<World>(scene.world, backend, options);

    // In the scene's order: scene_pins() relies on it to index a pin's motion.
    for (const SceneMotion& m : scene.motions) (void)world->add_motion(m.motion);

    // Colliders before cloths: a cloth's pins may follow a mesh collider's skin. Colliders that name
    // the same file at the same scale share one mesh.
    std::vector<ColliderDesc> placed;  // as added, meshes loaded
    std::map<std::pair<std::filesystem::path, double>, std::shared_ptr<const MeshData>> meshes;
    for (std::size_t k = 0; k < scene.colliders.size(); ++k) {
        ColliderDesc collider = scene.colliders[k];
        if (collider.shape == ColliderShape::Mesh && !collider.mesh) {
            const std::string where = file + ": collider[" + std::to_string(k) + "] '" + collider.name + "'";
            if (k >= scene.collider_meshes.size() || scene.collider_meshes[k].file.empty())
                throw Error(where + ": a mesh collider without a mesh file");
            const ColliderMeshSource& src = scene.collider_meshes[k];
            if (!src.clip.empty()) {  // an animated character: its bind-pose mesh is the collider's
                if (src.scale != 1.0)
                    throw Error(where + ": scale " + std::to_string(src.scale) +
                                " with a clip (a skinned character is taken at its file's size; scale it where it is made)");
                std::shared_ptr<const SkinnedMesh> skin;
                try {
                    skin = std::make_shared<const SkinnedMesh>(load_skinned_mesh_file(src.file));
                } catch (const Error& e) {
                    throw Error(where + ": " + e.what());
                }
                collider.skin = skin;
                collider.clip = src.clip;
                collider.mesh = std::make_shared<const MeshData>(skin->mesh);
                try {
                    world->add_collider(collider);  // checks the clip (naming the file's clips)
                } catch (const Error& e) {
                    throw Error(where + ": " + e.what());
                }
                placed.push_back(std::move(collider));
                continue;
            }
            auto& mesh = meshes[{src.file, src.scale}];
            if (!mesh) mesh = load_collider_mesh(src, where);
            collider.mesh = mesh;
        }
        world->add_collider(collider);
        placed.push_back(std::move(collider));
    }
    // Copies made by `repeat` are adjacent and identical up to their placement: they share one fabric.
    std::shared_ptr<const Fabric> shared;
    std::size_t vertices = 0;  // in the world so far, against kMaxWorldVertices
    for (std::size_t c = 0; c < scene.cloths.size(); ++c) {
        const SceneCloth& cloth = scene.cloths[c];
        const std::string where = file + ": cloth[" + std::to_string(cloth.entry) + "] '" + cloth.desc.name + "'";
        ClothDesc desc = cloth.desc;
        if (c > 0 && scene.cloths[c - 1].entry == cloth.entry && shared) {
            desc.fabric = shared;
        } else {
            try {
                desc.fabric = Fabric::cook(make_mesh(cloth), cloth.fabric);
            } catch (const Error& e) {
                throw Error(where + ": " + e.what());
            }
            shared = desc.fabric;
            // The entry's copies all at once, before any is added.
            std::size_t copies = 1;
            while (c + copies < scene.cloths.size() && scene.cloths[c + copies].entry == cloth.entry) ++copies;
            const std::size_t total = vertices + copies * desc.fabric->vertex_count();
            if (total > kMaxWorldVertices)
                throw Error(where + ": " + std::to_string(copies) + (copies == 1 ? " copy" : " copies") + " of " +
                            std::to_string(desc.fabric->vertex_count()) + " vertices bring the world to " + std::to_string(total) +
                            " cloth vertices, more than the " + std::to_string(kMaxWorldVertices) +
                            " a world may hold (weft/world_limits.h; check the grid cells and the repeat count)");
        }
        vertices += desc.fabric->vertex_count();
        desc.pins = scene_pins(scene, c, *desc.fabric, placed);
        world->add_cloth(desc);
    }
    return world;
}

}  // namespace weft
