#pragma once
/// @file
/// A fixed simulation rate under a variable display rate. Each displayed frame hands in the wall
/// time that passed; the loop runs the whole steps of `settings().solver.dt` that fit (scaled by the
/// time scale) and carries the remainder to the next frame, so the simulation advances at real
/// time (× the time scale) whatever the display does. At most `max_steps_per_frame` steps run per
/// call: when stepping is slower than real time the excess is dropped and counted (the simulation
/// falls behind instead of spiralling into ever longer frames). Pause, single-step and time scale
/// are what an editor's play controls need.
#include <cstdint>

#include <vector>

#include "weft/stats.h"
#include "weft/world.h"

namespace weft {

class FrameLoop {
public:
    struct Options {
        double time_scale = 1.0;     ///< simulated seconds per wall second; valid range [0.01, 100]
        int max_steps_per_frame = 4;  ///< valid range [1, 1000]
    };

    /// Drives `world` (kept by reference). Throws `weft::Error` for options out of range.
    explicit FrameLoop(World& world, Options options);
    explicit FrameLoop(World& world) : FrameLoop(world, Options{}) {}

    /// A display frame after `wall_seconds` (≥ 0) of wall time: runs the steps due and returns how
    /// many ran. Paused: none, unless a single step was requested, which runs exactly one.
    int advance(double wall_seconds);

    void set_paused(bool paused);
    [[nodiscard]] bool paused() const { return paused_; }
    /// While paused, the next `advance` runs exactly one step (then stays paused).
    void request_single_step() { single_step_ = true; }
    /// Throws `weft::Error` outside [0.01, 100].
    void set_time_scale(double scale);
    [[nodiscard]] double time_scale() const { return options_.time_scale; }

    /// Simulated time owed but not yet stepped, as a fraction of a step in [0, 1): how far the
    /// display is between the last two states (for interpolation).
    [[nodiscard]] double alpha() const;
    [[nodiscard]] std::int64_t steps() const { return steps_; }
    /// Steps skipped because a frame owed more than max_steps_per_frame.
    [[nodiscard]] std::int64_t dropped_steps() const { return dropped_; }
    /// Stats of the last step taken (empty before the first).
    [[nodiscard]] const StepStats& last_stats() const { return last_; }
    /// Stats of every step the last `advance` ran, in order (empty when it ran none): a frame that
    /// runs several steps shows each (the editor's per-step history). Holds at most
    /// max_steps_per_frame entries; its storage is reused, nothing is allocated after the first frame
    /// that ran that many.
    [[nodiscard]] const std::vector<StepStats>& frame_stats() const { return frame_stats_; }

private:
    World& world_;
    Options options_;
    double owed_ = 0.0;  // simulated seconds due, s
    bool paused_ = false;
    bool single_step_ = false;
    std::int64_t steps_ = 0;
    std::int64_t dropped_ = 0;
    StepStats last_{};
    std::vector<StepStats> frame_stats_;
};

}  // namespace weft
