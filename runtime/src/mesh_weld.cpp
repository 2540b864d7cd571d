// Welding vertices by position: undoes the vertex splits an importer makes at UV and normal seams.
#include <cmath>
#include <algorithm>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "weft/error.h"
#include "weft/mesh.h"

namespace weft {
namespace {

struct Cell {
    std::int64_t x, y, z;
    bool operator==(const Cell&) const = default;
};

struct CellHash {
    std::size_t operator()(const Cell& c) const {
        // Teschner et al. 2003 spatial hash primes.
        return static_cast<std::size_t>((static_cast<std::uint64_t>(c.x) * 73856093ULL) ^
                                        (static_cast<std::uint64_t>(c.y) * 19349663ULL) ^
                                        (static_cast<std::uint64_t>(c.z) * 83492791ULL));
    }
};

}  // namespace

std::size_t weld_by_position(MeshData& mesh, double tolerance) {
    const std::string src = mesh.source.empty() ? std::string("mesh") : mesh.source;
    const std::size_t n = mesh.positions.size();
    if (n > 0xFFFFFFFEULL) throw Error(src + ": too many vertices to weld");
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (std::uint32_t v : mesh.triangles[t].v)
            if (v >= n)
                throw Error(src + ": triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                            " but the mesh has only " + std::to_string(n) + " vertices");
    if (!(tolerance >= 0.0) || !std::isfinite(tolerance))
        throw Error(src + ": weld tolerance must be a finite non-negative length (got " + std::to_string(tolerance) + ")");

    // Hash grid with cells of the tolerance: a vertex can only merge with representatives in its own
    // or the 26 neighbouring cells. Vertices are visited in index order and merge into the first
    // (lowest-index) representative within the tolerance, so the result does not depend on the hash
    // table's iteration order. With tolerance 0 only exact duplicates merge (cells of 1 m, distance 0).
    const double cell = tolerance > 0.0 ? tolerance : 1.0;
    constexpr double kMaxCell = 4.0e18;  // keeps the cell coordinates inside int64
    std::unordered_map<Cell, std::uint32_t, CellHash> head;  // cell → first representative in it
    head.reserve(n);
    std::vector<std::uint32_t> next(n, ~0U);  // chain of representatives sharing a cell
    std::vector<std::uint32_t> target(n);
    const double tol2 = tolerance * tolerance;
    std::size_t merged = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        target[i] = i;
        const Vec3d p = mesh.positions[i];
        double q[3] = {std::floor(p.x / cell), std::floor(p.y / cell), std::floor(p.z / cell)};
        if (!(std::abs(q[0]) < kMaxCell && std::abs(q[1]) < kMaxCell && std::abs(q[2]) < kMaxCell))
            continue;  // non-finite or absurdly far: never merged (cooking rejects non-finite input)
        const Cell c{static_cast<std::int64_t>(q[0]), static_cast<std::int64_t>(q[1]), static_cast<std::int64_t>(q[2])};
        std::uint32_t best = ~0U;
        for (std::int64_t dz = -1; dz <= 1; ++dz)
            for (std::int64_t dy = -1; dy <= 1; ++dy)
                for (std::int64_t dx = -1; dx <= 1; ++dx) {
                    const auto it = head.find({c.x + dx, c.y + dy, c.z + dz});
                    if (it == head.end()) continue;
                    for (std::uint32_t r = it->second; r != ~0U && r < best; r = next[r])
                        if (math::length_squared(mesh.positions[r] - p) <= tol2) best = r;
                }
        if (best != ~0U) {
            target[i] = best;
            ++merged;
            continue;
        }
        // A new representative. Chains are kept in ascending index order (appending the largest
        // index so far), which lets the search above stop at the first candidate beyond `best`.
        const auto [it, inserted] = head.try_emplace(c, i);
        if (!inserted) {
            std::uint32_t r = it->second;
            while (next[r] != ~0U) r = next[r];
            next[r] = i;
        }
    }

    // Remap triangles, then drop vertices no triangle references, keeping the survivors' order.
    for (Triangle& t : mesh.triangles)
        for (std::uint32_t& v : t.v) v = target[v];
    std::vector<std::uint32_t> compact(n, ~0U);
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t v : t.v) compact[v] = 0;
    std::uint32_t kept = 0;
    for (std::uint32_t i = 0; i < n; ++i)
        if (compact[i] == 0) {
            compact[i] = kept;
            mesh.positions[kept++] = mesh.positions[i];
        }
    mesh.positions.resize(kept);
    for (Triangle& t : mesh.triangles)
        for (std::uint32_t& v : t.v) v = compact[v];
    mesh.welded_vertices += merged;
    return n - kept;
}

double bounding_box_diagonal(const MeshData& mesh) {
    if (mesh.positions.empty()) return 0.0;
    Vec3d lo = mesh.positions.front(), hi = lo;
    for (const Vec3d& p : mesh.positions)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], p[k]);
            hi[k] = std::max(hi[k], p[k]);
        }
    return math::length(hi - lo);
}

}  // namespace weft
