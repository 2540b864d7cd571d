#pragma once
/// @file
/// The grow-and-rerun protocol of the GPU collision passes (broad phase, proximity contacts, CCD).
/// A pass writes only what fits its buffers and counts on the device what it needed. The host reads
/// the counts back (the pass's one synchronisation) and, where something did not fit, grows the
/// buffer to the measured count with headroom and runs the pass again. Launch sizes depend only on
/// the host-side capacities, so an enqueued pass can be captured into a CUDA graph; nothing is
/// allocated once the sizes have settled. A capacity that a window of calls needed far less of is
/// cut back at the next enqueue (weft/backend/buffer_trim.h, the CPU's policy too).

#include <cuda_runtime_api.h>

#include <cstddef>
#include <string>
#include <string_view>

#include "device_array.h"
#include "weft/backend/buffer_trim.h"
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

/// After a pass that fit, needing `needed` of `capacity` slots of `element_bytes` each: records it in
/// `trim` and, at the end of a window that cuts, sets `pending` to the smaller capacity
/// (grown_capacity of the window's kept share) for `apply_trim` at the next enqueue.
inline void record_for_trim(CapacityTrim& trim, std::size_t needed, std::size_t capacity, std::size_t element_bytes,
                            std::size_t& pending) {
    if (const std::size_t kept = trim.record(needed, capacity, element_bytes, 1024)) {
        const std::size_t cut = grown_capacity(kept);
        if (cut < capacity) pending = cut;
    }
}

/// At the start of an enqueue: where a trim is `pending`, `capacity` takes it and `buffer` is freed
/// (reallocated at the new size by the enqueue; the free waits for the device, so the last call's
/// readers are done). Returns whether it did.
template <typename T>
bool apply_trim(std::size_t& pending, std::size_t& capacity, DeviceArray<T>& buffer) {
    if (pending == 0) return false;
    capacity = pending;
    pending = 0;
    buffer = {};
    return true;
}

/// Sizes `buffer` for `count` elements where it follows another pass's capacity (the candidate
/// pairs'): grown when smaller, and allocated anew at `count` when it holds more than kTrimExcess
/// times that and over kTrimFloorBytes, so it follows that capacity's trims down.
template <typename T>
void fit_to(DeviceArray<T>& buffer, std::size_t count, MemoryLedger& ledger, const std::string& purpose) {
    const bool oversized = buffer.size() > kTrimExcess * count && buffer.bytes() > kTrimFloorBytes;
    if (buffer.size() < count || oversized) buffer.allocate(count, ledger, purpose);
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
