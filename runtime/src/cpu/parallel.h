#pragma once
// Deterministic parallel loops for the CPU backend. Work is cut into fixed-size chunks that do not
// depend on the thread count; reductions sum one partial per chunk, then the partials in chunk order,
// so results are bit-identical on 1 or 64 threads (docs/design.md, "Determinism").

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>
#include <vector>

namespace weft::cpu {

inline constexpr std::size_t kChunk = 2048;

/// Calls body(begin, end) over [0, n) in parallel chunks.
template <typename Body>
void parallel_chunks(std::size_t n, Body&& body) {
    if (n == 0) return;
    if (n <= kChunk) {
        body(std::size_t{0}, n);
        return;
    }
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t c = r.begin(); c != r.end(); ++c) body(c * kChunk, std::min(n, (c + 1) * kChunk));
    });
}

/// Sums chunk(begin, end) → double over [0, n) deterministically. `partials` is scratch (kept to
/// avoid allocating in the step).
template <typename Chunk>
double deterministic_sum(std::size_t n, std::vector<double>& partials, Chunk&& chunk) {
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    if (partials.size() < chunks) partials.resize(chunks);
    parallel_chunks(n, [&](std::size_t b, std::size_t e) { partials[b / kChunk] = chunk(b, e); });
    double sum = 0.0;
    for (std::size_t c = 0; c < chunks; ++c) sum += partials[c];
    return sum;
}

}  // namespace weft::cpu
