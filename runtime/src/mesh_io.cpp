// Mesh files: the pluggable importer (assets/ installs an assimp one) and PLY/OBJ export.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <string>

#include "weft/atomic_file.h"
#include "weft/error.h"
#include "weft/mesh.h"

namespace weft {
namespace {

struct LoaderSlot {
    std::mutex mutex;
    MeshFileLoader loader;
    SkinnedMeshFileLoader skinned;
};

LoaderSlot& loader_slot() {
    static LoaderSlot slot;
    return slot;
}

std::string lowercase_extension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](char c) {
        return static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
    });
    return ext;
}

void put_u32(std::string& out, std::uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xFFU));
}

// Binary little-endian PLY: positions as float32, faces as uchar count + int32 indices (the layout
// every PLY reader accepts).
std::string encode_ply(std::span<const Vec3d> positions, std::span<const Triangle> triangles) {
    std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by weft\n";
    out += "element vertex " + std::to_string(positions.size()) + "\n";
    out += "property float x\nproperty float y\nproperty float z\n";
    out += "element face " + std::to_string(triangles.size()) + "\n";
    out += "property list uchar int vertex_indices\nend_header\n";
    out.reserve(out.size() + positions.size() * 12 + triangles.size() * 13);
    for (const Vec3d& p : positions)
        for (int k = 0; k < 3; ++k) put_u32(out, std::bit_cast<std::uint32_t>(static_cast<float>(p[k])));
    for (const Triangle& t : triangles) {
        out.push_back(3);
        for (std::uint32_t v : t.v) put_u32(out, v);
    }
    return out;
}

std::string encode_obj(std::span<const Vec3d> positions, std::span<const Triangle> triangles) {
    std::string out = "# written by weft\n";
    out.reserve(positions.size() * 40 + triangles.size() * 24);
    char line[128];
    for (const Vec3d& p : positions) {
        const int n = std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
        out.append(line, static_cast<std::size_t>(n));
    }
    for (const Triangle& t : triangles) {
        const int n = std::snprintf(line, sizeof line, "f %u %u %u\n", t.v[0] + 1, t.v[1] + 1, t.v[2] + 1);
        out.append(line, static_cast<std::size_t>(n));
    }
    return out;
}

}  // namespace

void set_mesh_file_loader(MeshFileLoader loader) {
    LoaderSlot& slot = loader_slot();
    const std::lock_guard lock(slot.mutex);
    slot.loader = std::move(loader);
}

void set_skinned_mesh_file_loader(SkinnedMeshFileLoader loader) {
    LoaderSlot& slot = loader_slot();
    const std::lock_guard lock(slot.mutex);
    slot.skinned = std::move(loader);
}

SkinnedMesh load_skinned_mesh_file(const std::filesystem::path& path) {
    SkinnedMeshFileLoader loader;
    {
        LoaderSlot& slot = loader_slot();
        const std::lock_guard lock(slot.mutex);
        loader = slot.skinned;
    }
    if (!loader) throw Error(path.string() + ": character import not built (configure with -DWEFT_ASSETS=ON)");
    return loader(path);
}

bool has_mesh_file_loader() {
    LoaderSlot& slot = loader_slot();
    const std::lock_guard lock(slot.mutex);
    return static_cast<bool>(slot.loader);
}

MeshData load_mesh_file(const std::filesystem::path& path) {
    MeshFileLoader loader;
    {
        LoaderSlot& slot = loader_slot();
        const std::lock_guard lock(slot.mutex);
        loader = slot.loader;
    }
    if (!loader) throw Error(path.string() + ": mesh import not built (configure with -DWEFT_ASSETS=ON)");
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(path.string() + ": mesh file not found");
    MeshData mesh = loader(path);
    if (mesh.source.empty()) mesh.source = path.string();
    // Importers split vertices at UV and normal seams; weld them back relative to the mesh's size so
    // that a garment does not fall apart along its seams. A no-op for loaders that welded already.
    const double diagonal = bounding_box_diagonal(mesh);
    if (std::isfinite(diagonal) && diagonal > 0.0) weld_by_position(mesh, kSeamWeldRelativeTolerance * diagonal);
    return mesh;
}

void write_mesh(const std::filesystem::path& path, std::span<const Vec3d> positions, std::span<const Triangle> triangles) {
    const std::string ext = lowercase_extension(path);
    std::string bytes;
    if (ext == ".ply") {
        bytes = encode_ply(positions, triangles);
    } else if (ext == ".obj") {
        bytes = encode_obj(positions, triangles);
    } else {
        throw Error(path.string() + ": cannot write mesh: unknown extension '" + ext + "' (expected .ply or .obj)");
    }
    write_file_atomically(path, bytes);  // whole or not at all (weft/atomic_file.h)
}

}  // namespace weft
