#pragma once
/// @file
/// The grow-and-rerun protocol of the GPU collision passes (broad phase, proximity contacts, CCD).
/// A pass writes only what fits its buffers and counts on the device what it needed. The host reads
/// the counts back (the pass's one synchronisation) and, where something did not fit, grows the
/// buffer to the measured count with headroom and runs the pass again. Launch sizes depend only on
/// the host-side capacities, so an enqueued pass can be captured into a CUDA graph; nothing is
/// allocated once the sizes have settled.

#include <cuda_runtime_api.h>

#include <cstddef>
#include <string>
#include <string_view>

#include "weft/error.h"

namespace weft::cuda::collision {

/// Capacity after an overflow that needed `needed` slots: 25 % headroom, so that a growing count
/// (cloth settling into folds) does not rerun every step; at least 1024.
[[nodiscard]] constexpr std::size_t grown_capacity(std::size_t needed) {
    const std::size_t c = needed + needed / 4 + 1024;
    return (c + 1023) / 1024 * 1024;
}

/// After a read-back: when the pass `overflowed`, `capacity` becomes grown_capacity(`needed`), the
/// rerun is counted in `reruns`, and the answer is true (run the pass again).
[[nodiscard]] inline bool grow_after_overflow(bool overflowed, std::size_t needed, std::size_t& capacity,
                                              int& reruns) {
    if (!overflowed) return false;
    capacity = grown_capacity(needed);
    ++reruns;
    return true;
}

/// Enqueues a pass with `enqueue(attempt)` (attempt 0 first; a rerun may redo only the part that
/// overflowed), reads its counts back with `pass.read_back(stream)` and asks `pass.needs_rerun()`
/// (which grows what did not fit); until a pass fits. Throws weft::Error "`what` still too small
/// after `attempts` attempts" when none of `attempts` passes did.
template <typename Pass, typename Enqueue>
void rerun_until_fits(Pass& pass, cudaStream_t stream, std::string_view what, int attempts, Enqueue&& enqueue) {
    for (int attempt = 0; attempt < attempts; ++attempt) {
        enqueue(attempt);
        pass.read_back(stream);
        if (!pass.needs_rerun()) return;
    }
    throw Error(std::string(what) + " still too small after " + std::to_string(attempts) + " attempts");
}

}  // namespace weft::cuda::collision
