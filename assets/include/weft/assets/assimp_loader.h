#pragma once
/// @file
/// Mesh import through assimp. `install_mesh_loader()` makes `weft::load_mesh_file()` (and so the
/// `mesh = { file = … }` key of scene files) read every format assimp reads: OBJ, PLY, glTF 2 (.gltf
/// and .glb), FBX, Collada, STL … Link `Weft::assets` (in the tree also `weft::assets`); it defines
/// `WEFT_HAVE_ASSETS=1` for its users, so a game that builds with and without it makes the call under
/// `#if WEFT_HAVE_ASSETS` (examples/README.md).

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "weft/fabric.h"

namespace weft::assets {

/// What importing one file did. Degenerate and non-manifold input is not judged here: cooking the
/// fabric counts, drops or works around it and says so in `Fabric::report()`.
struct ImportReport {
    std::string file;
    std::size_t meshes = 0;             ///< assimp meshes merged into one
    std::size_t imported_vertices = 0;  ///< vertices as assimp delivered them (split at UV/normal seams)
    std::size_t welded_vertices = 0;    ///< of those, merged back by position
    std::size_t triangles = 0;
    std::size_t skipped_primitives = 0;  ///< points and lines, which are not cloth
    double weld_tolerance = 0.0;         ///< m: 1e-6 × the bounding-box diagonal
    std::vector<std::string> warnings;   ///< human-readable, one per problem class
};

/// Imports every triangle of `path` into one mesh, in the file's world frame (node transforms applied),
/// and welds vertices closer than 1e-6 × the bounding-box diagonal. Throws `weft::Error` naming the
/// file with assimp's message when the file cannot be read or holds no triangles.
/// Thread-safe (each call uses its own importer).
[[nodiscard]] MeshData import_mesh(const std::filesystem::path& path, ImportReport* report = nullptr);

/// Installs `import_mesh` as the loader behind `weft::load_mesh_file()`, and `import_skinned_mesh`
/// behind `weft::load_skinned_mesh_file()` (a collider's `clip` key). Call once at start-up.
void install_mesh_loader();

}  // namespace weft::assets
