#pragma once
/// @file
/// Giving back what one rare frame made a scratch buffer hold (backend kit). The collision stages
/// keep their buffers between calls so that steady frames do not allocate (docs/design.md,
/// "Memory"); a sheet folding onto itself can make one frame need 15M candidate pairs (the soak's
/// `projectile`: 1.8 → 106 MB, kept for the rest of the run). A buffer whose capacity stays far above
/// what it held over a window of calls is cut back, with room to spare, so memory follows the scene
/// with a lag and a steady scene still never allocates. One policy for both backends: the CPU's
/// vectors (collision/buffer_trim.h, trim_to_peak) and the GPU passes' device arrays (CapacityTrim).

#include <algorithm>
#include <cstddef>

namespace weft {

/// Calls of the stage between two trims.
inline constexpr std::size_t kTrimPeriod = 240;
/// Capacity over this many times the window's peak is cut back...
inline constexpr std::size_t kTrimExcess = 4;
/// ...to this many times the peak...
inline constexpr std::size_t kTrimKeep = 2;
/// ...when it holds more than this (smaller buffers are not worth an allocation), bytes.
inline constexpr std::size_t kTrimFloorBytes = std::size_t{1} << 20;

/// The trim window of one buffer that is sized by a capacity (elements) and reallocated by its
/// owner: it records what each call needed and, at the end of every window of kTrimPeriod calls,
/// says whether the capacity should come down and to what.
class CapacityTrim {
public:
    /// After a call that needed `needed` elements of a buffer holding `capacity` of
    /// `element_bytes` bytes: the capacity to cut it to (kTrimKeep × the window's peak, at least
    /// `minimum`), or 0 to keep it. Nonzero only at a window's end.
    [[nodiscard]] std::size_t record(std::size_t needed, std::size_t capacity, std::size_t element_bytes,
                                     std::size_t minimum = 0) {
        peak_ = std::max(peak_, needed);
        if (++calls_ < kTrimPeriod) return 0;
        const std::size_t peak = peak_;
        calls_ = 0;
        peak_ = 0;
        if (capacity <= kTrimExcess * peak || capacity * element_bytes <= kTrimFloorBytes) return 0;
        const std::size_t kept = std::max(kTrimKeep * peak, minimum);
        return kept < capacity ? kept : 0;
    }

private:
    std::size_t calls_ = 0, peak_ = 0;
};

}  // namespace weft
