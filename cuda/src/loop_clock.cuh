#pragma once
// The device half of the loop clock (loop_clock.h): block 0's first thread reads the SM clock at
// each phase's end and charges the cycles since the last mark to that phase.

#include "loop_clock.h"

namespace weft::cuda {

struct LoopClock {
    long long* out = nullptr;  // null: off, and every call returns at once
    long long spent[kLoopPhases] = {};
    long long last = 0, iterations = 0;

    __device__ explicit LoopClock(long long* device_clock)
        : out(device_clock != nullptr && blockIdx.x == 0 && threadIdx.x == 0 ? device_clock : nullptr) {
        if (out != nullptr) last = clock64();
    }
    [[nodiscard]] __device__ bool on() const { return out != nullptr; }
    __device__ void iteration() { iterations += on() ? 1 : 0; }
    __device__ void mark(int phase) {
        if (!on()) return;
        const long long now = clock64();
        spent[phase] += now - last;
        last = now;
    }
    /// Adds `cycles` to a phase without moving the mark (a part of a phase timed inside it).
    __device__ void add(int phase, long long cycles) {
        if (on()) spent[phase] += cycles;
    }
    /// Adds this launch's cycles and iterations to the device totals.
    __device__ void flush() const {
        if (!on()) return;
        for (int k = 0; k < kLoopPhases; ++k) out[k] += spent[k];
        out[kLoopPhases] += iterations;
    }
};

}  // namespace weft::cuda
