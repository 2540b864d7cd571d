// Morton ordering and the level sizes of the additive Schwarz hierarchy (weft/backend/schwarz_hierarchy.h).
#include "weft/backend/schwarz_hierarchy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "weft/error.h"

namespace weft {
namespace {

/// The bits of a 21-bit integer spread to every third bit of a 63-bit code.
std::uint64_t spread_bits(std::uint64_t v) {
    v &= 0x1FFFFFu;
    v = (v | v << 32) & 0x1F00000000FFFFull;
    v = (v | v << 16) & 0x1F0000FF0000FFull;
    v = (v | v << 8) & 0x100F00F00F00F00Full;
    v = (v | v << 4) & 0x10C30C30C30C30C3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
}

}  // namespace

SchwarzHierarchy build_schwarz_hierarchy(std::span<const Vec3d> rest, int max_levels) {
    if (max_levels < 1) throw Error("Schwarz hierarchy: max_levels = " + std::to_string(max_levels) + " (at least 1)");
    const std::size_t n = rest.size();
    if (n >= std::numeric_limits<std::uint32_t>::max())
        throw Error("Schwarz hierarchy: " + std::to_string(n) + " vertices do not fit 32-bit indices");
    SchwarzHierarchy h;
    h.vertex_count = static_cast<std::uint32_t>(n);
    Vec3d lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
    Vec3d hi = -1.0 * lo;
    for (const Vec3d& p : rest) {
        if (!math::is_finite(p)) throw Error("Schwarz hierarchy: a rest position is not finite");
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], p[k]);
            hi[k] = std::max(hi[k], p[k]);
        }
    }
    // One scale for all axes keeps cells cubic, so a run of 32 codes is a compact patch of a sheet.
    double extent = 0.0;
    for (int k = 0; k < 3; ++k) extent = std::max(extent, hi[k] - lo[k]);
    const double scale = extent > 0.0 ? double((1u << 21) - 1) / extent : 0.0;
    std::vector<std::uint64_t> code(n);
    for (std::size_t v = 0; v < n; ++v) {
        std::uint64_t c = 0;
        for (int k = 0; k < 3; ++k) {
            const auto q = static_cast<std::uint64_t>(std::floor((rest[v][k] - lo[k]) * scale));
            c |= spread_bits(q) << k;
        }
        code[v] = c;
    }
    h.order.resize(n);
    std::iota(h.order.begin(), h.order.end(), 0u);
    std::stable_sort(h.order.begin(), h.order.end(), [&](std::uint32_t a, std::uint32_t b) { return code[a] < code[b]; });
    h.rank.resize(n);
    for (std::uint32_t p = 0; p < n; ++p) h.rank[h.order[p]] = p;
    std::uint32_t nodes = h.vertex_count;
    h.level_nodes.push_back(nodes);
    while (nodes > SchwarzHierarchy::kDomainSize && h.levels() < max_levels) {
        nodes = (nodes + SchwarzHierarchy::kDomainSize - 1) >> SchwarzHierarchy::kDomainBits;
        h.level_nodes.push_back(nodes);
    }
    return h;
}

}  // namespace weft
