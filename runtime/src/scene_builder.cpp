// build_world: a validated SceneDesc → meshes → cooked fabrics → pins → a World.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "weft/error.h"
#include "weft/scene.h"

namespace weft {
namespace {

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

}  // namespace

std::unique_ptr<World> build_world(const SceneDesc& scene, std::string_view backend, const BackendOptions& options) {
    const std::string file = scene.path.string();
    auto world = std::make_unique<World>(scene.world, backend, options);

    std::map<std::string, int> motion_index;
    for (const SceneMotion& m : scene.motions) motion_index[m.name] = world->add_motion(m.motion);
    const auto motion_of = [&](const std::string& name, const std::string& where) {
        if (name.empty()) return -1;
        const auto it = motion_index.find(name);
        if (it == motion_index.end()) throw Error(where + ": unknown motion '" + name + "'");
        return it->second;
    };

    for (std::size_t c = 0; c < scene.cloths.size(); ++c) {
        const SceneCloth& cloth = scene.cloths[c];
        const std::string where = file + ": cloth[" + std::to_string(c) + "] '" + cloth.desc.name + "'";
        ClothDesc desc = cloth.desc;
        try {
            desc.fabric = Fabric::cook(make_mesh(cloth), cloth.fabric);
        } catch (const Error& e) {
            throw Error(where + ": " + e.what());
        }
        // A vertex selected by several rules keeps the first rule's motion.
        std::set<std::uint32_t> pinned;
        for (const PinDesc& p : desc.pins) pinned.insert(p.vertex);
        for (std::size_t k = 0; k < cloth.pins.size(); ++k) {
            const std::string pin_where = where + " pin[" + std::to_string(k) + "]";
            const int motion = motion_of(cloth.pins[k].motion, pin_where);
            for (std::uint32_t v : select(cloth.pins[k], cloth, *desc.fabric, pin_where))
                if (pinned.insert(v).second) desc.pins.push_back({v, motion});
        }
        world->add_cloth(desc);
    }
    for (const ColliderDesc& collider : scene.colliders) world->add_collider(collider);
    return world;
}

}  // namespace weft
