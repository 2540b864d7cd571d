// Series of step statistics for the stats panel (see stats_history.h).
#include "weft/editor/stats_history.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace weft::editor {

void Series::push(double value) {
    values_[next_] = static_cast<float>(value);
    next_ = (next_ + 1) % values_.size();
    size_ = std::min(size_ + 1, values_.size());
}

void Series::clear() {
    std::fill(values_.begin(), values_.end(), 0.0F);
    next_ = 0;
    size_ = 0;
}

float Series::last() const { return size_ == 0 ? 0.0F : values_[(next_ + values_.size() - 1) % values_.size()]; }

float Series::max() const {
    float m = 0.0F;
    for (std::size_t k = 0; k < size_; ++k) m = std::max(m, values_[(offset() + k) % values_.size()]);
    return m;
}

std::array<Series, static_cast<int>(Stage::Count)> StatsHistory::make_stages() {
    return [&]<std::size_t... I>(std::index_sequence<I...>) {
        return std::array<Series, sizeof...(I)>{((void)I, Series(kCapacity))...};
    }(std::make_index_sequence<static_cast<std::size_t>(Stage::Count)>{});
}

void StatsHistory::record(const StepStats& s) {
    step_ms.push(s.step_ms);
    for (std::size_t i = 0; i < stage_ms.size(); ++i) stage_ms[i].push(s.stage_ms[i]);
    cg_iterations.push(s.cg_iterations);
    // Residuals span decades; 1e-12 keeps log10 finite for an exact solve.
    cg_residual_log10.push(std::log10(std::max(s.cg_residual, 1e-12)));
    contacts.push(s.collider_contacts + s.collision.contacts);
    impact_zones.push(s.collision.impact_zones);
    intersections.push(static_cast<double>(std::max<std::int64_t>(s.collision.remaining_intersections, 0)));
    ++steps;
    if (s.cg_not_converged > 0) ++not_converged_steps;
    if (s.non_finite) ++non_finite_steps;
    if (s.runaway_solves > 0) ++runaway_steps;
    if (s.max_stretch >= kOverstretch) ++overstretched_steps;
    if (s.energy_gained > 0) ++energy_gained_steps;
    last = s;
}

void StatsHistory::clear() {
    step_ms.clear();
    for (Series& s : stage_ms) s.clear();
    cg_iterations.clear();
    cg_residual_log10.clear();
    contacts.clear();
    impact_zones.clear();
    intersections.clear();
    frame_ms.clear();
    steps = not_converged_steps = non_finite_steps = runaway_steps = overstretched_steps = energy_gained_steps = 0;
    last = {};
}

}  // namespace weft::editor
