// The parameter table (weft/parameters.h): every scene key, once. A row names the key, its type,
// unit, valid range and doc, the editor's label, what a change takes, and the field that holds it;
// the default is that field's value in the default-constructed struct (settings.h, material.h,
// fabric.h, collider.h, motion.h, scene.h), so it is written nowhere here.
#include "weft/parameters.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>
#include <utility>

#include "scene_reader.h"
#include "weft/collider.h"
#include "weft/mesh.h"
#include "weft/world_limits.h"
#include "weft/scene.h"
#include "weft/settings.h"

namespace weft {
namespace {

// ---- field access: member pointers turned into the table's plain function pointers

template <auto M>
struct MemberOf;
template <class C, class T, T C::*M>
struct MemberOf<M> {
    using Owner = C;
    using Type = T;
};

// owner.*First.*Rest…: a field, possibly inside a nested struct (WorldDesc::solver then SolverSettings::dt).
template <auto First, auto... Rest>
auto& reach(typename MemberOf<First>::Owner& owner) {
    if constexpr (sizeof...(Rest) == 0)
        return owner.*First;
    else
        return reach<Rest...>(owner.*First);
}
template <auto First, auto... Rest>
const auto& reach(const typename MemberOf<First>::Owner& owner) {
    if constexpr (sizeof...(Rest) == 0)
        return owner.*First;
    else
        return reach<Rest...>(owner.*First);
}

// A double, int, bool or Vec3d field.
template <auto First, auto... Rest>
constexpr ParameterAccess field() {
    using Owner = typename MemberOf<First>::Owner;
    using Field = std::remove_cvref_t<decltype(reach<First, Rest...>(std::declval<Owner&>()))>;
    ParameterAccess a;
    a.owner = owner_of<Owner>;
    if constexpr (std::is_same_v<Field, Vec3d>) {
        a.vector = [](const void* o) -> Vec3d { return reach<First, Rest...>(*static_cast<const Owner*>(o)); };
        a.set_vector = [](void* o, const Vec3d& v) { reach<First, Rest...>(*static_cast<Owner*>(o)) = v; };
    } else {
        static_assert(std::is_arithmetic_v<Field>, "a parameter field is a number, a boolean or a Vec3d");
        a.integral = !std::is_floating_point_v<Field>;
        a.number = [](const void* o) -> double {
            return static_cast<double>(reach<First, Rest...>(*static_cast<const Owner*>(o)));
        };
        a.set_number = [](void* o, double v) {
            Field& f = reach<First, Rest...>(*static_cast<Owner*>(o));
            if constexpr (std::is_same_v<Field, bool>)
                f = v != 0.0;
            else if constexpr (std::is_integral_v<Field>)
                f = static_cast<Field>(std::lround(v));
            else
                f = static_cast<Field>(v);
        };
    }
    return a;
}

/// A collider's rotation as the scene writes it, Euler angles in degrees (weft/motion.h), over the
/// rotation matrix its motion keeps: read back from the matrix, and written as one.
constexpr ParameterAccess collider_rotation() {
    ParameterAccess a;
    a.owner = owner_of<ColliderDesc>;
    a.vector = [](const void* o) -> Vec3d {
        return euler_degrees_from_rotation(static_cast<const ColliderDesc*>(o)->motion.initial_rotation);
    };
    a.set_vector = [](void* o, const Vec3d& v) {
        static_cast<ColliderDesc*>(o)->motion.initial_rotation = rotation_from_euler_degrees(v);
    };
    return a;
}

// An enumeration field whose names are listed in the order of `Values` (the row's `choices`).
template <auto Values, auto First, auto... Rest>
constexpr ParameterAccess choice_field() {
    using Owner = typename MemberOf<First>::Owner;
    ParameterAccess a;
    a.owner = owner_of<Owner>;
    a.integral = true;
    a.number = [](const void* o) -> double {
        const auto current = reach<First, Rest...>(*static_cast<const Owner*>(o));
        for (std::size_t i = 0; i < Values.size(); ++i)
            if (Values[i] == current) return static_cast<double>(i);
        return -1.0;
    };
    a.set_number = [](void* o, double v) {
        const auto i = static_cast<std::size_t>(std::clamp<long>(std::lround(v), 0, static_cast<long>(Values.size()) - 1));
        reach<First, Rest...>(*static_cast<Owner*>(o)) = Values[i];
    };
    return a;
}

// A grid's cells_x and cells_y as one [nx, ny] key.
constexpr ParameterAccess grid_cells() {
    ParameterAccess a;
    a.owner = ParameterOwner::ClothSource;
    a.integral = true;
    a.vector = [](const void* o) -> Vec3d {
        const auto& s = *static_cast<const ClothSource*>(o);
        return {static_cast<double>(s.cells_x), static_cast<double>(s.cells_y), 0.0};
    };
    a.set_vector = [](void* o, const Vec3d& v) {
        auto& s = *static_cast<ClothSource*>(o);
        s.cells_x = static_cast<int>(std::lround(v.x));
        s.cells_y = static_cast<int>(std::lround(v.y));
    };
    return a;
}

// ---- the names of choices, in the order of the values they stand for

constexpr std::string_view kPrecisionNames[] = {"float", "double"};
constexpr std::array kPrecisions{Precision::Float, Precision::Double};
constexpr std::string_view kHessianNames[] = {"fast", "projected"};
constexpr std::array kHessians{HessianMode::Fast, HessianMode::Projected};
constexpr std::string_view kBendingNames[] = {"hinge", "shell", "midedge"};
constexpr std::array kBendings{BendingModel::Hinge, BendingModel::Shell, BendingModel::MidEdge};
constexpr std::string_view kPreconditionerNames[] = {"jacobi", "mas", "auto"};
constexpr std::array kPreconditioners{Preconditioner::Jacobi, Preconditioner::Schwarz, Preconditioner::Auto};
constexpr std::string_view kEnergyGuardNames[] = {"off", "report", "retry"};
constexpr std::array kEnergyGuards{EnergyGuard::Off, EnergyGuard::Report, EnergyGuard::Retry};
constexpr std::string_view kCullingNames[] = {"normal_cone", "none"};
constexpr std::array kCullings{CollisionCulling::NormalCone, CollisionCulling::None};
constexpr std::string_view kCollisionModeNames[] = {"ccd_zones", "offset"};
constexpr std::array kCollisionModes{CollisionMode::CcdZones, CollisionMode::Offset};
constexpr std::string_view kBoundShapeNames[] = {"planar", "sphere"};
constexpr std::array kBoundShapes{BoundShape::Planar, BoundShape::Sphere};
constexpr std::string_view kPlaneNames[] = {"xy", "xz"};
constexpr std::array kPlanes{GridPlane::XY, GridPlane::XZ};
constexpr std::string_view kEdgeNames[] = {"top", "bottom", "left", "right"};
constexpr std::string_view kCornerNames[] = {"top", "bottom", "left", "right", "all"};
// In the order of ColliderShape's values.
constexpr std::string_view kShapeNames[] = {"plane", "sphere", "capsule", "box", "mesh"};

constexpr std::uint8_t kRound = shape_bit(ColliderShape::Sphere) | shape_bit(ColliderShape::Capsule);
constexpr std::uint8_t kCapsule = shape_bit(ColliderShape::Capsule);
constexpr std::uint8_t kBox = shape_bit(ColliderShape::Box);
constexpr std::uint8_t kMesh = shape_bit(ColliderShape::Mesh);

constexpr double kHuge = 1e9;  // bound on a phase: finite, and far beyond any real scene

using T = ParameterType;
using E = ParameterEffect;
using R = ParameterRange;

// clang-format off
constexpr Parameter kTable[] = {
    // ---- [scene]
    {.section = "scene", .name = "name", .type = T::String, .doc = "shown in stats and the editor", .effect = E::Rebuild,
     .constraint = "non-empty", .default_text = "file name without extension"},
    {.section = "scene", .name = "frames", .type = T::Integer, .unit = "frames", .range = R{1, 10'000'000},
     .doc = "frames `weft run` simulates unless `--frames` says otherwise", .effect = E::Rebuild,
     .access = field<&SceneDesc::frames>()},

    // ---- [solver]: the knobs that trade speed for accuracy
    {.section = "solver", .name = "preset", .type = T::String,
     .doc = "a solver preset (interactive, game, balanced, accurate, piled; docs/tuning.md) applied before this "
            "table's other keys and the [collision] table, which win over it",
     .constraint = "a preset's name", .default_text = "none"},
    {.section = "solver", .name = "dt", .type = T::Real, .unit = "s", .range = R{1e-5, 0.1}, .doc = "frame time step",
     .label = "time step", .panel = "solver", .log_scale = true, .access = field<&WorldDesc::solver, &SolverSettings::dt>()},
    {.section = "solver", .name = "substeps", .type = T::Integer, .range = R{1, 1000},
     .doc = "implicit steps per frame (each of `dt/substeps`)", .label = "substeps", .panel = "solver", .log_scale = true,
     .access = field<&WorldDesc::solver, &SolverSettings::substeps>()},
    {.section = "solver", .name = "split_stretch", .type = T::Real, .range = R{0.0, 100.0},
     .doc = "redo a substep as two halves (each may split again) when it left a cloth triangle stretched beyond this "
            "principal stretch (1 at rest) and further than at its start: a fast body dragging light cloth over a long "
            "step; 0 turns it off; the attempt that stretched least is kept",
     .label = "split at stretch", .panel = "solver",
     .access = field<&WorldDesc::solver, &SolverSettings::split_stretch>()},
    {.section = "solver", .name = "max_substep_splits", .type = T::Integer, .range = R{0, 10},
     .doc = "halvings `split_stretch` may make of one substep (at most 2^this pieces)", .label = "max splits",
     .panel = "solver", .access = field<&WorldDesc::solver, &SolverSettings::max_substep_splits>()},
    {.section = "solver", .name = "newton_iterations", .type = T::Integer, .range = R{1, 50},
     .doc = "linearisations per substep (1 = Baraff–Witkin)", .label = "Newton iterations", .panel = "solver",
     .access = field<&WorldDesc::solver, &SolverSettings::newton_iterations>()},
    {.section = "solver", .name = "cg_tolerance", .type = T::Real, .range = R{1e-12, 1.0},
     .doc = "relative residual at which CG stops", .label = "CG tolerance", .panel = "solver", .log_scale = true,
     .access = field<&WorldDesc::solver, &SolverSettings::cg_tolerance>()},
    {.section = "solver", .name = "cg_max_iterations", .type = T::Integer, .range = R{1, 100000},
     .doc = "CG iteration cap per solve", .label = "CG iteration cap", .panel = "solver", .log_scale = true,
     .access = field<&WorldDesc::solver, &SolverSettings::cg_max_iterations>()},
    {.section = "solver", .name = "cg_velocity_tolerance", .type = T::Real, .unit = "m/s", .range = R{0.0, 10.0},
     .doc = "velocity error the CG's energy stopping test aims under: past the residual test, CG goes on while the "
            "incremental potential still falls by more than ½·mass·tolerance² over 4 iterations; 0 turns it off",
     .label = "CG velocity tolerance", .panel = "solver", .log_scale = true,
     .access = field<&WorldDesc::solver, &SolverSettings::cg_velocity_tolerance>()},
    {.section = "solver", .name = "cg_warm_start", .type = T::Boolean,
     .doc = "start CG from the previous substep's velocity change (fewer iterations at the same tolerance) instead of zero",
     .label = "CG warm start", .panel = "solver", .access = field<&WorldDesc::solver, &SolverSettings::cg_warm_start>()},
    {.section = "solver", .name = "precision", .type = T::Choice, .doc = "CPU backend scalar; double is the reference",
     .label = "precision", .panel = "solver", .choices = kPrecisionNames,
     .access = choice_field<kPrecisions, &WorldDesc::solver, &SolverSettings::precision>()},
    {.section = "solver", .name = "hessian", .type = T::Choice,
     .doc = "`fast`: cheap PSD approximation; `projected`: exact element Hessians clamped to PSD", .label = "Hessian",
     .panel = "solver", .choices = kHessianNames,
     .access = choice_field<kHessians, &WorldDesc::solver, &SolverSettings::hessian>()},
    {.section = "solver", .name = "bending", .type = T::Choice,
     .doc = "`hinge`: one term per interior edge (every backend; too soft by an amount that depends on the cells' "
            "shape); `shell` (the default): a shape operator per triangle, converged within 0.5% on a clamped strip at "
            "any cell shape (every backend, one GPU or several); `midedge`: the same with each edge's normal "
            "relaxed, which also converges on meshes whose rows run diagonally (cpu backend and one GPU; several "
            "GPUs refuse it)",
     .label = "bending model", .panel = "solver", .effect = E::Rebuild, .choices = kBendingNames,
     .access = choice_field<kBendings, &WorldDesc::solver, &SolverSettings::bending>()},
    {.section = "solver", .name = "preconditioner", .type = T::Choice,
     .doc = "`jacobi`: 3×3 block-Jacobi; `mas`: multilevel additive Schwarz, several times fewer CG iterations on "
            "fine or stiff cloth at a higher cost per iteration; `auto`: mas from 100K vertices on the cuda backend and "
            "from 15K on the cpu backend, else jacobi (the faster, as measured)",
     .label = "preconditioner", .panel = "solver", .choices = kPreconditionerNames,
     .access = choice_field<kPreconditioners, &WorldDesc::solver, &SolverSettings::preconditioner>()},
    {.section = "solver", .name = "preconditioner_refresh", .type = T::Integer, .range = R{1, 1000},
     .doc = "`mas` only: substeps between factorisations of the preconditioner (1: every Newton iteration; more "
            "reuses it, saving its setup at the price of some CG iterations)",
     .label = "MAS refresh", .panel = "solver", .log_scale = true,
     .access = field<&WorldDesc::solver, &SolverSettings::preconditioner_refresh>()},
    {.section = "solver", .name = "line_search", .type = T::Boolean,
     .doc = "halve a Newton update while it raises implicit Euler's objective (elastic, gravity and collider "
            "potentials): keeps stiff, light cloth from diverging over long steps; one energy evaluation per Newton "
            "iteration; cpu backend and cuda on one GPU (across GPUs it is not applied yet; a substep that searches runs outside "
            "the CUDA graph); the energy guard's redo turns it on",
     .label = "line search", .panel = "solver", .access = field<&WorldDesc::solver, &SolverSettings::line_search>()},
    {.section = "solver", .name = "energy_guard", .type = T::Choice,
     .doc = "check every substep for energy gained beyond the external work (an inexact solve): `off`; `report`: "
            "count it in the stats; `retry`: also redo the substep once with the CG tolerance / 100, the cap × 4, 4× the Newton "
            "iterations and the line search (then as four quarter substeps if it still gains), keeping the attempt that gained least",
     .label = "energy guard", .panel = "solver", .choices = kEnergyGuardNames,
     .access = choice_field<kEnergyGuards, &WorldDesc::solver, &SolverSettings::energy_guard>()},
    {.section = "solver", .name = "contact_stiffness", .type = T::Real, .unit = "N/m", .range = R{0.0, 1e12},
     .doc = "per-vertex collider contact stiffness; 0 picks one from the mass and `dt`", .label = "collider stiffness",
     .panel = "solver", .log_scale = true, .access = field<&WorldDesc::solver, &SolverSettings::contact_stiffness>()},
    {.section = "solver", .name = "face_contacts", .type = T::Boolean,
     .doc = "analytic colliders also push each cloth triangle's centroid, not only its vertices: a coarse cloth over a "
            "curved collider does not let it show through its triangles (a collider test per triangle)",
     .label = "face contacts", .panel = "solver", .effect = E::Rebuild,  // the cpu backend reads it when built
     .access = field<&WorldDesc::solver, &SolverSettings::face_contacts>()},
    {.section = "solver", .name = "threads", .type = T::Integer, .range = R{0, 1024},
     .doc = "CPU worker threads, 0 = all cores (results do not depend on it); `--threads` and "
            "`BackendOptions::threads` take precedence when non-zero",
     .effect = E::Rebuild, .access = field<&WorldDesc::solver, &SolverSettings::threads>()},
    {.section = "solver", .name = "gpus", .type = T::Integer, .range = R{1, 64},
     .doc = "GPUs one world is split across on the cuda backend (the cpu backend ignores it); `--gpus` and "
            "`BackendOptions::gpus` take precedence when non-zero",
     .effect = E::Rebuild, .access = field<&WorldDesc::solver, &SolverSettings::gpus>()},
    {.section = "solver", .name = "gpu_rebalance", .type = T::Real, .range = R{0.0, 100.0},
     .doc = "several GPUs with cloth collisions: re-cut the parts by rows and contacts when the busiest part's "
            "work (its rows' matrix blocks plus its contacts) is more than this multiple of the mean part's for 3 "
            "detections in a row (a rebuild of the parts); 0 never",
     .label = "GPU rebalance", .panel = "solver",
     .access = field<&WorldDesc::solver, &SolverSettings::gpu_rebalance>()},

    // ---- [world]
    {.section = "world", .name = "gravity", .type = T::Vector, .unit = "m/s²", .range = R{0.0, 1000.0},
     .doc = "gravitational acceleration", .label = "gravity", .panel = "world", .vector_bound = VectorBound::Length,
     .access = field<&WorldDesc::gravity>()},

    // ---- [wind]
    {.section = "wind", .name = "velocity", .type = T::Vector, .unit = "m/s", .range = R{0.0, 1000.0},
     .doc = "mean wind", .label = "wind", .panel = "world", .vector_bound = VectorBound::Length,
     .access = field<&WorldDesc::wind, &WindDesc::velocity>()},
    {.section = "wind", .name = "air_density", .type = T::Real, .unit = "kg/m³", .range = R{0.0, 100.0},
     .doc = "density of the air the drag and lift act through", .label = "air density", .panel = "world",
     .access = field<&WorldDesc::wind, &WindDesc::air_density>()},
    {.section = "wind", .name = "turbulence", .type = T::Real, .unit = "m/s", .range = R{0.0, 1000.0},
     .doc = "amplitude of the gust field added to the mean", .label = "turbulence", .panel = "world",
     .access = field<&WorldDesc::wind, &WindDesc::turbulence>()},
    {.section = "wind", .name = "turbulence_frequency", .type = T::Real, .unit = "Hz", .range = R{0.0, 1000.0},
     .doc = "how fast gusts change", .label = "gust frequency", .panel = "world",
     .access = field<&WorldDesc::wind, &WindDesc::turbulence_frequency>()},
    {.section = "wind", .name = "turbulence_scale", .type = T::Real, .unit = "m", .range = R{1e-3, 1e6},
     .doc = "spatial size of a gust", .label = "gust size", .panel = "world", .log_scale = true,
     .access = field<&WorldDesc::wind, &WindDesc::turbulence_scale>()},

    // ---- [collision]: the collision pipeline beyond the analytic colliders (docs/collisions.md)
    {.section = "collision", .name = "self", .type = T::Boolean,
     .doc = "self-contact: each cloth against itself and against the other cloths", .label = "self-collision",
     .panel = "collision", .access = field<&WorldDesc::collision, &CollisionSettings::self_collision>()},
    {.section = "collision", .name = "mode", .type = T::Choice,
     .doc = "`ccd_zones`: proximity springs, then CCD and impact zones after the solve (PSCC, P-Cloth); `offset`: "
            "offset geometric contact, a smooth penalty within the contact radius and every move truncated to the "
            "vertex's conservative bound, no CCD (docs/methods.md §7b)",
     .label = "contact mode", .panel = "collision", .choices = kCollisionModeNames,
     .access = choice_field<kCollisionModes, &WorldDesc::collision, &CollisionSettings::mode>()},
    {.section = "collision", .name = "continuous", .type = T::Boolean,
     .doc = "after the solve, continuous collision detection and impact zones leave every substep free of "
            "intersections; false: proximity forces only (faster; fast or thin motion may pass through)",
     .label = "continuous", .panel = "collision",
     .access = field<&WorldDesc::collision, &CollisionSettings::continuous>()},
    {.section = "collision", .name = "culling", .type = T::Choice,
     .doc = "`normal_cone`: pairs inside one self-collision-free patch are never generated (PSCC); `none`: every pair "
            "whose bounds overlap is tested. Meant as a speed knob, but `none` can turn near pairs inside a proven "
            "patch into impact-zone constraints (the rigged character: 68 substeps unresolved): keep `normal_cone`",
     .label = "culling", .panel = "collision", .choices = kCullingNames,
     .access = choice_field<kCullings, &WorldDesc::collision, &CollisionSettings::culling>()},
    {.section = "collision", .name = "cull_contacts", .type = T::Boolean,
     .doc = "also cull the proximity contacts' candidates (over the predicted motion), not only the CCD detections: "
            "faster, but a patch that folds during the solve then has no springs inside it and the impact zones take "
            "every crossing (`falling` at 48²: 30× more CCD hits). Offset mode (cpu): culls the bound query, "
            "certified again over each actual update",
     .label = "cull contacts", .panel = "collision",
     .access = field<&WorldDesc::collision, &CollisionSettings::cull_contacts>()},
    {.section = "collision", .name = "count_culled", .type = T::Boolean,
     .doc = "also count the pairs normal-cone culling removed (the summary's and stats' `culled_pairs`; a box test per "
            "culled pair, "
            "for benchmarks; cpu backend only)",
     .label = "count culled pairs", .panel = "collision",
     .access = field<&WorldDesc::collision, &CollisionSettings::count_culled>()},
    {.section = "collision", .name = "rest_exclusion", .type = T::Real, .unit = "thicknesses", .range = R{0.0, 10.0},
     .doc = "pairs of primitives of one cloth closer than this many contact thicknesses in the rest shape get no "
            "proximity spring (fabric neighbours, not surfaces touching); CCD and the impact zones still test them. "
            "0 keeps every pair",
     .label = "rest exclusion", .panel = "collision",
     .access = field<&WorldDesc::collision, &CollisionSettings::rest_exclusion>()},
    {.section = "collision", .name = "thickness", .type = T::Real, .unit = "m", .range = R{0.0, 0.1},
     .doc = "gap kept between cloth surfaces; 0: the larger of the two cloths' material `contact_thickness`",
     .label = "thickness", .panel = "collision", .access = field<&WorldDesc::collision, &CollisionSettings::thickness>()},
    {.section = "collision", .name = "stiffness", .type = T::Real, .unit = "N/m", .range = R{0.0, 1e9},
     .doc = "stiffness of the proximity springs; 0: 100·m/h² from the pair's effective mass m and the substep h",
     .label = "stiffness", .panel = "collision", .log_scale = true,
     .access = field<&WorldDesc::collision, &CollisionSettings::stiffness>()},
    {.section = "collision", .name = "relaxation", .type = T::Real, .range = R{0.05, 0.49},
     .doc = "offset mode: the share γ of its distance to the nearest primitive a vertex may move per update (< ½: "
            "approaching primitives keep (1 − 2γ) of their gap); smaller truncates more",
     .label = "bound relaxation", .panel = "collision",
     .access = field<&WorldDesc::collision, &CollisionSettings::relaxation>()},
    {.section = "collision", .name = "bound_shape", .type = T::Choice,
     .doc = "offset mode: `planar` limits each move only towards each nearby primitive's separating plane (keeps "
            "about 3× more of a random move); `sphere` limits its length",
     .label = "bound shape", .panel = "collision", .choices = kBoundShapeNames,
     .access = choice_field<kBoundShapes, &WorldDesc::collision, &CollisionSettings::bound_shape>()},
    {.section = "collision", .name = "max_query_radius", .type = T::Real, .unit = "contact radii", .range = R{1.0, 100.0},
     .doc = "offset mode: the largest per-vertex query radius (each covers 1.5× the vertex's predicted move over γ); "
            "larger: fewer truncations and reruns, more pairs measured",
     .label = "max query radius", .panel = "collision", .log_scale = true,
     .access = field<&WorldDesc::collision, &CollisionSettings::max_query_radius>()},
    {.section = "collision", .name = "redetect_share", .type = T::Real, .range = R{0.0, 1.0},
     .doc = "offset mode: rerun the detection, with one more Newton iteration, when more than this share of the free "
            "cloth vertices was truncated",
     .label = "redetect share", .panel = "collision",
     .access = field<&WorldDesc::collision, &CollisionSettings::redetect_share>()},
    {.section = "collision", .name = "max_redetections", .type = T::Integer, .range = R{0, 64},
     .doc = "offset mode: detection reruns allowed per substep", .label = "max redetections", .panel = "collision",
     .access = field<&WorldDesc::collision, &CollisionSettings::max_redetections>()},
    {.section = "collision", .name = "max_impact_iterations", .type = T::Integer, .range = R{1, 1000},
     .doc = "impact-zone rounds per substep before the rigid-zone fallback", .label = "impact-zone rounds",
     .panel = "collision", .log_scale = true,
     .access = field<&WorldDesc::collision, &CollisionSettings::max_impact_iterations>()},
    {.section = "collision", .name = "impact_tolerance", .type = T::Real, .unit = "thicknesses", .range = R{0.0, 0.5},
     .doc = "convergence tolerance of a zone's projection as a fraction of the thickness (larger: faster, gaps "
            "restored to ≥ (1 − it)·thickness); 0: the backend's default (cpu 0.01, cuda 0.1)",
     .label = "impact tolerance", .panel = "collision",
     .access = field<&WorldDesc::collision, &CollisionSettings::impact_tolerance>()},
    {.section = "collision", .name = "max_impact_sweeps", .type = T::Integer, .range = R{0, 100000},
     .doc = "cap on one zone's projection iterations per round (smaller: faster rounds, maybe more rounds or "
            "fallbacks); 0: the backend's default (cpu 1000, cuda 200)",
     .label = "impact sweeps", .panel = "collision", .log_scale = true,
     .access = field<&WorldDesc::collision, &CollisionSettings::max_impact_sweeps>()},
    {.section = "collision", .name = "max_impact_work", .type = T::Real, .unit = "constraint updates",
     .range = R{0.0, 1e12},
     .doc = "cap on the zone projections' work in one substep (constraint updates over all zones and rounds); "
            "once spent, the hits left go to the rigid and freezing fallbacks, so a pinch no projection can "
            "solve costs a bounded time; 0: the default, 2e7 (on the cuda backend an iteration of a zone "
            "counts as a sweep)",
     .label = "impact work cap", .panel = "collision", .log_scale = true,
     .access = field<&WorldDesc::collision, &CollisionSettings::max_impact_work>()},
    {.section = "collision", .name = "ccd_time_tolerance", .type = T::Real, .unit = "substeps", .range = R{0.0, 1e-2},
     .doc = "time tolerance of the impact zones' CCD as a fraction of the substep: hits are resolved to it (larger: "
            "faster, near misses within about eta + this × the motion may count as hits); 0: the CCD's default, "
            "1e-6 on the cpu backend (double), 1e-4 on cuda (float)",
     .label = "CCD time tolerance", .panel = "collision", .log_scale = true,
     .access = field<&WorldDesc::collision, &CollisionSettings::ccd_time_tolerance>()},
    {.section = "collision", .name = "check", .type = T::Boolean,
     .doc = "run the exact triangle–triangle intersection check after every step and report the count in the stats "
            "(costly: for tests; also `weft run --check`)",
     .label = "exact check", .panel = "collision", .access = field<&WorldDesc::collision, &CollisionSettings::check>()},

    // ---- [[motion]]: named rigid motions that pins and colliders follow
    {.section = "motion", .name = "name", .type = T::String, .doc = "how pins and colliders refer to it",
     .effect = E::Rebuild, .constraint = "non-empty, unique", .default_text = "**required**"},
    {.section = "motion", .name = "origin", .type = T::Vector, .unit = "m", .range = R{-kWorldExtent, kWorldExtent},
     .doc = "frame origin at t = 0",
     .label = "origin", .panel = "motions", .vector_bound = VectorBound::Components, .slider = R{-1e4, 1e4}, .access = field<&Motion::origin>()},
    {.section = "motion", .name = "rotation", .type = T::Vector, .unit = "degrees",
     .doc = "initial orientation, Euler angles (see *Rotations*)", .effect = E::Rebuild,
     .access = field<&SceneMotion::rotation_degrees>()},
    {.section = "motion", .name = "linear_velocity", .type = T::Vector, .unit = "m/s", .doc = "constant drift",
     .label = "velocity", .panel = "motions", .slider = R{-1e3, 1e3}, .access = field<&Motion::linear_velocity>()},
    {.section = "motion", .name = "angular_velocity", .type = T::Vector, .unit = "rad/s",
     .doc = "axis × rate, world frame, about the moving origin", .label = "angular velocity", .panel = "motions",
     .slider = R{-1e3, 1e3}, .access = field<&Motion::angular_velocity>()},
    {.section = "motion", .name = "amplitude", .type = T::Vector, .unit = "m", .doc = "sinusoidal oscillation per axis",
     .label = "amplitude", .panel = "motions", .slider = R{-1e3, 1e3}, .access = field<&Motion::amplitude>()},
    {.section = "motion", .name = "frequency", .type = T::Real, .unit = "Hz", .range = R{0.0, 1000.0},
     .doc = "oscillation frequency", .label = "frequency", .panel = "motions", .access = field<&Motion::frequency>()},
    {.section = "motion", .name = "phase", .type = T::Real, .unit = "rad", .range = R{-kHuge, kHuge},
     .doc = "oscillation phase", .label = "phase", .panel = "motions", .slider = R{-1e3, 1e3},
     .access = field<&Motion::phase>()},

    // ---- [[cloth]]
    {.section = "cloth", .name = "name", .type = T::String, .doc = "used by `--set cloth.NAME…` and in messages",
     .effect = E::Rebuild, .constraint = "non-empty, unique", .default_text = "\"cloth0\", \"cloth1\", …"},
    {.section = "cloth", .name = "mesh", .type = T::Table, .doc = "where the rest shape comes from", .effect = E::Recook,
     .constraint = "see below", .default_text = "**required**"},
    {.section = "cloth", .name = "position", .type = T::Vector, .unit = "m", .range = R{-kWorldExtent, kWorldExtent},
     .doc = "translation of the rest shape into the world", .effect = E::Rebuild, .vector_bound = VectorBound::Components,
     .access = field<&ClothPlacement::position>()},
    {.section = "cloth", .name = "rotation", .type = T::Vector, .unit = "degrees",
     .doc = "orientation of the rest shape (see *Rotations*)", .effect = E::Rebuild,
     .access = field<&ClothPlacement::rotation_degrees>()},
    {.section = "cloth", .name = "initial_velocity", .type = T::Vector, .unit = "m/s", .doc = "of every vertex at t = 0",
     .effect = E::Rebuild, .access = field<&ClothDesc::initial_velocity>()},
    {.section = "cloth", .name = "density", .type = T::Real, .unit = "kg/m²", .range = R{0.0, 100.0, true},
     .doc = "areal density: the vertex masses", .label = "density", .effect = E::Recook,
     .access = field<&FabricDesc::density>()},
    {.section = "cloth", .name = "flat_rest_bending", .type = T::Boolean,
     .doc = "true: the rest dihedral angles are 0 (a flat sheet); false: taken from the rest mesh (a garment keeps "
            "its shape)",
     .label = "flat rest bending", .effect = E::Recook, .access = field<&FabricDesc::flat_rest_bending>()},
    {.section = "cloth", .name = "material", .type = T::Table, .doc = "`[cloth.material]`: the physical constants",
     .default_text = "see below"},
    {.section = "cloth", .name = "pin", .type = T::TableArray, .doc = "`[[cloth.pin]]`: pinned vertices",
     .effect = E::Rebuild, .default_text = "none"},
    {.section = "cloth", .name = "repeat", .type = T::Table, .doc = "several copies of this cloth (stacks of sheets)",
     .effect = E::Rebuild, .constraint = "see below", .default_text = "none"},

    // ---- [[cloth]] repeat = { … }
    {.section = "cloth.repeat", .name = "count", .type = T::Integer, .range = R{1, 10000},
     .doc = "number of copies (1: a single cloth named `NAME0`)", .effect = E::Rebuild, .default_text = "**required**",
     .access = field<&ClothPlacement::repeat_count>()},
    {.section = "cloth.repeat", .name = "offset", .type = T::Vector, .unit = "m", .doc = "translation added per copy",
     .effect = E::Rebuild, .access = field<&ClothPlacement::repeat_offset>()},
    {.section = "cloth.repeat", .name = "rotation_step", .type = T::Vector, .unit = "degrees",
     .doc = "added to `rotation` per copy (see *Rotations*)", .effect = E::Rebuild,
     .access = field<&ClothPlacement::repeat_rotation_step>()},

    // ---- [[cloth]] mesh = { … }: exactly one of grid and file
    {.section = "cloth.mesh", .name = "grid", .type = T::Table, .doc = "a procedural rectangle (below)",
     .effect = E::Recook, .constraint = "see below", .default_text = "none"},
    {.section = "cloth.mesh", .name = "file", .type = T::String, .doc = "a mesh file, path relative to the scene file",
     .effect = E::Recook, .constraint = "an existing file", .default_text = "none"},
    {.section = "cloth.mesh", .name = "scale", .type = T::Real, .range = R{0.0, 1e6, true},
     .doc = "multiplies the file's coordinates (e.g. 0.01 for centimetres); mesh files only", .label = "scale",
     .effect = E::Recook, .access = field<&ClothSource::scale>()},

    // ---- [[cloth]] mesh = { grid = { … } }
    {.section = "cloth.mesh.grid", .name = "width", .type = T::Real, .unit = "m", .range = R{0.0, 1000.0, true},
     .doc = "extent along x", .effect = E::Recook, .access = field<&ClothSource::width>()},
    {.section = "cloth.mesh.grid", .name = "height", .type = T::Real, .unit = "m", .range = R{0.0, 1000.0, true},
     .doc = "extent along y (`\"xy\"`) or z (`\"xz\"`)", .effect = E::Recook, .access = field<&ClothSource::height>()},
    {.section = "cloth.mesh.grid", .name = "cells", .type = T::CellCounts, .range = R{1, 4096},
     .doc = "resolution; (nx+1)·(ny+1) vertices", .label = "cells", .effect = E::Recook, .access = grid_cells()},
    {.section = "cloth.mesh.grid", .name = "plane", .type = T::Choice,
     .doc = "`xy`: vertical sheet facing +z (flag, curtain); `xz`: horizontal sheet facing +y (table cloth)",
     .effect = E::Recook, .choices = kPlaneNames, .access = choice_field<kPlanes, &ClothSource::plane>()},

    // ---- [cloth.material]: every field of weft::Material
    {.section = "cloth.material", .name = "stretch_stiffness", .type = T::Real, .unit = "N/m", .range = R{1.0, 1e8},
     .doc = "Young's modulus × thickness", .label = "stretch stiffness", .panel = "materials", .log_scale = true,
     .access = field<&Material::stretch_stiffness>()},
    {.section = "cloth.material", .name = "poisson_ratio", .type = T::Real, .range = R{0.0, 0.49},
     .doc = "lateral contraction under stretch", .label = "Poisson ratio", .panel = "materials",
     .access = field<&Material::poisson_ratio>()},
    {.section = "cloth.material", .name = "bending_stiffness", .type = T::Real, .unit = "N·m", .range = R{0.0, 1.0},
     .doc = "the plate bending stiffness D", .label = "bending stiffness", .panel = "materials", .log_scale = true,
     .access = field<&Material::bending_stiffness>()},
    {.section = "cloth.material", .name = "damping_mass", .type = T::Real, .unit = "1/s", .range = R{0.0, 100.0},
     .doc = "Rayleigh α: f = −α·M·v", .label = "damping (mass)", .panel = "materials",
     .access = field<&Material::damping_mass>()},
    {.section = "cloth.material", .name = "damping_stiffness", .type = T::Real, .unit = "s", .range = R{0.0, 1.0},
     .doc = "Rayleigh β: f = −β·K·v", .label = "damping (stiffness)", .panel = "materials", .log_scale = true,
     .access = field<&Material::damping_stiffness>()},
    {.section = "cloth.material", .name = "drag_coefficient", .type = T::Real, .range = R{0.0, 10.0},
     .doc = "aerodynamic drag normal to the surface", .label = "drag coefficient", .panel = "materials",
     .access = field<&Material::drag_coefficient>()},
    {.section = "cloth.material", .name = "lift_coefficient", .type = T::Real, .range = R{0.0, 10.0},
     .doc = "aerodynamic lift", .label = "lift coefficient", .panel = "materials",
     .access = field<&Material::lift_coefficient>()},
    {.section = "cloth.material", .name = "contact_thickness", .type = T::Real, .unit = "m", .range = R{1e-5, 0.1},
     .doc = "distance kept from colliders", .label = "contact thickness", .panel = "materials", .log_scale = true,
     .access = field<&Material::contact_thickness>()},
    {.section = "cloth.material", .name = "friction", .type = T::Real, .range = R{0.0, 10.0},
     .doc = "Coulomb coefficient against colliders", .label = "friction", .panel = "materials",
     .access = field<&Material::friction>()},

    // ---- [[cloth.pin]]: exactly one selection per entry
    {.section = "cloth.pin", .name = "vertices", .type = T::IndexList,
     .doc = "vertex indices of the rest mesh (for grids: j·(nx+1)+i)", .effect = E::Rebuild, .constraint = "non-empty"},
    {.section = "cloth.pin", .name = "box", .type = T::Box,
     .doc = "every vertex inside the box (m), bounds included", .effect = E::Rebuild, .constraint = "min ≤ max"},
    {.section = "cloth.pin", .name = "edge", .type = T::Choice, .doc = "grids only: a whole edge", .effect = E::Rebuild,
     .choices = kEdgeNames},
    {.section = "cloth.pin", .name = "corners", .type = T::Choice,
     .doc = "grids only: the two corners of that edge, or all four", .effect = E::Rebuild, .choices = kCornerNames},
    {.section = "cloth.pin", .name = "motion", .type = T::String,
     .doc = "a `[[motion]]` the pins follow; without it they stay where they start", .effect = E::Rebuild,
     .constraint = "a `[[motion]]` name", .default_text = "none"},
    {.section = "cloth.pin", .name = "follow", .type = T::String,
     .doc = "a mesh collider (a character's skin) the pins follow: each selected vertex keeps its offset from the "
            "collider vertex nearest to it at t = 0 (not with `motion`)",
     .effect = E::Rebuild, .constraint = "a mesh `[[collider]]` name", .default_text = "none"},
    {.section = "cloth.pin", .name = "joint", .type = T::String,
     .doc = "with `follow`: a joint (bone) of the character's skeleton the pins follow rigidly, keeping their place in "
            "its frame from t = 0, so they turn with it (instead of the nearest skin vertex)",
     .effect = E::Rebuild, .constraint = "a joint name of the followed character", .default_text = "none"},

    // ---- [[collider]]
    {.section = "collider", .name = "name", .type = T::String, .doc = "used by `--set collider.NAME…` and in messages",
     .effect = E::Rebuild, .constraint = "non-empty, unique", .default_text = "\"collider0\", …"},
    {.section = "collider", .name = "shape", .type = T::Choice, .doc = "analytic shape or triangle mesh",
     .effect = E::Rebuild, .choices = kShapeNames, .default_text = "**required**"},
    {.section = "collider", .name = "radius", .type = T::Real, .unit = "m", .range = R{1e-6, 1e6},
     .doc = "of the sphere, or of the capsule around its axis", .label = "radius", .panel = "colliders",
     .log_scale = true, .shapes = kRound, .access = field<&ColliderDesc::radius>()},
    {.section = "collider", .name = "half_height", .type = T::Real, .unit = "m", .range = R{0.0, 1e6},
     .doc = "half the length of the axis segment (local y)", .label = "half height", .panel = "colliders",
     .log_scale = true, .shapes = kCapsule, .access = field<&ColliderDesc::half_height>()},
    {.section = "collider", .name = "half_extents", .type = T::Vector, .unit = "m", .range = R{1e-6, 1e6},
     .doc = "half sizes along local x, y, z", .label = "half extent", .panel = "colliders", .log_scale = true,
     .vector_bound = VectorBound::Components, .shapes = kBox, .access = field<&ColliderDesc::half_extents>()},
    {.section = "collider", .name = "file", .type = T::String, .doc = "triangle mesh, path relative to the scene file",
     .effect = E::Rebuild, .constraint = "an existing file", .default_text = "**required**", .shapes = kMesh},
    {.section = "collider", .name = "scale", .type = T::Real, .range = R{0.0, 1e6, true},
     .doc = "multiplies the file's coordinates", .effect = E::Rebuild, .shapes = kMesh,
     .access = field<&ColliderMeshSource::scale>()},
    {.section = "collider", .name = "clip", .type = T::String,
     .doc = "play this animation clip of the file: the file is then read as a skinned character (glTF 2.0 or FBX: "
            "skeleton, skin weights, clips; `tools/make_character.py` writes `assets/characters/runner.gltf`)",
     .effect = E::Rebuild, .constraint = "a clip the file holds", .default_text = "none: a rigid mesh", .shapes = kMesh},
    {.section = "collider", .name = "clip_speed", .type = T::Real, .range = R{0.0, 100.0},
     .doc = "clip seconds per simulated second", .label = "clip speed", .panel = "colliders", .shapes = kMesh,
     .access = field<&ColliderDesc::clip_speed>()},
    {.section = "collider", .name = "clip_loop", .type = T::Boolean, .doc = "wrap the clip; false: hold its last key",
     .label = "loop clip", .panel = "colliders", .shapes = kMesh, .access = field<&ColliderDesc::clip_loop>()},
    {.section = "collider", .name = "clip_start", .type = T::Real, .unit = "s", .range = R{-1e6, 1e6},
     .doc = "simulated time the clip starts at (its first pose before; negative: already playing at 0)", .label = "clip start", .panel = "colliders",
     .shapes = kMesh, .access = field<&ColliderDesc::clip_start>()},
    {.section = "collider", .name = "friction", .type = T::Real, .range = R{0.0, 10.0},
     .doc = "Coulomb coefficient; omitted: each cloth's material friction", .label = "friction", .panel = "colliders",
     .slider = R{-1.0, 10.0}, .default_text = "the cloth's", .unset_when_negative = true,
     .access = field<&ColliderDesc::friction>()},
    {.section = "collider", .name = "position", .type = T::Vector, .unit = "m", .range = R{-kWorldExtent, kWorldExtent},
     .doc = "centre (sphere, capsule, box), a point on the plane, the mesh's origin", .label = "position",
     .panel = "colliders", .vector_bound = VectorBound::Components, .slider = R{-1e4, 1e4}, .access = field<&ColliderDesc::motion, &Motion::origin>()},
    {.section = "collider", .name = "rotation", .type = T::Vector, .unit = "degrees", .range = R{-360.0, 360.0},
     .doc = "orientation of the local frame (see *Rotations*)", .label = "rotation", .panel = "colliders",
     .vector_bound = VectorBound::Components, .default_text = "[0, 0, 0]", .access = collider_rotation()},
    {.section = "collider", .name = "motion", .type = T::String,
     .doc = "follow this motion instead of `position` and `rotation`", .effect = E::Rebuild,
     .constraint = "a `[[motion]]` name", .default_text = "none"},

    // ---- [camera]
    {.section = "camera", .name = "position", .type = T::Vector, .unit = "m", .doc = "eye", .effect = E::Rebuild,
     .access = field<&CameraDesc::position>()},
    {.section = "camera", .name = "target", .type = T::Vector, .unit = "m", .doc = "point looked at",
     .effect = E::Rebuild, .constraint = "≠ position", .access = field<&CameraDesc::target>()},
    {.section = "camera", .name = "fov", .type = T::Real, .unit = "degrees", .range = R{0.0, 180.0, true, true},
     .doc = "vertical field of view", .effect = E::Rebuild, .access = field<&CameraDesc::fov_degrees>()},
};
// clang-format on

// A default-constructed owner of `p`, handed to `f`.
template <class F>
auto with_default_owner(const Parameter& p, F&& f) {
    switch (p.access.owner) {
        case ParameterOwner::World: return f(WorldDesc{});
        case ParameterOwner::Material: return f(Material{});
        case ParameterOwner::Fabric: return f(FabricDesc{});
        case ParameterOwner::Cloth: return f(ClothDesc{});
        case ParameterOwner::ClothSource: return f(ClothSource{});
        case ParameterOwner::ClothPlacement: return f(ClothPlacement{});
        case ParameterOwner::Motion: return f(Motion{});
        case ParameterOwner::SceneMotion: return f(SceneMotion{});
        case ParameterOwner::Collider: return f(ColliderDesc{});
        case ParameterOwner::ColliderMesh: return f(ColliderMeshSource{});
        case ParameterOwner::Camera: return f(CameraDesc{});
        case ParameterOwner::Scene: return f(SceneDesc{});
        case ParameterOwner::None: break;
    }
    throw Error("parameter '" + p.key() + "' has no field, hence no default value");
}

std::string vector_text(const Vec3d& v, int components) {
    std::string s = "[";
    for (int k = 0; k < components; ++k) {
        if (k > 0) s += ", ";
        s += scene_toml::format_number(v[k]);
    }
    return s + "]";
}

std::string quoted_list(std::span<const std::string_view> names) {
    std::string s;
    for (const std::string_view n : names) s.append(s.empty() ? "\"" : ", \"").append(n).append("\"");
    return s;
}

template <class Owner>
void check_ranges(const Owner& owner, std::string_view where, std::optional<ColliderShape> shape = std::nullopt) {
    for (const Parameter& p : kTable) {
        if (!holds<Owner>(p) || (shape && !p.applies_to(*shape))) continue;
        const std::string place = where.empty() ? std::string(p.section) : std::string(where);
        if (p.type == ParameterType::Real || p.type == ParameterType::Integer) {
            const double v = parameter_number(p, owner);
            if (p.unset_when_negative && v < 0.0) continue;
            check_parameter_range(p, v, place);
        } else if (p.type == ParameterType::Choice && p.access.number != nullptr) {
            // A value cast from an integer through the API that names no choice (the scene reader
            // only ever stores a listed one).
            const double v = parameter_number(p, owner);
            if (v < 0.0) {
                std::string names;
                for (const std::string_view c : p.choices) names += std::string(names.empty() ? "\"" : ", \"") + std::string(c) + "\"";
                throw Error(place + ": " + std::string(p.name) + " holds a value that is none of " + names);
            }
        } else if (p.type == ParameterType::Vector) {
            const Vec3d v = parameter_vector(p, owner);
            const std::string shown = place + ": " + std::string(p.name) + " = " + vector_text(v, 3);
            if (!math::is_finite(v)) throw Error(shown + " is not finite");
            if (p.vector_bound == VectorBound::Length && !p.range.contains(math::length(v)))
                throw Error(shown + " has a magnitude outside " + p.range.text());
            if (p.vector_bound == VectorBound::Components)
                for (int k = 0; k < 3; ++k)
                    if (!p.range.contains(v[k])) throw Error(shown + " has a component outside " + p.range.text());
        }
    }
}

}  // namespace

std::string ParameterRange::text() const {
    return std::string(lo_open ? "(" : "[") + scene_toml::format_number(lo) + ", " + scene_toml::format_number(hi) +
           (hi_open ? ")" : "]");
}

std::string ParameterRange::integer_text() const {
    return std::string(lo_open ? "(" : "[") + std::to_string(std::llround(lo)) + ", " + std::to_string(std::llround(hi)) +
           (hi_open ? ")" : "]");
}

std::string Parameter::key() const { return std::string(section) + "." + std::string(name); }

bool Parameter::applies_to(ColliderShape shape) const { return shapes == 0 || (shapes & shape_bit(shape)) != 0; }

std::span<const Parameter> parameter_table() { return kTable; }

const Parameter* find_parameter(std::string_view key) {
    for (const Parameter& p : kTable)
        if (key.size() == p.section.size() + 1 + p.name.size() && key.starts_with(p.section) &&
            key[p.section.size()] == '.' && key.ends_with(p.name))
            return &p;
    return nullptr;
}

const Parameter& parameter(std::string_view section, std::string_view name) {
    for (const Parameter& p : kTable)
        if (p.section == section && p.name == name) return p;
    throw Error("no parameter '" + std::string(name) + "' in section '" + std::string(section) + "' of the parameter table");
}

namespace detail {
void wrong_owner(const Parameter& p, std::string_view wanted) {
    throw Error("parameter '" + p.key() + "' is not " + std::string(wanted) + " of this struct");
}
}  // namespace detail

double parameter_default_number(const Parameter& p) {
    return with_default_owner(p, [&](const auto& owner) { return p.access.number(&owner); });
}

Vec3d parameter_default_vector(const Parameter& p) {
    return with_default_owner(p, [&](const auto& owner) { return p.access.vector(&owner); });
}

std::string parameter_default_text(const Parameter& p) {
    if (!p.default_text.empty()) return std::string(p.default_text);
    if (p.access.owner == ParameterOwner::None) return {};
    switch (p.type) {
        case ParameterType::Real: return scene_toml::format_number(parameter_default_number(p));
        case ParameterType::Integer: return std::to_string(std::llround(parameter_default_number(p)));
        case ParameterType::Boolean: return parameter_default_number(p) != 0.0 ? "true" : "false";
        case ParameterType::Choice: {
            const auto i = static_cast<std::size_t>(std::llround(parameter_default_number(p)));
            if (i >= p.choices.size()) return {};
            // Appended piecewise: GCC 12 warns (-Wrestrict, a false positive) on "literal" + string chains.
            std::string quoted(1, '"');
            quoted.append(p.choices[i]).push_back('"');
            return quoted;
        }
        case ParameterType::Vector: return vector_text(parameter_default_vector(p), 3);
        case ParameterType::CellCounts: return vector_text(parameter_default_vector(p), 2);
        default: return {};
    }
}

std::string parameter_range_text(const Parameter& p) {
    if (!p.constraint.empty()) return std::string(p.constraint);
    switch (p.type) {
        case ParameterType::Real: return p.range.text();
        case ParameterType::Integer: return p.range.integer_text();
        case ParameterType::Choice: return quoted_list(p.choices);
        case ParameterType::Vector:
            switch (p.vector_bound) {
                case VectorBound::Finite: return "finite";
                case VectorBound::Length: return "magnitude ≤ " + scene_toml::format_number(p.range.hi);
                case VectorBound::Components: return "each in " + p.range.text();
            }
            return {};
        case ParameterType::CellCounts: return "integers in " + p.range.integer_text();
        default: return {};
    }
}

void check_parameter_range(const Parameter& p, double value, std::string_view where) {
    if (p.range.contains(value)) return;
    const bool integer = p.type == ParameterType::Integer;
    const std::string shown = integer && std::isfinite(value) ? std::to_string(std::llround(value))
                                                               : scene_toml::format_number(value);
    throw Error(std::string(where) + ": " + std::string(p.name) + " = " + shown + " is outside " +
                (integer ? p.range.integer_text() : p.range.text()));
}

void check_parameter_ranges(const WorldDesc& owner, std::string_view where) { check_ranges(owner, where); }
void check_parameter_ranges(const Material& owner, std::string_view where) { check_ranges(owner, where); }
void check_parameter_ranges(const Motion& owner, std::string_view where) { check_ranges(owner, where); }
void check_parameter_ranges(const ColliderDesc& owner, std::string_view where) {
    check_ranges(owner, where, owner.shape);
}

}  // namespace weft
