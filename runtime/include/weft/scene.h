#pragma once
/// @file
/// Scenes: TOML files in `assets/scenes/` (format in docs/scene-format.md) turned into a `World`.

#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {

/// Where a cloth's mesh comes from.
struct ClothSource {
    enum class Kind : std::uint8_t { Grid, File } kind = Kind::Grid;
    double width = 1.0, height = 1.0;   ///< m (grid)
    int cells_x = 32, cells_y = 32;     ///< grid resolution
    GridPlane plane = GridPlane::XY;
    std::filesystem::path file;         ///< mesh file, resolved relative to the scene file
    double scale = 1.0;                 ///< applied to file positions
};

/// A rule that selects pinned vertices from the rest mesh (in fabric coordinates).
struct PinSelection {
    enum class Kind : std::uint8_t { Vertices, Box, Edge, Corners } kind = Kind::Vertices;
    std::vector<std::uint32_t> vertices;  ///< Vertices
    Vec3d box_min{}, box_max{};           ///< Box: every vertex inside (m)
    std::string edge;                     ///< Edge/Corners: "top", "bottom", "left", "right" (grid only)
    std::string motion;                   ///< name of the motion the pins follow; empty = fixed
};

struct SceneCloth {
    ClothDesc desc;            ///< fabric is filled in by build_world()
    ClothSource source;
    FabricDesc fabric;
    std::vector<PinSelection> pins;
    /// Index of the `[[cloth]]` table this cloth comes from. A table with `repeat` makes several
    /// cloths (copies of one mesh, one pin set and one material, placed apart); they share the table's
    /// index and, once built, one cooked `Fabric`.
    std::size_t entry = 0;
};

/// Where a mesh collider's triangles come from: a mesh file that build_world() reads through
/// `load_mesh_file()`, as it reads a cloth's mesh file.
struct ColliderMeshSource {
    std::filesystem::path file;  ///< resolved relative to the scene file; empty for analytic shapes
    double scale = 1.0;          ///< applied to file positions, giving the collider's local frame (m)
};

struct CameraDesc {
    Vec3d position{0.0, 1.0, 3.0};  ///< m
    Vec3d target{0.0, 0.5, 0.0};    ///< m
    double fov_degrees = 45.0;
};

struct SceneMotion {
    std::string name;
    Motion motion;
};

/// A parsed, validated scene.
struct SceneDesc {
    std::string name;
    std::filesystem::path path;
    WorldDesc world{};
    std::vector<SceneCloth> cloths;
    std::vector<ColliderDesc> colliders;
    std::vector<SceneMotion> motions;
    std::vector<std::string> collider_motions;  ///< per collider: motion name or empty
    /// Per collider: the mesh file of a mesh collider (its `ColliderDesc::mesh` stays empty until
    /// build_world() loads it), an empty path for analytic shapes.
    std::vector<ColliderMeshSource> collider_meshes;
    CameraDesc camera{};
    int frames = 300;  ///< frames `weft run` simulates unless told otherwise
};

/// Parses and validates a scene file. `overrides` are "dotted.key=value" strings (the `--set` flag),
/// applied on top of the file as if written in it; a value is parsed as TOML (`1e4`, `true`,
/// `"text"`, `[0, 1, 0]`). Throws `weft::Error` naming the file, line and key (or the override) for
/// syntax errors, unknown keys, wrong types and out-of-range values.
[[nodiscard]] SceneDesc load_scene(const std::filesystem::path& path, std::span<const std::string> overrides = {});
/// Same as load_scene for TOML text already in memory; `name` stands in for the file name in errors.
[[nodiscard]] SceneDesc parse_scene(std::string_view toml_text, const std::filesystem::path& name,
                                    std::span<const std::string> overrides = {});

/// Cooks the fabrics (loading mesh files), loads the meshes of mesh colliders, resolves pins and
/// motions and creates the world. Copies made by `repeat` share one cooked fabric. Throws
/// `weft::Error` naming the scene file and the cloth or collider for meshes it cannot use: a cloth
/// mesh that cooking rejects, a collider mesh with no triangles, non-finite positions or zero-area
/// triangles (docs/scene-format.md says why those are errors for colliders).
[[nodiscard]] std::unique_ptr<World> build_world(const SceneDesc& scene, std::string_view backend = "cpu",
                                                 const BackendOptions& options = {});

}  // namespace weft
