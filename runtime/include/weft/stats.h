#pragma once
/// @file
/// What one `World::step()` reports. Numerical trouble is never hidden: non-convergence and
/// non-finite values are flagged here and summarised by the `weft` command.

#include <array>
#include <cstdint>
#include <string_view>

namespace weft {

/// The stages of a substep, in order (docs/architecture.md, "the step in detail").
enum class Stage : std::uint8_t { Kinematics, Forces, Assembly, Solve, Update, Count };
inline constexpr std::array<std::string_view, static_cast<int>(Stage::Count)> kStageNames{
    "kinematics", "forces", "assembly", "solve", "update"};

struct StepStats {
    int substeps = 0;
    int newton_iterations = 0;     ///< summed over substeps
    int cg_iterations = 0;         ///< summed over all solves of the step
    int cg_iterations_max = 0;     ///< largest single solve
    double cg_residual = 0.0;      ///< largest final relative residual sqrt(δ/δ₀) of the step's solves
    int cg_not_converged = 0;      ///< solves that hit the iteration cap
    int collider_contacts = 0;     ///< vertex–collider contacts active in the last substep
    bool non_finite = false;       ///< a NaN or Inf appeared; the state was restored to the last good one
    std::array<double, static_cast<int>(Stage::Count)> stage_ms{};  ///< wall time per stage, ms
    double step_ms = 0.0;          ///< wall time of the whole step, ms
    [[nodiscard]] bool ok() const { return !non_finite && cg_not_converged == 0; }
    [[nodiscard]] double& ms(Stage s) { return stage_ms[static_cast<int>(s)]; }
    [[nodiscard]] double ms(Stage s) const { return stage_ms[static_cast<int>(s)]; }
};

}  // namespace weft
