#pragma once
/// @file
/// The last few hundred steps' statistics as series for the stats panel's plots (ImGui PlotLines
/// takes a float array and an offset: a ring buffer per series).
#include <array>
#include <cstddef>
#include <string_view>
#include <vector>

#include "weft/stats.h"

namespace weft::editor {

/// A ring of the last `capacity` values of one quantity.
class Series {
public:
    explicit Series(std::size_t capacity) : values_(capacity, 0.0F) {}
    void push(double value);
    void clear();
    /// Values oldest first are values()[(offset() + k) % capacity] for k < size().
    [[nodiscard]] const std::vector<float>& values() const { return values_; }
    [[nodiscard]] std::size_t offset() const { return size_ < values_.size() ? 0 : next_; }
    [[nodiscard]] std::size_t size() const { return size_; }
    [[nodiscard]] float last() const;
    [[nodiscard]] float max() const;

private:
    std::vector<float> values_;
    std::size_t next_ = 0;
    std::size_t size_ = 0;
};

/// One series per plotted quantity, fed one StepStats per step.
struct StatsHistory {
    static constexpr std::size_t kCapacity = 300;  ///< steps kept (5 s at 60 Hz)
    Series step_ms{kCapacity};                     ///< wall time of the step, ms
    std::array<Series, static_cast<int>(Stage::Count)> stage_ms = make_stages();  ///< per stage, ms
    Series cg_iterations{kCapacity};                                             ///< summed over the step's solves
    Series cg_residual_log10{kCapacity};  ///< log10 of the largest final relative residual
    Series contacts{kCapacity};           ///< collider contacts + cloth proximity contacts
    Series impact_zones{kCapacity};       ///< impact zones formed in the step (collision stages only)
    Series intersections{kCapacity};      ///< intersecting triangle pairs after the step (exact check on)
    Series frame_ms{kCapacity};           ///< wall time between displayed frames, ms
    int steps = 0;                        ///< steps recorded since the last clear
    int not_converged_steps = 0;          ///< of those, steps with a CG solve that hit its cap
    int energy_gained_steps = 0;          ///< of those, steps with a substep that gained energy (energy guard)
    int non_finite_steps = 0;             ///< of those, steps where NaN or Inf appeared
    int runaway_steps = 0;                ///< of those, steps with a solve that ran away (StepStats::runaway_solves)
    int overstretched_steps = 0;          ///< of those, steps ending with cloth at kOverstretch or more (StepStats::max_stretch)
    StepStats last{};

    void record(const StepStats& s);
    void clear();

private:
    static std::array<Series, static_cast<int>(Stage::Count)> make_stages();
};

}  // namespace weft::editor
