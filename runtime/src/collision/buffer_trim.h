#pragma once
// The CPU collision stages' side of the trim (weft/backend/buffer_trim.h, the policy both backends
// share): a std::vector cut back to what its window needed.

#include <cstddef>
#include <vector>

#include "weft/backend/buffer_trim.h"

namespace weft::collision {

using weft::kTrimExcess;
using weft::kTrimFloorBytes;
using weft::kTrimKeep;
using weft::kTrimPeriod;

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
