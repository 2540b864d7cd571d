#pragma once
/// @file
/// Stage times for StepStats (weft/stats.h): what a backend, a tool or a benchmark measures on the
/// host is wall time on the steady clock, in milliseconds.

#include <chrono>

namespace weft {

/// Milliseconds from `start` to now, on std::chrono::steady_clock (monotonic: never negative).
[[nodiscard]] inline double ms_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace weft
