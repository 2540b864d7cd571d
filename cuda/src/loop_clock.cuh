#pragma once
// The device half of the loop clock (loop_clock.h): block 0's first thread reads the SM clock at
// each phase's end and charges the cycles since the last mark to that phase.

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
        if (on()) out[kLoopPhases] += 1;
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

}  // namespace weft::cuda
