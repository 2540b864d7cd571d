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
    /// Name of a mesh collider (an animated character) whose skin the pins follow instead: each
    /// selected vertex follows the collider vertex nearest to it at t = 0, keeping its offset
    /// (PinDesc::collider). Empty: none. Not together with `motion`.
    std::string follow;
    /// With `follow`: the name of a joint of that character's skeleton (a bone) the pins follow
    /// rigidly, turning with it (PinDesc::collider_joint). Empty: the nearest skin vertex.
    std::string joint;
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
    /// The clip a skinned character plays (`clip` key); non-empty: the file is read as a character.
    std::string clip;
};

struct CameraDesc {
    Vec3d position{0.0, 1.0, 3.0};  ///< m
    Vec3d target{0.0, 0.5, 0.0};    ///< m
    double fov_degrees = 45.0;
};

struct SceneMotion {
    std::string name;
    Motion motion;
    Vec3d rotation_degrees{};  ///< the file's Euler angles behind motion.initial_rotation (save_scene writes them)
};

/// How one `[[cloth]]` table placed its cloths, as written in the file: what save_scene() writes back
/// (the cloths' transforms are derived from it).
struct ClothPlacement {
    std::string name;
    Vec3d position{};          ///< m
    Vec3d rotation_degrees{};  ///< Euler angles, degrees
    int repeat_count = 0;      ///< 0: no `repeat` table
    Vec3d repeat_offset{};     ///< m
    Vec3d repeat_rotation_step{};  ///< degrees
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
    /// Per `[[cloth]]` table (SceneCloth::entry indexes it).
    std::vector<ClothPlacement> cloth_placements;
    /// Per collider: the file's Euler angles behind its initial rotation (zero for one that follows a motion).
    std::vector<Vec3d> collider_rotation_degrees;
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

/// The scene as TOML text in the format of docs/scene-format.md: every key written, numbers in their
/// shortest form that reads back to the same double, mesh paths relative to `directory` (the folder
/// the text will be saved in). Loading the text gives the same scene (tests/scene/test_scene_writer.cpp).
/// The cloths of one `[[cloth]]` table are written as that table, with the first cloth's material:
/// throws `weft::Error` naming the cloths when copies of one table have different materials.
[[nodiscard]] std::string scene_to_toml(const SceneDesc& scene, const std::filesystem::path& directory);
/// Writes scene_to_toml() to `path` (relative to its folder). Throws `weft::Error` naming the file on failure.
void save_scene(const SceneDesc& scene, const std::filesystem::path& path);
/// Copies what can be tuned live in `world` into `scene`: the world settings (solver, gravity, wind,
/// collisions), each cloth's material and pins, each motion, and each collider's sizes, friction and
/// (for one that follows no motion) position. Pins are kept as the scene's rules while the world pins
/// exactly what they select; otherwise (World::pin and unpin were used) the cloth's rules become
/// vertex lists, one per motion, which pin each vertex where the cloth starts. Throws `weft::Error`
/// if the world's cloths, motions or colliders are not the scene's, or if the copies of one
/// `[[cloth]]` table (repeat) have different pins (the format gives them one pin set).
void update_scene_from_world(SceneDesc& scene, const World& world);

/// The pins of `scene.cloths[cloth]` on its cooked `fabric`: the cloth's own PinDescs, then each
/// `[[cloth.pin]]` rule's vertices (a vertex chosen by several rules keeps the first rule's motion;
/// motions indexed in `scene.motions` order, as build_world adds them). A rule with `follow` pins
/// each vertex to the nearest vertex at t = 0 of that collider in `colliders` (the scene's colliders
/// with their meshes loaded, in scene order, as build_world adds them). Throws `weft::Error` naming
/// the file, cloth and rule for a rule that selects nothing or names an unknown motion, vertex or
/// collider, or follows a collider whose mesh `colliders` does not hold.
[[nodiscard]] std::vector<PinDesc> scene_pins(const SceneDesc& scene, std::size_t cloth, const Fabric& fabric,
                                              std::span<const ColliderDesc> colliders = {});

/// Cooks the fabrics (loading mesh files), loads the meshes of mesh colliders, resolves pins and
/// motions and creates the world. Copies made by `repeat` share one cooked fabric. Throws
/// `weft::Error` naming the scene file and the cloth or collider for meshes it cannot use: a cloth
/// mesh that cooking rejects, a collider mesh with no triangles, non-finite positions or zero-area
/// triangles (docs/scene-format.md says why those are errors for colliders).
[[nodiscard]] std::unique_ptr<World> build_world(const SceneDesc& scene, std::string_view backend = "cpu",
                                                 const BackendOptions& options = {});

}  // namespace weft
