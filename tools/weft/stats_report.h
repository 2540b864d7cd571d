#pragma once
/// @file
/// What a run measured and how it is reported: per-frame `StepStats` reduced to medians and maxima,
/// the stats JSON of docs/design.md ("Statistics") and the summary table `weft run` prints.
/// Numerical trouble (CG hitting its cap, NaN/Inf) is counted and turned into warnings, never hidden.

#include <array>
#include <cstddef>
#include <limits>
#include <ostream>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "weft/backend_options.h"
#include "weft/stats.h"

#include "frame_capture.h"
#include "json_writer.h"

namespace weft {
class World;
struct SceneDesc;
}  // namespace weft

namespace weft::cli {

inline constexpr std::size_t kStageCount = static_cast<std::size_t>(Stage::Count);

/// Median, maximum, mean and sum of a per-frame quantity, NaN values left out. NaN (JSON null) when
/// nothing is left.
struct Distribution {
    double median = std::numeric_limits<double>::quiet_NaN();
    double max = std::numeric_limits<double>::quiet_NaN();
    double mean = std::numeric_limits<double>::quiet_NaN();
    double total = 0.0;
    std::size_t count = 0;
};
[[nodiscard]] Distribution distribution(std::vector<double> values);

/// Frame-by-frame stats reduced over a run.
struct RunSummary {
    std::size_t frames = 0;
    std::array<Distribution, kStageCount> stage_ms{};  ///< per frame (summed over its substeps)
    Distribution step_ms;
    Distribution cg_iterations;       ///< per frame, summed over its solves
    Distribution kernels;             ///< GPU kernels enqueued per frame (StepStats::kernels_launched; 0 on the cpu)
    int cg_iterations_max_solve = 0;  ///< largest single solve
    long long solves = 0;             ///< linear solves (Newton iterations) in all frames
    long long cg_not_converged = 0;   ///< solves that hit the iteration cap
    long long cg_preconditioner_fallbacks = 0;  ///< solves whose Schwarz preconditioner was not SPD, redone with block-Jacobi
    std::size_t frames_not_converged = 0;
    double cg_residual_max = 0.0;  ///< largest final relative residual of any solve
    std::size_t non_finite_frames = 0;
    long long runaway_solves = 0;  ///< substeps whose solve ran away and was dropped (StepStats::runaway_solves)
    /// The largest principal stretch of any triangle at the end of any frame (StepStats::max_stretch;
    /// 0 when the energy guard is off), the frames at or over kOverstretch and the first (1-based, −1).
    double max_stretch = 0.0;
    std::size_t overstretched_frames = 0;
    long long first_overstretched_frame = -1;
    long long first_non_finite_frame = -1;  ///< 1-based frame number, -1 if none
    Distribution contacts;                  ///< collider contacts per frame
    /// Analytic colliders after the solve (swept_collider.h), over all frames: vertices a fast one
    /// carried along, and slow vertices that ended inside one and were put back onto its surface.
    long long swept_collider_hits = 0;
    long long collider_overshoots = 0;
    /// Energy guard (solver.energy_guard; docs/methods.md §1b), over all frames: substeps whose
    /// energy grew beyond the external work as kept (StepStats::energy_gained), the frames they fell
    /// in, their summed excess (J), the redone substeps and those the guard could not judge.
    long long substeps = 0;
    long long energy_gained = 0;
    std::size_t frames_energy_gained = 0;
    long long first_energy_frame = -1;  ///< 1-based frame number, -1 if none
    double energy_gain = 0.0;
    long long energy_retries = 0;
    long long line_search_halvings = 0;
    long long energy_unchecked = 0;
    /// Substeps redone as halves for overstretching the cloth (solver.split_stretch), and the frames
    /// in which any was.
    long long split_substeps = 0;
    std::size_t frames_split = 0;
    /// Cloth collisions (docs/collisions.md), over all frames.
    struct Collisions {
        bool active = false;                  ///< any collision stage ran
        Distribution candidate_pairs;         ///< per frame
        Distribution culled_pairs;            ///< per frame
        Distribution contacts;                ///< proximity contacts in a frame's last substep
        Distribution contacts_largest_part;   ///< several GPUs: those on the busiest part
        long long ccd_tests = 0, ccd_hits = 0;
        long long impact_zones = 0;
        int impact_iterations_max = 0;
        long long rigid_zones = 0, frozen_vertices = 0;
        long long impact_work_spent = 0;  ///< substeps whose projections spent collision.max_impact_work
        long long unresolved_substeps = 0;
        long long reused_detections = 0;  ///< first zone detections that reused the proximity's pairs (cpu)
        long long ejected_vertices = 0;  ///< cloth vertices moved out of a closed mesh collider (cpu backend)
        long long collider_jumps = 0;    ///< substeps a mesh collider started away from where it ended (cpu)
        double collider_jump_max = 0.0;  ///< the largest such jump, m
        /// Offset mode (CollisionStats): truncated vertex moves, detection reruns, CCD fallbacks and
        /// the largest query radius (m).
        long long truncated_vertices = 0, redetections = 0, bound_fallbacks = 0, uncullings = 0;
        long long buffer_growths = 0;  ///< collision buffers grown while stepping (GPU)
        long long parts_recut = 0;     ///< several GPUs: re-cuts of the parts by contact load
        double query_radius_max = 0.0;
        std::size_t checked_frames = 0;       ///< frames the exact check ran after
        long long remaining_intersections_max = 0;
        std::size_t frames_with_intersections = 0;
        /// Of the intersections: frames with a cloth triangle through a mesh collider's, and the most
        /// such pairs in a frame.
        long long collider_intersections_max = 0;
        std::size_t frames_with_collider_intersections = 0;
        long long first_intersecting_frame = -1;  ///< 1-based, -1 if none
    } collisions;
    double simulation_seconds = 0.0;        ///< sum of step times, s
    double fps = 0.0;                       ///< frames per second of simulation time (I/O excluded)
    [[nodiscard]] bool ok() const {
        return cg_not_converged == 0 && non_finite_frames == 0 && runaway_solves == 0 && energy_gained == 0 &&
               collisions.unresolved_substeps == 0 &&
               collisions.frames_with_intersections == 0;
    }
};
[[nodiscard]] RunSummary summarize(std::span<const StepStats> frames);

/// Facts about the scene and world that do not change from frame to frame.
struct RunContext {
    std::string scene;  ///< scene name
    std::string scene_file;
    std::string backend;
    std::string device;
    int threads = 0;  ///< as requested (0 = all cores)
    std::string host_wait = "auto";  ///< how the host waits for a GPU backend (--host-wait)
    std::size_t cloths = 0;
    std::size_t vertices = 0;
    std::size_t triangles = 0;
    double dt = 0.0;  ///< s per frame
    int substeps = 0;
    int newton_iterations = 0;
    double cg_tolerance = 0.0;
    int cg_max_iterations = 0;
    std::string precision;  ///< "float" or "double"
    std::string energy_guard = "off";  ///< solver.energy_guard: "off", "report" or "retry"
    double split_stretch = 0.0;        ///< solver.split_stretch (0: off)
    /// Whether CollisionStats::culled_pairs was counted: collision.count_culled on the cpu backend
    /// (the cuda backend does not count them; weft_cuda_collision_bench measures its culling).
    bool culled_pairs_counted = false;
    std::size_t backend_memory_bytes = 0;
    std::vector<std::pair<std::string, std::size_t>> backend_memory_breakdown;  ///< by purpose
    std::size_t fabric_memory_bytes = 0;     ///< each shared fabric counted once
    std::vector<std::string> cook_warnings;  ///< from the fabrics' cook reports, prefixed by cloth name
    [[nodiscard]] std::size_t memory_bytes() const { return backend_memory_bytes + fabric_memory_bytes; }
    [[nodiscard]] double memory_bytes_per_triangle() const {
        return triangles > 0 ? static_cast<double>(memory_bytes()) / static_cast<double>(triangles) : 0.0;
    }
};
[[nodiscard]] RunContext describe_run(const SceneDesc& scene, const World& world, int threads,
                                      HostWait host_wait = HostWait::automatic);

/// One line per problem: solves that did not converge, non-finite events, cook warnings.
[[nodiscard]] std::vector<std::string> run_warnings(const RunContext& context, const RunSummary& summary);

/// Writes the summary keys into an object the caller has opened (shared by run and bench JSON).
void write_summary_fields(json::JsonWriter& json, const RunContext& context, const RunSummary& summary);
/// The stats JSON of one run: summary keys plus the per-frame series (step_ms, cg_iterations, contacts).
/// With `capture`, a "capture" object: renderer, device, path, bytes per frame, frames, median ms.
void write_run_json(std::ostream& out, const RunContext& context, const RunSummary& summary,
                    std::span<const StepStats> frames, double wall_seconds, const CaptureSummary* capture = nullptr);
/// The summary table printed at the end of `weft run`, warnings included, and the capture's lines.
void print_run_summary(std::ostream& out, const RunContext& context, const RunSummary& summary, double wall_seconds,
                       const CaptureSummary* capture = nullptr);

}  // namespace weft::cli
