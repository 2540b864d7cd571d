#pragma once
// Deterministic parallel loops on the host (TBB), for the CPU backend and the CPU collision stages.
// Work is cut into fixed-size chunks that do not depend on the thread count; reductions sum one
// partial per chunk, then the partials in chunk order, so results are bit-identical on 1 or 64
// threads (docs/design.md, "Determinism").

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>
#include <vector>

namespace weft {

/// Elements per chunk: large enough to amortise a task, small enough to balance 2–64 threads on a
/// game's cloth (5K rows make 10 chunks; 2,048 made 3, and one of two threads waited: 5–7% of a
/// frame, docs/results.md "The CPU backend as a game fallback").
inline constexpr std::size_t kParallelChunk = 512;

/// Calls body(begin, end) over [0, n) in parallel chunks.
template <typename Body>
void parallel_chunks(std::size_t n, Body&& body) {
    if (n == 0) return;
    if (n <= kParallelChunk) {
        body(std::size_t{0}, n);
        return;
    }
    const std::size_t chunks = (n + kParallelChunk - 1) / kParallelChunk;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t c = r.begin(); c != r.end(); ++c) body(c * kParallelChunk, std::min(n, (c + 1) * kParallelChunk));
    });
}

/// Calls body(begin, end) over [0, n) in parallel chunks of `grain` elements, for loops whose
/// elements are heavy (a dense 48×48 solve each) and write disjoint outputs: no reduction, so any
/// grain gives the same result.
template <typename Body>
void parallel_grains(std::size_t n, std::size_t grain, Body&& body) {
    if (n == 0) return;
    if (n <= grain) {
        body(std::size_t{0}, n);
        return;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

/// Sums chunk(begin, end) → double over [0, n) deterministically. `partials` is scratch (kept to
/// avoid allocating in the step).
template <typename Chunk>
double deterministic_sum(std::size_t n, std::vector<double>& partials, Chunk&& chunk) {
    const std::size_t chunks = (n + kParallelChunk - 1) / kParallelChunk;
    if (partials.size() < chunks) partials.resize(chunks);
    parallel_chunks(n, [&](std::size_t b, std::size_t e) { partials[b / kParallelChunk] = chunk(b, e); });
    double sum = 0.0;
    for (std::size_t c = 0; c < chunks; ++c) sum += partials[c];
    return sum;
}

}  // namespace weft
