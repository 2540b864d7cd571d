// Fixed simulation rate under a variable display rate (see frame_loop.h).
#include "weft/frame_loop.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "weft/error.h"

namespace weft {
namespace {

void check_time_scale(double scale) {
    if (!(scale >= 0.01 && scale <= 100.0))
        throw Error("frame loop: time scale " + std::to_string(scale) + " is outside [0.01, 100]");
}

}  // namespace

FrameLoop::FrameLoop(World& world, Options options) : world_(world), options_(options) {
    check_time_scale(options.time_scale);
    if (options.max_steps_per_frame < 1 || options.max_steps_per_frame > 1000)
        throw Error("frame loop: max_steps_per_frame " + std::to_string(options.max_steps_per_frame) +
                    " is outside [1, 1000]");
}

void FrameLoop::set_paused(bool paused) {
    paused_ = paused;
    owed_ = 0.0;  // no catching up on the time spent paused
}

void FrameLoop::set_time_scale(double scale) {
    check_time_scale(scale);
    options_.time_scale = scale;
}

double FrameLoop::alpha() const {
    const double dt = world_.settings().solver.dt;
    return dt > 0.0 ? std::clamp(owed_ / dt, 0.0, 1.0 - 1e-12) : 0.0;
}

int FrameLoop::advance(double wall_seconds) {
    if (!(wall_seconds >= 0.0) || !std::isfinite(wall_seconds))
        throw Error("frame loop: wall time " + std::to_string(wall_seconds) + " s is not a finite time ≥ 0");
    frame_stats_.clear();
    if (paused_) {
        if (!single_step_) return 0;
        single_step_ = false;
        last_ = world_.step();
        frame_stats_.push_back(last_);
        ++steps_;
        return 1;
    }
    single_step_ = false;
    const double dt = world_.settings().solver.dt;  // read each frame: dt may be edited live
    owed_ += wall_seconds * options_.time_scale;
    // A relative tolerance keeps 60 calls of 1/60 s from stepping 59 times by rounding.
    auto due = static_cast<std::int64_t>(std::floor(owed_ / dt + 1e-9));
    int ran = 0;
    if (due > options_.max_steps_per_frame) {
        dropped_ += due - options_.max_steps_per_frame;
        owed_ -= static_cast<double>(due - options_.max_steps_per_frame) * dt;
        due = options_.max_steps_per_frame;
    }
    for (std::int64_t k = 0; k < due; ++k) {
        last_ = world_.step();
        frame_stats_.push_back(last_);
        ++steps_;
        ++ran;
    }
    owed_ = std::max(0.0, owed_ - static_cast<double>(due) * dt);
    return ran;
}

}  // namespace weft
