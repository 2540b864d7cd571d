#pragma once
/// @file
/// What one `World::step()` reports. Numerical trouble is never hidden: non-convergence and
/// non-finite values are flagged here and summarised by the `weft` command.

#include <array>
#include <cstdint>
#include <string_view>

namespace weft {

/// The stages of a substep, in order (docs/architecture.md, "the step in detail").
/// The collision stages (broad phase to check) run only when the scene has collisions to handle.
enum class Stage : std::uint8_t {
    Kinematics,
    Forces,
    Assembly,
    Precondition,  ///< the preconditioner's setup (MAS: aggregation and domain factorisation)
    Solve,
    Update,
    BroadPhase,   ///< spatial hash over the (swept) bounds, for proximity contacts and for CCD
    Culling,      ///< normal-cone BVH refit and test front
    NarrowPhase,  ///< proximity tests and the contact terms of the solve
    Ccd,          ///< continuous collision detection on the candidates
    ImpactZones,  ///< impact-zone solves and their re-checks
    Check,        ///< exact intersection check (only when asked for)
    Count
};
inline constexpr std::array<std::string_view, static_cast<int>(Stage::Count)> kStageNames{
    "kinematics", "forces", "assembly", "precondition", "solve", "update", "broad_phase", "culling", "narrow_phase", "ccd",
    "impact_zones", "check"};

/// Collision work and outcome of one step (all zero when the scene has no cloth collisions).
/// Pair counts are summed over the step's substeps and impact-zone rounds.
struct CollisionStats {
    std::int64_t candidate_pairs = 0;   ///< vertex–face + edge–edge pairs the broad phase produced
    std::int64_t culled_pairs = 0;      ///< pairs normal-cone culling removed (candidates without culling = both)
    int contacts = 0;                   ///< proximity contacts in the last substep's solve
    /// Several GPUs: the proximity contacts on the part that has the most, in the last substep (a
    /// contact with vertices on two parts is on both). Against `contacts` / parts it shows how
    /// evenly the contact work of the solve is spread; 0 on one GPU and on the CPU.
    int contacts_largest_part = 0;
    /// Several GPUs: times the parts were re-cut by contact load in the step (solver.gpu_rebalance).
    int parts_recut = 0;
    std::int64_t ccd_tests = 0;         ///< CCD queries run
    std::int64_t ccd_hits = 0;          ///< of those, reported as colliding (false positives included)
    int impact_zones = 0;               ///< zones formed in the step (summed over substeps)
    int impact_iterations = 0;          ///< largest number of impact-zone rounds one substep needed
    int rigid_zones = 0;                ///< zones that fell back to rigid motion (the cap was hit)
    int frozen_vertices = 0;            ///< vertices the last-resort fallback held at their start position
    /// Substeps whose zone projections spent their work cap (collision.max_impact_work) and handed
    /// the hits left to the fallbacks (cpu backend).
    int impact_work_spent = 0;
    int swept_collider_hits = 0;        ///< vertices a fast analytic collider hit mid-substep and carried along
    /// Slow vertices that ended a substep inside a bounded analytic collider they started outside (a
    /// contact that began within the substep) and were put back onto its surface (swept_collider.h).
    int collider_overshoots = 0;
    int unresolved_substeps = 0;        ///< substeps that ended with a collision still detected (must be 0)
    /// Substeps whose first impact-zone detection reused the proximity detection's pairs instead of
    /// hashing every primitive again (cpu backend; the same pairs either way: docs/collisions.md).
    int reused_detections = 0;
    /// Cloth vertices found inside a closed piece of a mesh collider at a substep's start and moved
    /// just outside its nearest face (cpu backend; summed over the substeps). Should stay 0: a vertex
    /// inside got there past the contacts and the CCD, and counting it says so.
    int ejected_vertices = 0;
    /// Substeps at whose start a mesh collider was not where the last substep ended it (by more than
    /// a tenth of the collision gap), and the largest such jump, m (cpu backend). Should stay 0: the
    /// collider moved with no motion for the CCD to sweep (a game rewriting a pose or motion for
    /// times already stepped, a clip switched with a jump), and cloth can end up through it.
    int collider_jumps = 0;
    double collider_jump_max = 0.0;
    /// Offset mode (CollisionSettings::mode): free cloth vertices whose move the bounds shortened,
    /// summed over the updates of the step; detection reruns; substeps sent to the CCD and impact-zone
    /// fallback because a prescribed move (pin, mesh collider, fast collider) broke a bound; and the
    /// largest per-vertex query radius used, m.
    std::int64_t truncated_vertices = 0;
    int redetections = 0;
    int bound_fallbacks = 0;
    double query_radius_max = 0.0;
    /// Offset mode with normal-cone culling (CPU): updates after which a patch the bound query had
    /// culled no longer passed over the actual move, so every pair was measured and the move
    /// truncated again.
    int uncullings = 0;
    /// GPU: collision buffers (candidate pairs, contacts, CCD hits) grown to a measured need in the
    /// step, each a rerun of its pass; device memory grows with them (sized from use, not in advance).
    int buffer_growths = 0;
    std::int64_t remaining_intersections = -1;  ///< exact check after the step; −1 when not run
    /// Of those, the pairs of a cloth triangle through a mesh collider's (the rest are cloth through
    /// cloth); −1 when not run.
    std::int64_t remaining_collider_intersections = -1;
};

/// A principal stretch at or over which the run summaries report a cloth as overstretched (torn, or
/// held by something that drags it: StepStats::max_stretch).
inline constexpr double kOverstretch = 3.0;

struct StepStats {
    int substeps = 0;
    int newton_iterations = 0;     ///< summed over substeps
    int cg_iterations = 0;         ///< summed over all solves of the step
    int cg_iterations_max = 0;     ///< largest single solve
    double cg_residual = 0.0;      ///< largest final relative residual sqrt(δ/δ₀) of the step's solves
    int cg_not_converged = 0;      ///< solves that hit the iteration cap
    /// MAS domain factorisations that met a non-positive pivot (a domain matrix not SPD in the
    /// backend's precision; the pivot is replaced and the solve goes on, usually with more iterations)
    int preconditioner_pivot_failures = 0;
    /// Solves whose multilevel Schwarz preconditioner turned out not SPD in the backend's precision
    /// (rᵀM⁻¹r negative, so its stopping norm means nothing) and were solved again with block-Jacobi
    /// (cpu backend). The first try's iterations are in cg_iterations too.
    int cg_preconditioner_fallbacks = 0;
    int collider_contacts = 0;     ///< vertex–collider contacts active in the last substep
    CollisionStats collision{};
    bool non_finite = false;       ///< a NaN or Inf appeared; the state was restored to the last good one
    /// Substeps whose solve gave a free vertex a speed no cloth reaches (over 10 km/s: a system
    /// singular in the backend's precision); the solve is dropped and the free vertices keep their
    /// start velocity through the substep, collisions included (cpu and cuda backends; across GPUs
    /// every part drops its solve when any part's vertex ran away).
    int runaway_solves = 0;
    /// The largest principal stretch of any cloth triangle at the end of the step (1 at rest; cloth
    /// stretches a few percent, kOverstretch and more means a torn or dragged cloth), measured by the
    /// energy guard's audit: 0 with solver.energy_guard = "off" and no split_stretch. Reported, not
    /// judged by ok(): very soft cloth may stretch that far by design.
    double max_stretch = 0.0;
    /// Energy guard (SolverSettings::energy_guard; docs/methods.md §1b): substeps whose kinetic +
    /// potential + elastic energy grew beyond the external work, as kept in the state (in retry
    /// mode, those whose redo still gained), and the sum of their gains beyond it, J.
    int energy_gained = 0;
    double energy_gain = 0.0;
    /// Substeps redone with a tighter CG tolerance because their first solve gained energy (retry
    /// mode); those the redo did not cure are also in `energy_gained`.
    int energy_retries = 0;
    /// Substeps (or pieces of one) redone as two halves because they stretched a triangle beyond
    /// SolverSettings::split_stretch; `substeps` counts the pieces the step finally took.
    int split_substeps = 0;
    /// Halvings of Newton updates by the line search (SolverSettings::line_search), over the step.
    int line_search_halvings = 0;
    /// GPU kernels the backend enqueued over the step (cuda backend; 0 on the cpu backend): direct
    /// launches, plus the kernel nodes of each CUDA graph launched. A graph's CG loop is a while node
    /// whose body (two CG iterations) counts once per solve, however often it turns; the one-launch
    /// CG is one kernel whatever its iterations. The energy guard's audits count with the substep
    /// that follows them.
    long long kernels_launched = 0;
    /// Substeps the guard could not judge: a moving mesh collider, or a fast analytic collider that
    /// carried cloth along (work it cannot bound).
    int energy_unchecked = 0;
    std::array<double, static_cast<int>(Stage::Count)> stage_ms{};  ///< wall time per stage, ms
    double step_ms = 0.0;          ///< wall time of the whole step, ms
    /// No NaN, every solve converged, no energy gained, no collision left unresolved and no
    /// intersection found.
    [[nodiscard]] bool ok() const {
        return !non_finite && runaway_solves == 0 && cg_not_converged == 0 && energy_gained == 0 && collision.unresolved_substeps == 0 &&
               collision.remaining_intersections <= 0;
    }
    [[nodiscard]] double& ms(Stage s) { return stage_ms[static_cast<int>(s)]; }
    [[nodiscard]] double ms(Stage s) const { return stage_ms[static_cast<int>(s)]; }
};

}  // namespace weft
