#pragma once
// The device half of the loop clock (loop_clock.h): block 0's first thread reads the SM clock at
// each phase's end and charges the cycles since the last mark to that phase.

#include "contact_terms.cuh"
#include "loop_clock.h"

namespace weft::cuda {

/// Charges straight to device memory (one thread's read-modify-writes, a few per iteration): the
/// clock costs every other thread of the loop one pointer and one count in registers, not a
/// register per phase, which would lower the occupancy of the loop it times.
struct LoopClock {
    long long* out = nullptr;  // null: off, and every call returns at once
    long long last = 0;

    __device__ explicit LoopClock(long long* device_clock)
        : out(device_clock != nullptr && blockIdx.x == 0 && threadIdx.x == 0 ? device_clock : nullptr) {
        if (out != nullptr) last = clock64();
    }
    [[nodiscard]] __device__ bool on() const { return out != nullptr; }
    __device__ void iteration() {
        if (on()) out[kCountIterations] += 1;
    }
    __device__ void mark(int phase) {
        if (!on()) return;
        const long long now = clock64();
        out[phase] += now - last;
        last = now;
    }
    /// Adds `cycles` to a phase without moving the mark (a part of a phase timed inside it).
    __device__ void add(int phase, long long cycles) {
        if (on()) out[phase] += cycles;
    }
};

/// Counts a solve's contact work into the clock (kCountSolves…kCountEntries): the pairs of `c`, those
/// in the solve (a popcount of the active mask, a warp sum and one atomic a warp) and the incidence
/// entries of rows [0, rows). Every thread of the grid calls it, converged, before its loop.
__device__ inline void clock_contact_work(long long* device_clock, const ContactView& c, std::uint32_t rows) {
    if (device_clock == nullptr) return;
    const std::uint32_t pairs = contact_count(c), words = (pairs + 31) / 32;
    const std::uint32_t thread = blockIdx.x * blockDim.x + threadIdx.x, threads = gridDim.x * blockDim.x;
    unsigned active = 0;
    for (std::uint32_t k = thread; k < words; k += threads) active += static_cast<unsigned>(__popc(c.active_mask[k]));
    for (int offset = 16; offset > 0; offset /= 2) active += __shfl_down_sync(0xffffffffu, active, offset);
    auto* counts = reinterpret_cast<unsigned long long*>(device_clock);
    if (threadIdx.x % 32 == 0 && active != 0) atomicAdd(counts + kCountActivePairs, static_cast<unsigned long long>(active));
    if (thread == 0) {
        atomicAdd(counts + kCountSolves, 1ull);
        atomicAdd(counts + kCountPairs, static_cast<unsigned long long>(pairs));
        atomicAdd(counts + kCountEntries, static_cast<unsigned long long>(c.start[rows]));
    }
}

}  // namespace weft::cuda
