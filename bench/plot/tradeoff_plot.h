#pragma once
// Error against cost on log axes (the speed/accuracy benchmarks): each run a labelled point, the
// Pareto front filled and joined. SVG or PNG by the file's extension.

#include <filesystem>
#include <string>
#include <vector>

namespace weft::bench {

struct TradeoffPoint {
    std::string label;
    double cost = 0.0;   ///< x: wall ms per simulated second
    double error = 0.0;  ///< y: RMS position error, m
    bool front = false;  ///< on the Pareto front (filled, joined)
    bool clean = true;   ///< no NaN, capped solve or energy gained (else drawn in orange, marked)
};

/// Whether this build writes PNG plots (the renderer's PNG writer and Dear ImGui's font are built).
[[nodiscard]] bool png_plots_available();

/// Writes the plot of `points` (those with a finite, positive cost and error) to `file`: SVG for a
/// `.svg` file, PNG for `.png`. Throws weft::Error naming the file when there is nothing to draw,
/// the extension is neither, PNG is not built, or the file cannot be written.
void write_tradeoff_plot(const std::filesystem::path& file, const std::string& title, const std::vector<TradeoffPoint>& points);

}  // namespace weft::bench
