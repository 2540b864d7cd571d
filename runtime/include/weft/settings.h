#pragma once
/// @file
/// World-wide settings: gravity, wind and the solver's speed/accuracy knobs. The valid range of each
/// field, its scene key and its editor label are in the parameter table (weft/parameters.h; `weft
/// help scene-keys`); `World` refuses values outside it.

#include <cstddef>
#include <cstdint>

#include "weft/types.h"

namespace weft {

/// Wind acting on every cloth through per-triangle aerodynamic drag and lift.
struct WindDesc {
    Vec3d velocity{};             ///< m/s, mean wind
    double air_density = 1.2;     ///< kg/m³
    double turbulence = 0.0;      ///< m/s, amplitude of the gust field added to the mean
    double turbulence_frequency = 1.0;  ///< Hz, how fast gusts change
    double turbulence_scale = 1.0;      ///< m, spatial size of a gust
    [[nodiscard]] bool active() const {
        return velocity.x != 0.0 || velocity.y != 0.0 || velocity.z != 0.0 || turbulence > 0.0;
    }
};

/// Which Hessian approximation the elements hand to the solver (a speed/accuracy knob).
enum class HessianMode : std::uint8_t {
    /// Cheap PSD form: membrane with compressive stress dropped from the geometric term, bending
    /// by Gauss–Newton (∇θ ∇θᵀ). Exact at rest and in tension.
    Fast,
    /// Exact element Hessian, eigen-clamped to the nearest PSD matrix (9×9 membrane, 12×12 bending).
    Projected,
};

/// The discrete bending energy (an accuracy knob; docs/methods.md, docs/results.md "Bending
/// convergence").
enum class BendingModel : std::uint8_t {
    /// One term per interior edge, ½·D·w·(θ − θ̄)² (Grinspun et al. 2003): a four-vertex stencil,
    /// on every backend. Too soft by 13–70% on a clamped strip, by an amount that depends on the
    /// cells' shape and does not shrink with refinement on square cells.
    Hinge,
    /// The default. A shape operator per triangle from its three edges' angles and the plate energy
    /// ½·D·A·|S − S̄|² (weft/physics/shell_bending.h): within 0.5% of the heavy elastica from 12
    /// cells along a clamped strip, whatever the cells' shape. Every backend, one GPU or several, at
    /// about the hinge model's cost. About 1.5× too stiff for a bend across a grid's diagonal.
    Shell,
    /// The shell model with each edge's normal free to turn about the edge, relaxed to minimise the
    /// energy (weft/physics/midedge_bending.h): a cylinder costs the plate energy bent about any
    /// direction of the mesh (the shell and hinge models charge 1.49× about a grid's diagonal), so a
    /// strip meshed with its rows at 45° converges too. A small solve per Newton iteration over the
    /// edges. CPU backend and one GPU.
    MidEdge,
};

/// The preconditioner of the CG solve (a speed knob: both reach the same answer at the tolerance).
enum class Preconditioner : std::uint8_t {
    /// Block-Jacobi: the inverse of each vertex's 3×3 diagonal block. Cheapest per iteration; the
    /// iteration count grows with resolution and stiffness.
    Jacobi,
    /// Multilevel additive Schwarz (Wu, Wang & Wang 2022; docs/methods.md §2b): dense solves on
    /// domains of 16 vertices at several levels of aggregation. Costlier per iteration, far fewer
    /// iterations on fine or stiff cloth.
    Schwarz,
    /// Whichever measured faster for the backend and size (docs/tuning.md, `preconditioner`): the
    /// Schwarz preconditioner from kAutoSchwarzMinVertices vertices on the cuda backend and from
    /// kAutoSchwarzMinVerticesCpu on the CPU backend, block-Jacobi below.
    Auto,
};

/// Where `Preconditioner::Auto` switches to the Schwarz preconditioner on a GPU: measured on an
/// H100 (docs/results.md, issue 18), Jacobi is faster on the flag up to 80K triangles (40K vertices)
/// and the Schwarz preconditioner from 320K (160K vertices); at 200K (the sphere, 100K vertices) they
/// solve in about the same time, Jacobi with 142 of 240 solves capped and Schwarz with none.
inline constexpr std::size_t kAutoSchwarzMinVertices = 100000;
/// The same on the CPU backend (2-core development machine, double): Jacobi and Schwarz run the
/// flag at the same speed at 4.6K vertices (14.3 and 14.0 frames/s), Schwarz is ahead at 15.6K
/// (3.64 against 3.54) and 1.2× faster at 40K vertices.
inline constexpr std::size_t kAutoSchwarzMinVerticesCpu = 15000;

/// What the world does about a substep whose energy grew beyond what the outside world can have put
/// in (an inexact CG solve; docs/methods.md §1b, docs/tuning.md).
enum class EnergyGuard : std::uint8_t {
    /// No check: nothing is measured.
    Off,
    /// Measure the energy before and after every substep and count a gain in
    /// `StepStats::energy_gained` (the state is kept as solved).
    Report,
    /// As Report, and redo a substep that gained energy once from its start with the CG tolerance
    /// divided by 100 (the velocity tolerance by 10), the iteration cap multiplied by 4 and four times the Newton iterations (at most
    /// 50); if that still gains, once more as four quarter substeps; keeps the attempt that gained
    /// least.
    Retry,
};

/// SolverSettings::split_stretch: substeps without a split after which the halvings every substep
/// starts with come down by one (half a second at 60 Hz).
inline constexpr int kSplitRelaxSubsteps = 30;

/// Solver knobs. Every one trades speed against accuracy; docs/tuning.md measures them.
struct SolverSettings {
    double dt = 1.0 / 60.0;        ///< frame time step, s.
    int substeps = 1;              ///< implicit steps per frame.
    int newton_iterations = 1;     ///< linearisations per substep (1 = Baraff–Witkin).
    double cg_tolerance = 1e-4;    ///< relative residual: stop when rᵀP⁻¹r ≤ ε²·δ₀.
    int cg_max_iterations = 500;   ///< CG cap per solve.
    /// Velocity error, m/s, that the CG's second stopping test aims under (0, the default, turns it
    /// off): past the residual test a solve goes on, up to the cap, while the incremental potential
    /// fell by more than ½·m·ε² over its last 4 iterations (m the cloths' mass): its estimate of the
    /// energy-norm error left (weft/backend/cg_energy_stop.h). It costs only where the residual test
    /// stopped on a plateau, the solves that now and then gain energy; 5e-4 removed the flag's gains
    /// for 2% more iterations (docs/tuning.md).
    double cg_velocity_tolerance = 0.0;
    /// Start each substep's first CG solve from the previous substep's velocity change instead of
    /// zero. Accelerations change smoothly from one substep to the next, so CG starts closer to the
    /// answer and stops sooner at the same tolerance (docs/results.md measures by how much).
    bool cg_warm_start = true;
    Precision precision = Precision::Double;  ///< CPU backend scalar; double is the reference
    HessianMode hessian = HessianMode::Fast;
    BendingModel bending = BendingModel::Shell;
    Preconditioner preconditioner = Preconditioner::Auto;
    /// Schwarz preconditioner only: substeps between its factorisations. 1 refactors in every Newton
    /// iteration; k > 1 only in the first Newton iteration of every k-th substep, the others reusing
    /// the last factors (a stale preconditioner is still a valid one: only the iteration count moves).
    int preconditioner_refresh = 1;
    /// A substep that leaves a cloth triangle stretched beyond this principal stretch (1 at rest), and
    /// further than at its start, is redone from its start as two halves, each of which may be split
    /// again, down to 2^max_substep_splits pieces; 0 turns it off. Why: a long step lets a fast
    /// kinematic body carry light cloth through the solve, and the collision stages then push it back
    /// in front of the body, where it stays held while the cloth behind it stretches open (a banner
    /// a runner passes through: docs/methods.md §1c). Shorter pieces only where that happens cost
    /// nothing elsewhere; the attempt that stretched least is kept. Each substep's start state is
    /// kept for the redo (a host read of the state per substep on a device backend).
    double split_stretch = 0.0;
    /// Halvings of a substep that `split_stretch` may ask for (a substep becomes at most 2^this pieces).
    /// The pieces a drag needs grow with the cloth's resolution against the body's speed: the
    /// cape_runner's banner at its coarsest tore with 1 and held with 2, at detail 3 (3.5 cm cells,
    /// 5 m/s) it tore with 2 and held with 3 (docs/results.md).
    int max_substep_splits = 3;
    /// Energy check after every substep (a cost of two host reads of the state per substep on a device
    /// backend; docs/tuning.md measures it on the CPU).
    EnergyGuard energy_guard = EnergyGuard::Report;
    /// A backtracking line search on every Newton update (CPU backend, and CUDA on one GPU; across GPUs not applied yet):
    /// the update is halved, up to 8 times, while it raises implicit Euler's
    /// objective ½‖v − v₀‖²_M + Ψ(x₀ + h·v) (elastic, gravity and collider potentials). Costs one
    /// energy evaluation per Newton iteration, and more where it backtracks; it keeps plain Newton
    /// from diverging on stiff, light cloth over long steps. The energy guard's redo turns it on.
    bool line_search = false;
    double contact_stiffness = 0.0;  ///< N/m per vertex against colliders; 0 picks a stiffness from mass and dt
    /// The analytic colliders also push each cloth triangle's centroid, not only its vertices: a
    /// coarse cloth over a curved collider no longer lets it show through the middle of its
    /// triangles (weft/physics/implicit_terms.h, face_collider_terms). Costs a collider test per
    /// triangle. cpu backend only so far.
    bool face_contacts = false;
    int threads = 0;               ///< CPU worker threads; 0 = all cores. Results do not depend on it.
    /// GPUs one world is split across on the cuda backend (docs/multi-gpu.md); `--gpus` and
    /// BackendOptions::gpus take precedence when non-zero. The CPU backend ignores it.
    int gpus = 1;
    /// Several GPUs with cloth collisions: re-cut the parts by rows and contacts when the busiest
    /// part's work (its rows' matrix blocks plus its contacts, weft/backend/vertex_partition.h
    /// part_work_imbalance) is more than this multiple of the mean part's for a few detections in a
    /// row (weft/backend/recut_policy.h; docs/multi-gpu.md, "Re-cutting by contact load"). A re-cut
    /// rebuilds the parts. 0 never re-cuts.
    double gpu_rebalance = 1.1;
};

/// How the broad phase prunes pairs within one cloth. Meant as a speed knob, but `None` can make the
/// CCD's near pairs inside a patch into impact-zone constraints (docs/results.md: the rigged character
/// left 68 substeps unresolved without culling, none with it).
enum class CollisionCulling : std::uint8_t {
    None,        ///< every pair whose bounds overlap is tested
    NormalCone,  ///< pairs inside one self-collision-free patch are never generated (PSCC; docs/collisions.md)
};

/// Cloth collisions beyond the analytic colliders (docs/collisions.md): self-contact, cloth against
/// cloth and cloth against triangle-mesh colliders. Analytic colliders (plane, sphere, capsule, box)
/// are always handled by penalty contacts in the solve; mesh colliders always go through this
/// pipeline. Only the stages a scene needs are built: with `self_collision` off and no mesh collider
/// nothing here runs.
/// How cloth is kept from passing through cloth (docs/collisions.md).
enum class CollisionMode : std::uint8_t {
    /// Proximity springs in the solve, then continuous collision detection and impact zones after it
    /// (the PSCC / P-Cloth pipeline; docs/methods.md §6–7).
    CcdZones,
    /// Offset geometric contact: a smooth penalty inside the contact radius in the solve, and every
    /// vertex's move truncated to its conservative bound (docs/methods.md §7b). No CCD; the impact
    /// zones only as the fallback for a substep whose prescribed motion breaks a bound.
    Offset,
};

/// The shape of the per-vertex bound the offset mode truncates moves to (docs/methods.md §7b).
enum class BoundShape : std::uint8_t {
    Sphere,  ///< |move| ≤ γ·min(r_v, d_v)
    Planar,  ///< at most γ·d towards each partner's separating plane (and γ·r_v in all): keeps more of each move
};

struct CollisionSettings {
    /// Cloth against itself and against the other cloths.
    bool self_collision = false;
    /// After the solve, continuous collision detection and impact zones make every substep free of
    /// intersections. Off: proximity forces only (faster; fast or thin motion may pass through).
    bool continuous = true;
    CollisionCulling culling = CollisionCulling::NormalCone;
    /// Also cull the proximity contacts' candidates (the broad phase over the predicted motion x + h·v),
    /// not only the CCD and impact-zone detections over the solved motion. Faster, but a patch proven
    /// free over the *predicted* motion gets no contacts inside it, and when the solved motion folds
    /// it the crossings all go to the impact zones: `falling` at 48² on the CPU took 30× more CCD
    /// hits and never finished (docs/results.md). Off by default.
    bool cull_contacts = false;
    /// Proximity pairs inside one cloth whose primitives lie closer than this many contact thicknesses
    /// in the cloth's rest shape (its initial placement) get no spring: they are neighbours in the
    /// fabric, not surfaces touching, and a spring would push them apart against the membrane (on
    /// a sheet whose edges are shorter than the thickness, every vertex would have several). CCD and
    /// the impact zones still test them. 0 keeps every pair.
    double rest_exclusion = 1.0;
    /// Also count the pairs culling removed (`CollisionStats::culled_pairs`), which costs a box test
    /// per culled pair (about 4× the culled broad phase on a twisted sheet): for benchmarks.
    bool count_culled = false;
    /// Gap kept between cloth surfaces, m. 0: the larger of the two cloths' material contact_thickness.
    double thickness = 0.0;
    /// Stiffness of the proximity springs, N/m. 0: 100·m/h² from the pair's effective mass m and the
    /// substep h (the rule the analytic colliders use).
    double stiffness = 0.0;
    /// Impact-zone rounds per substep before the rigid-zone fallback takes over.
    int max_impact_iterations = 32;
    /// Convergence tolerance of one impact zone's projection, as a fraction of the thickness: the
    /// zone's constraints end violated by at most this (the gap restored is ≥ (1 − it)·thickness,
    /// far above the CCD separation of 0.1·thickness either way). Larger is faster. 0: the backend's
    /// default (cpu 0.01, the reference; cuda 0.1, measured on the 200K twist in docs/results.md).
    double impact_tolerance = 0.0;
    /// Cap on the iterations of one zone's projection in one round (cpu: Gauss–Seidel sweeps; cuda:
    /// parallel projected-gradient steps); an unconverged zone is detected again next round. Smaller
    /// is faster per round but may need more rounds or the fallbacks. 0: the backend's default (cpu
    /// 1000, cuda 200).
    int max_impact_sweeps = 0;
    /// Cap on the work of all zone projections in one substep, in constraint updates (a sweep of a
    /// zone updates each of its constraints once), summed over zones and rounds. Once spent, the
    /// rounds stop and the hits left go to the fallbacks (rigid zones, then freezing), which always
    /// end: a pinch no projection can solve (cloth pressed between two colliders, or into a
    /// collider's own overlapping parts) costs a bounded time instead of seconds. Smaller bounds the
    /// worst substep tighter and falls back sooner. 0: the default, 2·10⁷ (about 0.2 s on one core
    /// of the development machine). Both backends (on cuda an iteration of a zone's projection
    /// counts as a sweep).
    double max_impact_work = 0.0;
    /// Time tolerance of the impact zones' CCD, as a fraction of the substep: a hit's time of impact
    /// is resolved to within it (always a lower bound of the first contact), and a near miss within
    /// about eta + this × the pair's motion may be taken for a hit. Larger is faster: a hit is
    /// bisected to the tolerance, and on `layers` hits are 2% of the CCD queries and half the CCD
    /// time (1e-4 takes a quarter off the stage for 0.7% more hits, each within 4% of eta:
    /// docs/results.md). 0: the CCD's default, 1e-6. Both backends (the cuda backend's float CCD at 0: 1e-4).
    double ccd_time_tolerance = 0.0;
    /// Contact pipeline: CCD with impact zones, or offset contact with displacement bounds.
    CollisionMode mode = CollisionMode::CcdZones;
    /// Offset mode: γ, the share of its distance to the nearest primitive a vertex may move per update
    /// (below ½, so two approaching primitives keep a gap of at least (1 − 2γ) of their distance).
    double relaxation = 0.45;
    /// Offset mode: sphere or planar bounds.
    BoundShape bound_shape = BoundShape::Planar;
    /// Offset mode: the largest per-vertex query radius, in contact radii. A vertex's radius covers
    /// 1.5× its predicted move (relative to the cloth's mean motion) over γ, from one contact radius up
    /// to this; a vertex moving faster is truncated and the detection rerun. Larger: fewer reruns,
    /// more pairs measured.
    double max_query_radius = 4.0;
    /// Offset mode: rerun the detection (and one more Newton iteration) when more than this share of
    /// the free cloth vertices was truncated. 0.05 measured faster than 0.01 on the 200K twist from
    /// 1 s on (53–135 against 89–186 ms per step, H100; docs/results.md); with no reruns at all the
    /// pins break their bounds and the CCD fallback takes over.
    double redetect_share = 0.05;
    /// Offset mode: reruns allowed per substep.
    int max_redetections = 2;
    /// Run the exact triangle–triangle intersection check after every step and report the count in
    /// `StepStats::collision.remaining_intersections` (also `weft run --check`). Costly: for tests.
    bool check = false;
};

/// Everything that applies to the whole world.
struct WorldDesc {
    Vec3d gravity{0.0, -9.81, 0.0};  ///< m/s²
    WindDesc wind{};
    SolverSettings solver{};
    CollisionSettings collision{};
};

}  // namespace weft
