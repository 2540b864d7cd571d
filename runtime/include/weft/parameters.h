#pragma once
/// @file
/// The parameter table: every key of a scene file (docs/scene-format.md), declared once with its
/// type, unit, valid range, one-line doc, the editor's label, what a change to it takes (live, a
/// re-cook of the fabric or a rebuild of the world) and the struct field that holds it. Defaults are
/// not repeated here: they are the default-constructed structs' values (`parameter_default`).
///
/// The scene loader reads keys, types and ranges from it; the scene writer writes what it lists;
/// `World` checks the ranges of what a game hands it; the editor builds its panels from it; `weft
/// help scene-keys` prints it and docs/scene-format.md's key tables are generated from it. A game
/// may enumerate it too, for its own tuning UI:
///
/// @code
///   for (const weft::Parameter& p : weft::parameter_table())
///       if (p.effect == weft::ParameterEffect::Live && weft::holds<weft::Material>(p))
///           add_slider(p.key(), p.unit, p.range, weft::parameter_number(p, world.material(0)));
/// @endcode
///
/// Adding a knob is one row in runtime/src/parameters.cpp plus the code that uses the value.

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "weft/error.h"
#include "weft/types.h"

namespace weft {

struct WorldDesc;
struct Material;
struct FabricDesc;
struct ClothDesc;
struct ColliderDesc;
struct Motion;
struct ClothSource;
struct ClothPlacement;
struct SceneMotion;
struct ColliderMeshSource;
struct CameraDesc;
struct SceneDesc;
enum class ColliderShape : std::uint8_t;

/// What a scene key holds.
enum class ParameterType : std::uint8_t {
    Real,        ///< a number (a TOML integer is accepted)
    Integer,     ///< a whole number
    Boolean,     ///< true or false
    Choice,      ///< a string, one of `Parameter::choices`; its value is the index in that list
    Vector,      ///< [x, y, z], three numbers
    CellCounts,  ///< [nx, ny], two integers (a grid's resolution)
    String,      ///< a non-empty string: a name, a file, a reference to a `[[motion]]`
    Table,       ///< a sub-table of keys (`mesh`, `material`, `repeat`)
    TableArray,  ///< an array of tables (`[[cloth.pin]]`)
    IndexList,   ///< an array of vertex indices
    Box,         ///< { min = [x, y, z], max = [x, y, z] }
};

/// What a change to a parameter takes before the simulation sees it.
enum class ParameterEffect : std::uint8_t {
    Live,     ///< read at every step: change it on a running `World` (settings, material, motion, collider)
    Recook,   ///< cooked into the fabric: takes a new `Fabric::cook` (the editor's Re-cook)
    Rebuild,  ///< read when the world is built from the scene (placement, pins, shapes): build it again
};

/// How a vector's `Parameter::range` applies.
enum class VectorBound : std::uint8_t {
    Finite,      ///< any finite components; the range is unused
    Length,      ///< the vector's length lies in the range (gravity, wind)
    Components,  ///< each component lies in the range (a box's half extents)
};

/// An interval of valid values, closed unless an end is marked open.
struct ParameterRange {
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
    bool lo_open = false;
    bool hi_open = false;
    [[nodiscard]] bool contains(double v) const {
        return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
    }
    /// "[1e-5, 0.1]", "(0, 100]": the ends in their shortest form.
    [[nodiscard]] std::string text() const;
    /// "[1, 1000]" with the ends as whole numbers.
    [[nodiscard]] std::string integer_text() const;
};

/// The struct a parameter's value lives in (what `ParameterAccess` reads and writes).
enum class ParameterOwner : std::uint8_t {
    None,            ///< structural keys (names, meshes, pins, references): read by the scene loader itself
    World,           ///< WorldDesc: gravity, wind, solver and collision settings
    Material,        ///< Material of a cloth
    Fabric,          ///< FabricDesc of a cloth (cooked)
    Cloth,           ///< ClothDesc
    ClothSource,     ///< ClothSource: the grid or the mesh file (cooked)
    ClothPlacement,  ///< ClothPlacement: a `[[cloth]]` table's position, rotation and repeat
    Motion,          ///< Motion
    SceneMotion,     ///< SceneMotion: a motion's rotation as written in the file
    Collider,        ///< ColliderDesc
    ColliderMesh,    ///< ColliderMeshSource of a mesh collider
    Camera,          ///< CameraDesc
    Scene,           ///< SceneDesc
};

/// The owner enumerator of struct `T` (specialised for each owner type).
template <class T>
inline constexpr ParameterOwner owner_of = ParameterOwner::None;
template <> inline constexpr ParameterOwner owner_of<WorldDesc> = ParameterOwner::World;
template <> inline constexpr ParameterOwner owner_of<Material> = ParameterOwner::Material;
template <> inline constexpr ParameterOwner owner_of<FabricDesc> = ParameterOwner::Fabric;
template <> inline constexpr ParameterOwner owner_of<ClothDesc> = ParameterOwner::Cloth;
template <> inline constexpr ParameterOwner owner_of<ClothSource> = ParameterOwner::ClothSource;
template <> inline constexpr ParameterOwner owner_of<ClothPlacement> = ParameterOwner::ClothPlacement;
template <> inline constexpr ParameterOwner owner_of<Motion> = ParameterOwner::Motion;
template <> inline constexpr ParameterOwner owner_of<SceneMotion> = ParameterOwner::SceneMotion;
template <> inline constexpr ParameterOwner owner_of<ColliderDesc> = ParameterOwner::Collider;
template <> inline constexpr ParameterOwner owner_of<ColliderMeshSource> = ParameterOwner::ColliderMesh;
template <> inline constexpr ParameterOwner owner_of<CameraDesc> = ParameterOwner::Camera;
template <> inline constexpr ParameterOwner owner_of<SceneDesc> = ParameterOwner::Scene;

/// How to reach a parameter's field in its owner struct. Use it through `parameter_number`,
/// `parameter_vector` and their setters, which check the owner's type.
struct ParameterAccess {
    ParameterOwner owner = ParameterOwner::None;
    /// Real, Integer, Boolean (0 or 1) and Choice (the index in `choices`).
    double (*number)(const void* owner) = nullptr;
    void (*set_number)(void* owner, double value) = nullptr;
    /// Vector and CellCounts (nx, ny, 0).
    Vec3d (*vector)(const void* owner) = nullptr;
    void (*set_vector)(void* owner, const Vec3d& value) = nullptr;
    bool integral = false;  ///< the field is an integer or an enumeration (a test holds `type` to it)
};

/// One scene key.
struct Parameter {
    /// The scene table that holds it, array indices left out: "solver", "cloth.material", "collider".
    std::string_view section;
    std::string_view name;  ///< its key in that table: "dt"
    ParameterType type = ParameterType::Real;
    std::string_view unit;  ///< SI unit ("m/s²"), "degrees" for orientations; "" when dimensionless
    /// Real and Integer: the valid values; Vector: see `vector_bound`; CellCounts: each count.
    ParameterRange range{};
    std::string_view doc;    ///< one line: what it does
    std::string_view label;  ///< the editor's widget label ("" for no widget)
    /// The editor panel of a live parameter: solver, collision, world, materials, motions, colliders.
    std::string_view panel;
    ParameterEffect effect = ParameterEffect::Live;
    bool log_scale = false;  ///< the editor's slider spans decades
    VectorBound vector_bound = VectorBound::Finite;
    std::span<const std::string_view> choices{};  ///< Choice: the accepted names
    /// The editor's slider range where the valid range is unbounded or wider than a slider can
    /// show (a motion's origin, a phase; for vectors its `hi` caps the length).
    std::optional<ParameterRange> slider{};
    /// What a valid value is where the type and range do not say ("non-empty, unique").
    std::string_view constraint;
    /// The default as words where it is not the owner struct's default value ("**required**",
    /// "the cloth's"), or where the key has no owner field.
    std::string_view default_text;
    /// Collider keys: the shapes that have the key, one bit per `ColliderShape` (`shape_bit`);
    /// 0 for every shape.
    std::uint8_t shapes = 0;
    /// Negative in the owner struct means "not set": the key is omitted (a collider's friction,
    /// where the cloth's material then applies).
    bool unset_when_negative = false;
    ParameterAccess access{};

    /// "solver.dt", "cloth.material.friction".
    [[nodiscard]] std::string key() const;
    /// Whether a collider of `shape` has this key.
    [[nodiscard]] bool applies_to(ColliderShape shape) const;
};

/// The bit of `shape` in `Parameter::shapes`.
[[nodiscard]] constexpr std::uint8_t shape_bit(ColliderShape shape) {
    return static_cast<std::uint8_t>(1U << static_cast<unsigned>(shape));
}

/// Every scene key, section by section in the order of docs/scene-format.md and of the files the
/// scene writer saves.
[[nodiscard]] std::span<const Parameter> parameter_table();
/// The parameter for `key` ("solver.dt"), or nullptr.
[[nodiscard]] const Parameter* find_parameter(std::string_view key);
/// The parameter `name` of `section`; throws `weft::Error` when there is none (a misspelt name in code).
[[nodiscard]] const Parameter& parameter(std::string_view section, std::string_view name);

/// Whether `p` is a field of struct `Owner`.
template <class Owner>
[[nodiscard]] bool holds(const Parameter& p) {
    return owner_of<Owner> != ParameterOwner::None && p.access.owner == owner_of<Owner>;
}

namespace detail {
[[noreturn]] void wrong_owner(const Parameter& p, std::string_view wanted);
}  // namespace detail

/// The value of `p` in `owner`: a number, a boolean as 0 or 1, a choice as its index.
template <class Owner>
[[nodiscard]] double parameter_number(const Parameter& p, const Owner& owner) {
    if (!holds<Owner>(p) || p.access.number == nullptr) detail::wrong_owner(p, "a number field");
    return p.access.number(&owner);
}
/// Sets `p` in `owner` (integers rounded, choices by index). Does not check the range.
template <class Owner>
void set_parameter_number(const Parameter& p, Owner& owner, double value) {
    if (!holds<Owner>(p) || p.access.set_number == nullptr) detail::wrong_owner(p, "a number field");
    p.access.set_number(&owner, value);
}
/// The vector `p` in `owner` (CellCounts as nx, ny, 0).
template <class Owner>
[[nodiscard]] Vec3d parameter_vector(const Parameter& p, const Owner& owner) {
    if (!holds<Owner>(p) || p.access.vector == nullptr) detail::wrong_owner(p, "a vector field");
    return p.access.vector(&owner);
}
template <class Owner>
void set_parameter_vector(const Parameter& p, Owner& owner, const Vec3d& value) {
    if (!holds<Owner>(p) || p.access.set_vector == nullptr) detail::wrong_owner(p, "a vector field");
    p.access.set_vector(&owner, value);
}

/// The default of a parameter with an owner field: its value in the default-constructed owner.
/// Numbers as `parameter_number` gives them, vectors in `parameter_vector`'s form.
[[nodiscard]] double parameter_default_number(const Parameter& p);
[[nodiscard]] Vec3d parameter_default_vector(const Parameter& p);

/// The default as shown in docs and help: `default_text`, or the owner's default value written as
/// in a scene file ("1e-4", "[0, -9.81, 0]", `"double"`), or "" for a key with neither.
[[nodiscard]] std::string parameter_default_text(const Parameter& p);
/// The valid values as shown in docs and help: "[1e-5, 0.1]", `"float", "double"`, "magnitude ≤ 1000",
/// "finite", or `constraint`.
[[nodiscard]] std::string parameter_range_text(const Parameter& p);

/// Checks every ranged parameter of `owner` (a WorldDesc, Material, Motion or ColliderDesc, the
/// structs a game hands `World`) and throws `weft::Error` for the first out of range, as
/// "WHERE: KEY = VALUE is outside RANGE" (`where` names the owner: "cloth 'flag' material";
/// empty: the parameter's section). Collider keys its shape does not have are skipped.
void check_parameter_ranges(const WorldDesc& owner, std::string_view where = {});
void check_parameter_ranges(const Material& owner, std::string_view where);
void check_parameter_ranges(const Motion& owner, std::string_view where);
void check_parameter_ranges(const ColliderDesc& owner, std::string_view where);
/// Throws as above when `value` is outside the range of `p` (a Real or Integer parameter).
void check_parameter_range(const Parameter& p, double value, std::string_view where);

}  // namespace weft
