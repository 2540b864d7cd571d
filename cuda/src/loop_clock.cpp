// The loop clock's host half (loop_clock.h).
#include "loop_clock.h"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <string_view>

namespace weft::cuda {

bool loop_clock_requested() {
    const char* env = std::getenv("WEFT_CUDA_PCG_CLOCK");
    return env != nullptr && std::string_view(env) == "1";
}

void print_loop_clock(const std::string& who, const long long* device_cycles, int device) noexcept {
    static constexpr std::array<const char*, kLoopPhases> kNames = {
        "update", "restrict", "level 1", "coarse restrict", "solves", "prolong", "push", "pairs", "row sums", "product", "sums", "meetings", "(waiting)"};
    std::array<long long, kLoopClockEntries> cycles{};
    int previous = 0, rate_khz = 0;
    if (device_cycles == nullptr || cudaGetDevice(&previous) != cudaSuccess) return;
    const bool read = cudaSetDevice(device) == cudaSuccess && cudaDeviceSynchronize() == cudaSuccess &&
                      cudaMemcpy(cycles.data(), device_cycles, sizeof(cycles), cudaMemcpyDeviceToHost) == cudaSuccess &&
                      cudaDeviceGetAttribute(&rate_khz, cudaDevAttrClockRate, device) == cudaSuccess && rate_khz > 0;
    cudaSetDevice(previous);
    if (!read || cycles[kCountIterations] == 0) return;
    const double iterations = static_cast<double>(cycles[kCountIterations]), mhz = rate_khz / 1e3;
    double total = 0.0;
    for (int k = 0; k < kLoopPhases; ++k)
        if (k != kPhaseWaiting) total += static_cast<double>(cycles[k]) / iterations / mhz;
    std::fprintf(stderr, "CG loop clock, %s (GPU %d), %lld iterations, us per iteration at %.0f MHz: total %.2f;",
                 who.c_str(), device, cycles[kCountIterations], mhz, total);
    for (int k = 0; k < kLoopPhases; ++k)
        if (cycles[k] != 0) std::fprintf(stderr, " %s %.2f", kNames[k], static_cast<double>(cycles[k]) / iterations / mhz);
    if (const long long solves = cycles[kCountSolves]; solves > 0) {
        const auto per_solve = [&](int k) { return static_cast<double>(cycles[k]) / static_cast<double>(solves); };
        std::fprintf(stderr, "; contacts a solve (%lld solves): pairs %.0f, in the solve %.0f, incidence entries %.0f", solves,
                     per_solve(kCountPairs), per_solve(kCountActivePairs), per_solve(kCountEntries));
    }
    std::fprintf(stderr, "\n");
}

}  // namespace weft::cuda
