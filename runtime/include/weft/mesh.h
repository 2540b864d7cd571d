#pragma once
/// @file
/// Mesh sources for fabrics: procedural grids, mesh files (through a loader that `assets/`
/// installs), welding of split vertices and mesh export.

#include <filesystem>
#include <functional>
#include <string>

#include "weft/fabric.h"
#include "weft/skinning.h"

namespace weft {

/// Orientation of a procedural grid.
enum class GridPlane : std::uint8_t {
    XY,  ///< vertical sheet facing +Z (a flag, a hanging sheet); x to the right, y up
    XZ,  ///< horizontal sheet facing +Y (a table cloth); x to the right, z towards the viewer
};

/// A `cells_x × cells_y` grid of `width × height` metres centred on the origin, each cell split into
/// two triangles along alternating diagonals (so the sheet has no preferred shear direction).
/// Vertex (i, j) has index j·(cells_x+1) + i, i along width and j along height; j = cells_y is the
/// top (XY) or far (XZ, −z) edge. Throws `weft::Error` for non-positive sizes or cell counts.
[[nodiscard]] MeshData make_grid(double width, double height, int cells_x, int cells_y, GridPlane plane = GridPlane::XY);

/// Merges vertices closer than `tolerance` (m), e.g. those an importer split at UV or normal seams,
/// and remaps the triangles. Returns the number of vertices removed. Deterministic.
std::size_t weld_by_position(MeshData& mesh, double tolerance);

/// Relative tolerance of the seam welding that mesh import applies: 1e-6 of the bounding-box
/// diagonal, so that millimetre and metre models behave alike.
inline constexpr double kSeamWeldRelativeTolerance = 1e-6;
/// Length of the diagonal of the mesh's axis-aligned bounding box, m (0 for an empty mesh; not
/// finite when a position is not).
[[nodiscard]] double bounding_box_diagonal(const MeshData& mesh);

/// Loads a mesh file (OBJ, PLY, glTF, FBX … whatever the installed loader reads) and welds it.
/// Throws `weft::Error` naming the file on failure, or saying that mesh import was not built.
using MeshFileLoader = std::function<MeshData(const std::filesystem::path&)>;
void set_mesh_file_loader(MeshFileLoader loader);
[[nodiscard]] bool has_mesh_file_loader();
[[nodiscard]] MeshData load_mesh_file(const std::filesystem::path& path);

/// Loads a skinned character (glTF 2.0, FBX … whatever the installed loader reads: weft::assets
/// installs one). Throws `weft::Error` naming the file on failure, or saying that import was not built.
using SkinnedMeshFileLoader = std::function<SkinnedMesh(const std::filesystem::path&)>;
void set_skinned_mesh_file_loader(SkinnedMeshFileLoader loader);
[[nodiscard]] SkinnedMesh load_skinned_mesh_file(const std::filesystem::path& path);

/// Writes a triangle mesh as PLY (binary little-endian) or OBJ (text), chosen by the extension.
void write_mesh(const std::filesystem::path& path, std::span<const Vec3d> positions, std::span<const Triangle> triangles);

}  // namespace weft
