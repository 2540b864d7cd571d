#pragma once
// Giving back what one rare frame made a scratch buffer hold. The collision stages keep their
// buffers between calls so that steady frames do not allocate (docs/design.md); a sheet folding
// onto itself can make one frame need 15M candidate pairs (the soak's `projectile`: 1.8 → 106 MB,
// kept for the rest of the run). A buffer whose capacity stays far above what it held over a window
// of calls is cut back, with room to spare, so memory follows the scene with a lag and a steady
// scene still never allocates.

#include <cstddef>
#include <vector>

namespace weft::collision {

/// Calls of the stage between two trims.
inline constexpr std::size_t kTrimPeriod = 240;
/// Capacity over this many times the window's peak is cut back...
inline constexpr std::size_t kTrimExcess = 4;
/// ...to this many times the peak...
inline constexpr std::size_t kTrimKeep = 2;
/// ...when it holds more than this (smaller buffers are not worth an allocation), bytes.
inline constexpr std::size_t kTrimFloorBytes = std::size_t{1} << 20;

/// Cuts `v`'s capacity to kTrimKeep·`peak` elements when it exceeds kTrimExcess·`peak` and
/// kTrimFloorBytes; `peak` is the largest size it held in the window (≥ its size now). The contents
/// are kept. Returns whether it was cut.
template <typename T>
bool trim_to_peak(std::vector<T>& v, std::size_t peak) {
    if (v.capacity() <= kTrimExcess * peak || v.capacity() * sizeof(T) <= kTrimFloorBytes) return false;
    std::vector<T> kept;
    kept.reserve(kTrimKeep * peak > v.size() ? kTrimKeep * peak : v.size());
    kept.assign(v.begin(), v.end());
    v.swap(kept);
    return true;
}

}  // namespace weft::collision
