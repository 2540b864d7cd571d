#pragma once
// A stable least-significant-digit radix sort on an unsigned 64-bit key of each item, in passes of
// at most 11 bits (2048 buckets stay in L1 per chunk), over fixed chunks so that the (digit, chunk)
// offsets, hence the result, do not depend on the thread count. The broad phase sorts its hash
// entries by cell with it, and its pair lists by their two ids (a key that orders them as the
// pairs' own comparison does, so the result is the comparison sort's).

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace weft::collision {

/// Sorts `items` by `key(item)` on its low `bits` bits (0: nothing to sort), stably. `scratch` and
/// `histogram` are the caller's buffers, kept between calls.
template <typename Item, typename Key>
void radix_sort_by_key(std::vector<Item>& items, std::vector<Item>& scratch, std::vector<std::size_t>& histogram, int bits,
                       Key&& key) {
    if (bits <= 0) return;
    const int passes = (bits + 10) / 11;
    const int digit_bits = (bits + passes - 1) / passes;
    const std::size_t buckets = std::size_t{1} << digit_bits;
    const std::uint64_t digit_mask = buckets - 1;
    const std::size_t n = items.size();
    constexpr std::size_t kSortChunk = std::size_t{1} << 16;
    const std::size_t chunks = (n + kSortChunk - 1) / kSortChunk;
    histogram.resize(chunks * buckets);
    scratch.resize(n);
    for (int pass = 0; pass < passes; ++pass) {
        const int shift = pass * digit_bits;
        const auto each_chunk = [&](auto&& body) {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t c = r.begin(); c != r.end(); ++c) body(c, c * kSortChunk, std::min(n, (c + 1) * kSortChunk));
            });
        };
        each_chunk([&](std::size_t c, std::size_t b, std::size_t e) {
            std::size_t* h = histogram.data() + c * buckets;
            std::fill(h, h + buckets, std::size_t{0});
            for (std::size_t i = b; i < e; ++i) ++h[(key(items[i]) >> shift) & digit_mask];
        });
        std::size_t at = 0;
        for (std::size_t d = 0; d < buckets; ++d)
            for (std::size_t c = 0; c < chunks; ++c) {
                const std::size_t count = histogram[c * buckets + d];
                histogram[c * buckets + d] = at;
                at += count;
            }
        each_chunk([&](std::size_t c, std::size_t b, std::size_t e) {
            std::size_t* h = histogram.data() + c * buckets;
            for (std::size_t i = b; i < e; ++i) scratch[h[(key(items[i]) >> shift) & digit_mask]++] = items[i];
        });
        items.swap(scratch);
    }
}

/// Bits needed for ids below `count` (0 for count ≤ 1).
inline int bits_for(std::size_t count) {
    int bits = 0;
    while (bits < 64 && (std::size_t{1} << bits) < count) ++bits;
    return bits;
}

}  // namespace weft::collision
