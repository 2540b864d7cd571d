#pragma once
// Candidate pairs on the device are single 64-bit keys: the kind of the pair in one bit above the
// two primitive indices, packed in just the bits the mesh needs. Sorting the keys (one CUB radix sort,
// no values) therefore gives the CPU reference's order at once: every vertex–face pair before every
// edge–edge pair, each kind ordered by (first index, second index), exactly as
// weft::collision::BroadPhaseResult holds them. Host and device code (the narrow phase decodes keys
// in its kernels; the tests decode the downloaded list).

#include <bit>
#include <cstdint>
#include <string>

#include "weft/error.h"
#include "weft/math/host_device.h"

namespace weft::cuda::collision {

/// "No patch": a primitive with this patch id is never culled (weft::collision::kNoPatch).
inline constexpr std::uint32_t kNoPatch = 0xFFFFFFFFU;

/// "Not a pair": the key that pads the unused tail of a pair buffer; it sorts after every real key.
inline constexpr std::uint64_t kPadKey = ~std::uint64_t{0};

/// Bit layout of the pair keys of one mesh (vertex, edge and triangle counts).
///   vertex–face (v, t):   key = v << vf_low | t                 (bit `kind_bit` clear)
///   edge–edge (a, b):     key = 1 << kind_bit | a << ee_low | b  (a < b)
/// Bit kind_bit + 1 is clear in every real key and set in kPadKey, so the sort over the low
/// `sort_bits` bits puts padding last.
struct PairEncoding {
    std::uint32_t vf_low = 0;     ///< bits of a triangle index
    std::uint32_t ee_low = 0;     ///< bits of an edge index
    std::uint32_t kind_bit = 0;   ///< position of the kind bit
    std::uint32_t sort_bits = 0;  ///< bits the canonical sort looks at: kind_bit + 2

    [[nodiscard]] WEFT_HD std::uint64_t vf(std::uint32_t vertex, std::uint32_t triangle) const {
        return (static_cast<std::uint64_t>(vertex) << vf_low) | triangle;
    }
    [[nodiscard]] WEFT_HD std::uint64_t ee(std::uint32_t a, std::uint32_t b) const {
        return (std::uint64_t{1} << kind_bit) | (static_cast<std::uint64_t>(a) << ee_low) | b;
    }
    [[nodiscard]] WEFT_HD bool is_ee(std::uint64_t key) const { return ((key >> kind_bit) & 1U) != 0; }
    /// The vertex (vertex–face) or the lower edge (edge–edge).
    [[nodiscard]] WEFT_HD std::uint32_t first(std::uint64_t key) const {
        const std::uint64_t body = key & ((std::uint64_t{1} << kind_bit) - 1);
        return static_cast<std::uint32_t>(body >> (is_ee(key) ? ee_low : vf_low));
    }
    /// The triangle (vertex–face) or the higher edge (edge–edge).
    [[nodiscard]] WEFT_HD std::uint32_t second(std::uint64_t key) const {
        const std::uint32_t low = is_ee(key) ? ee_low : vf_low;
        return static_cast<std::uint32_t>(key & ((std::uint64_t{1} << low) - 1));
    }
};

/// Bits that hold every index below `count` (0 for count ≤ 1).
[[nodiscard]] constexpr std::uint32_t index_bits(std::uint64_t count) {
    return count <= 1 ? 0U : static_cast<std::uint32_t>(std::bit_width(count - 1));
}

/// The encoding for a mesh. Throws weft::Error when a key would not fit in 64 bits (vertices ×
/// triangles beyond 2^62: far beyond any device's memory).
[[nodiscard]] inline PairEncoding make_pair_encoding(std::uint64_t vertices, std::uint64_t edges,
                                                     std::uint64_t triangles) {
    PairEncoding e;
    e.vf_low = index_bits(triangles);
    e.ee_low = index_bits(edges);
    const std::uint32_t vf_bits = index_bits(vertices) + e.vf_low;
    const std::uint32_t ee_bits = 2 * e.ee_low;
    e.kind_bit = vf_bits > ee_bits ? vf_bits : ee_bits;
    e.sort_bits = e.kind_bit + 2;
    if (e.sort_bits > 64)
        throw Error("GPU broad phase: pair keys need " + std::to_string(e.sort_bits) + " bits (" +
                    std::to_string(vertices) + " vertices, " + std::to_string(edges) + " edges, " +
                    std::to_string(triangles) + " triangles); at most 64 fit");
    return e;
}

/// A sorted candidate list on the device, as the broad phase leaves it for the narrow phase. Valid
/// until the broad phase runs again.
struct GpuPairList {
    const unsigned long long* keys = nullptr;  ///< [0, count) sorted keys, then kPadKey up to `capacity`
    /// Device counters: count[0] = pairs found (may exceed `capacity` after an overflow; readers clamp),
    /// count[1] = vertex–face pairs among them (they come first).
    const std::uint32_t* count = nullptr;
    std::uint32_t capacity = 0;  ///< host: slots in `keys`, what a kernel over the list is launched for
    PairEncoding encoding;
};

}  // namespace weft::cuda::collision
