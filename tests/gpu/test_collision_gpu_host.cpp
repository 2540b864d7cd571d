// Host-side rules of the GPU collision detection (cuda/src/collision/), no device needed: the pair key
// encoding gives the CPU reference's pair order and puts padding last, the thickness is rounded up to
// float, capacities grow with headroom, the sort width covers the keys, and the shared constants
// equal the CPU's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "collision/broad_phase.h"
#include "collision/broad_phase_gpu.h"
#include "collision/pair_keys.h"
#include "weft/error.h"

namespace weft::cuda::collision {
namespace {

static_assert(kNoPatch == weft::collision::kNoPatch);
static_assert(kMaxCellsPerPrimitive == weft::collision::BroadPhase::kMaxCellsPerPrimitive);

TEST(CollisionGpuHost, IndexBits) {
    EXPECT_EQ(index_bits(0), 0U);
    EXPECT_EQ(index_bits(1), 0U);
    EXPECT_EQ(index_bits(2), 1U);
    EXPECT_EQ(index_bits(1024), 10U);
    EXPECT_EQ(index_bits(1025), 11U);
}

TEST(CollisionGpuHost, PairKeysRoundTripAndSortLikeTheCpu) {
    struct Mesh {
        std::uint64_t n, e, t;
    };
    for (const Mesh m : {Mesh{1, 1, 1}, Mesh{3, 3, 1}, Mesh{100489, 300000, 199712}, Mesh{1u << 20, 3u << 20, 2u << 20},
                         Mesh{5, 4000000, 2}}) {
        const PairEncoding enc = make_pair_encoding(m.n, m.e, m.t);
        EXPECT_LE(enc.sort_bits, 64U);
        std::mt19937_64 rng(m.n + m.e);
        std::vector<std::uint64_t> keys;
        std::vector<std::pair<int, std::pair<std::uint32_t, std::uint32_t>>> want;  // (kind, (first, second))
        for (int i = 0; i < 2000; ++i) {
            const auto v = static_cast<std::uint32_t>(rng() % m.n), t = static_cast<std::uint32_t>(rng() % m.t);
            auto a = static_cast<std::uint32_t>(rng() % m.e), b = static_cast<std::uint32_t>(rng() % m.e);
            if (a > b) std::swap(a, b);
            const std::uint64_t kv = enc.vf(v, t), ke = enc.ee(a, b);
            EXPECT_FALSE(enc.is_ee(kv));
            EXPECT_TRUE(enc.is_ee(ke));
            EXPECT_EQ(enc.first(kv), v);
            EXPECT_EQ(enc.second(kv), t);
            EXPECT_EQ(enc.first(ke), a);
            EXPECT_EQ(enc.second(ke), b);
            // Real keys use only the sorted bits; the pad key is above all of them there.
            if (enc.sort_bits < 64) {
                EXPECT_LT(kv >> enc.sort_bits, 1U);
                EXPECT_LT(ke >> enc.sort_bits, 1U);
            }
            const std::uint64_t low = enc.sort_bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << enc.sort_bits) - 1;
            EXPECT_LT(kv & low, kPadKey & low);
            EXPECT_LT(ke & low, kPadKey & low);
            keys.push_back(kv);
            keys.push_back(ke);
            want.push_back({0, {v, t}});
            want.push_back({1, {a, b}});
        }
        // Key order = (vertex-face first, then by first index, then by second): the CPU's order.
        std::sort(keys.begin(), keys.end());
        std::sort(want.begin(), want.end());
        ASSERT_EQ(keys.size(), want.size());
        for (std::size_t i = 0; i < keys.size(); ++i) {
            EXPECT_EQ(enc.is_ee(keys[i]) ? 1 : 0, want[i].first);
            EXPECT_EQ(enc.first(keys[i]), want[i].second.first);
            EXPECT_EQ(enc.second(keys[i]), want[i].second.second);
        }
    }
    EXPECT_THROW((void)make_pair_encoding(std::uint64_t{1} << 32, std::uint64_t{1} << 32, std::uint64_t{1} << 32), Error);
}

TEST(CollisionGpuHost, ThicknessRoundsUpToFloat) {
    for (double t : {0.0, 0.005, 0.1, 1.0 / 3.0, 1e-30, 3.0e38, 0.004}) {
        const float f = float_at_least(t);
        EXPECT_GE(static_cast<double>(f), t);
        // The smallest such float: the one below is below t.
        if (f > 0.0F) {
            EXPECT_LT(static_cast<double>(std::nextafter(f, 0.0F)), t);
        }
    }
    EXPECT_EQ(float_at_least(0.5), 0.5F);  // exactly representable: unchanged
}

TEST(CollisionGpuHost, CapacitiesGrowWithHeadroomAndSortWidthsCoverTheKeys) {
    for (std::size_t needed : {std::size_t{0}, std::size_t{1}, std::size_t{1000}, std::size_t{123456789}}) {
        const std::size_t c = grown_capacity(needed);
        EXPECT_GE(c, needed + needed / 4);
        EXPECT_GE(c, 1024U);
        EXPECT_EQ(c % 1024, 0U);
    }
    for (std::uint32_t bits = 0; bits <= 63; ++bits) {
        const int w = entry_sort_bits(bits);
        EXPECT_GE(w, static_cast<int>(bits));
        EXPECT_EQ(w % 8, 0);
        EXPECT_LE(w, 64);
        EXPECT_LT(w, static_cast<int>(bits) + 8 + (bits == 0 ? 8 : 0));
    }
}

}  // namespace
}  // namespace weft::cuda::collision
