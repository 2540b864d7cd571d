#include "collision/intersection_check.h"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "weft/error.h"
#include "weft/physics/triangle_intersection.h"

#include "deterministic_parallel.h"

namespace weft::collision {
namespace {

// Cell coordinates take 21 bits per axis in a packed 64-bit key.
constexpr int kCoordBits = 21;
constexpr std::uint32_t kMaxCoord = (1u << kCoordBits) - 1;
// A triangle whose box overlaps more cells than this is tested against all others directly, so that
// one huge (or exploded) triangle cannot flood the grid. The result is the same either way.
constexpr std::uint64_t kMaxCellsPerTriangle = 1024;

struct Box {
    Vec3d lo, hi;
};

struct Entry {
    std::uint64_t key;  // packed cell coordinates
    std::uint32_t tri;
};

enum class State : std::uint8_t { Hashed, Oversized, NonFinite };

// Work one chunk of the narrow phase did; merged in chunk order.
struct Partial {
    std::size_t count = 0;
    std::size_t candidates = 0;
    std::vector<IntersectingPair> pairs;  // the smallest found so far, trimmed now and then
};

std::uint64_t pack(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return std::uint64_t{x} | (std::uint64_t{y} << kCoordBits) | (std::uint64_t{z} << (2 * kCoordBits));
}

// Cell coordinate of x. Monotone non-decreasing in x (subtraction, multiplication by a positive
// number, floor and clamping all are), which the one-cell-per-pair rule relies on.
std::uint32_t cell_coord(double x, double origin, double inv_cell) {
    const double c = std::floor((x - origin) * inv_cell);
    if (!(c > 0.0)) return 0;
    if (c >= double{kMaxCoord}) return kMaxCoord;
    return static_cast<std::uint32_t>(c);
}

bool boxes_overlap(const Box& a, const Box& b) {
    return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z &&
           b.lo.z <= a.hi.z;
}

bool share_vertex(const Triangle& a, const Triangle& b) {
    for (const std::uint32_t u : a.v)
        for (const std::uint32_t w : b.v)
            if (u == w) return true;
    return false;
}

// Keeps `pairs` from growing without bound: only the `keep` smallest can end up in the report.
void trim_pairs(std::vector<IntersectingPair>& pairs, std::size_t keep) {
    if (pairs.size() <= keep) return;
    std::nth_element(pairs.begin(), pairs.begin() + static_cast<std::ptrdiff_t>(keep), pairs.end());
    pairs.resize(keep);
}

}  // namespace

IntersectionReport check_intersections(std::span<const Vec3d> positions, std::span<const Triangle> triangles,
                                       const IntersectionCheckOptions& options) {
    const std::size_t nv = positions.size(), nt = triangles.size();
    if (nt >= std::numeric_limits<std::uint32_t>::max())
        throw Error("intersection check: more than 2^32 - 1 triangles (" + std::to_string(nt) + ")");
    for (std::size_t t = 0; t < nt; ++t)
        for (const std::uint32_t v : triangles[t].v)
            if (v >= nv)
                throw Error("intersection check: triangle " + std::to_string(t) + " uses vertex " + std::to_string(v) +
                            " but there are " + std::to_string(nv) + " positions");
    if (!std::isfinite(options.cell_size) || options.cell_size < 0.0)
        throw Error("intersection check: cell size must be finite and non-negative");

    IntersectionReport report;
    const std::size_t keep = options.max_examples;

    // ---- Boxes ----------------------------------------------------------------------------------
    std::vector<Box> box(nt);
    std::vector<State> state(nt, State::Hashed);
    const double inf = std::numeric_limits<double>::infinity();
    Vec3d origin{inf, inf, inf}, top{-inf, -inf, -inf};
    std::vector<double> extent;
    extent.reserve(nt);
    for (std::size_t t = 0; t < nt; ++t) {
        const Vec3d& p0 = positions[triangles[t].v[0]];
        const Vec3d& p1 = positions[triangles[t].v[1]];
        const Vec3d& p2 = positions[triangles[t].v[2]];
        if (!physics::is_finite(p0) || !physics::is_finite(p1) || !physics::is_finite(p2)) {
            state[t] = State::NonFinite;
            ++report.nonfinite_triangles;
            continue;
        }
        Box& b = box[t];
        for (int k = 0; k < 3; ++k) {
            b.lo[k] = std::min(p0[k], std::min(p1[k], p2[k]));
            b.hi[k] = std::max(p0[k], std::max(p1[k], p2[k]));
            origin[k] = std::min(origin[k], b.lo[k]);
            top[k] = std::max(top[k], b.hi[k]);
        }
        extent.push_back(std::max(b.hi.x - b.lo.x, std::max(b.hi.y - b.lo.y, b.hi.z - b.lo.z)));
    }
    report.triangles_checked = nt - report.nonfinite_triangles;
    if (report.triangles_checked < 2) return report;

    // ---- Grid -----------------------------------------------------------------------------------
    double cell = options.cell_size;
    if (cell == 0.0) {
        // The median, not the mean: a few huge triangles must not make every cell huge. Collapsed
        // triangles (zero extent) are left out, or a mesh full of them would get needle-sized cells.
        // The k-th smallest value is unique, so nth_element's internal order does not matter.
        extent.erase(std::remove(extent.begin(), extent.end(), 0.0), extent.end());
        if (!extent.empty()) {
            const auto mid = extent.begin() + static_cast<std::ptrdiff_t>(extent.size() / 2);
            std::nth_element(extent.begin(), mid, extent.end());
            cell = *mid;
        }
    }
    // At most 2^21 cells per axis (the scene's extent may overflow to infinity: then 1/cell is 0 and
    // everything falls into cell 0, still correct).
    const Vec3d span = top - origin;
    const double scene = std::max(span.x, std::max(span.y, span.z));
    cell = std::max(cell, scene / double{kMaxCoord - 1});
    if (!(cell > 0.0)) cell = 1.0;  // every triangle is one and the same point: any size will do
    report.cell_size = cell;
    const double inv_cell = 1.0 / cell;

    std::vector<std::uint32_t> cell_lo(3 * nt), cell_hi(3 * nt);
    std::vector<std::size_t> offset(nt + 1, 0);
    std::vector<std::uint32_t> oversized;
    for (std::size_t t = 0; t < nt; ++t) {
        if (state[t] == State::NonFinite) continue;
        std::uint64_t cells = 1;
        for (int k = 0; k < 3; ++k) {
            cell_lo[3 * t + std::size_t(k)] = cell_coord(box[t].lo[k], origin[k], inv_cell);
            cell_hi[3 * t + std::size_t(k)] = cell_coord(box[t].hi[k], origin[k], inv_cell);
            cells *= cell_hi[3 * t + std::size_t(k)] - cell_lo[3 * t + std::size_t(k)] + 1;  // < 2^63
        }
        if (cells > kMaxCellsPerTriangle) {
            state[t] = State::Oversized;
            oversized.push_back(static_cast<std::uint32_t>(t));
            continue;
        }
        offset[t] = static_cast<std::size_t>(cells);
    }
    report.oversized_triangles = oversized.size();
    std::size_t total = 0;
    for (std::size_t t = 0; t < nt; ++t) {
        const std::size_t count = offset[t];
        offset[t] = total;
        total += count;
    }
    offset[nt] = total;

    std::vector<Entry> entries(total);
    parallel_chunks(nt, [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t < end; ++t) {
            if (state[t] != State::Hashed) continue;
            std::size_t at = offset[t];
            const std::uint32_t* lo = &cell_lo[3 * t];
            const std::uint32_t* hi = &cell_hi[3 * t];
            for (std::uint32_t z = lo[2]; z <= hi[2]; ++z)
                for (std::uint32_t y = lo[1]; y <= hi[1]; ++y)
                    for (std::uint32_t x = lo[0]; x <= hi[0]; ++x)
                        entries[at++] = Entry{pack(x, y, z), static_cast<std::uint32_t>(t)};
        }
    });
    // (key, tri) is unique, so the order is total and the sort deterministic.
    tbb::parallel_sort(entries.begin(), entries.end(),
                       [](const Entry& a, const Entry& b) { return a.key != b.key ? a.key < b.key : a.tri < b.tri; });
    std::vector<std::size_t> run_start;
    for (std::size_t i = 0; i < total; ++i)
        if (i == 0 || entries[i].key != entries[i - 1].key) run_start.push_back(i);
    const std::size_t runs = run_start.size();
    run_start.push_back(total);

    // ---- Narrow phase ---------------------------------------------------------------------------
    const auto test_pair = [&](std::uint32_t i, std::uint32_t j, Partial& out) {
        const Triangle& ti = triangles[i];
        const Triangle& tj = triangles[j];
        if (share_vertex(ti, tj)) return;
        ++out.candidates;
        const Vec3d a[3] = {positions[ti.v[0]], positions[ti.v[1]], positions[ti.v[2]]};
        const Vec3d b[3] = {positions[tj.v[0]], positions[tj.v[1]], positions[tj.v[2]]};
        if (!physics::triangles_intersect(a, b)) return;
        ++out.count;
        out.pairs.push_back({std::min(i, j), std::max(i, j)});
        if (out.pairs.size() >= 2 * keep + 256) trim_pairs(out.pairs, keep);
    };

    const std::size_t chunks = (runs + kParallelChunk - 1) / kParallelChunk;
    std::vector<Partial> partial(chunks + 1);  // the last one is for the oversized triangles
    parallel_chunks(runs, [&](std::size_t begin, std::size_t end) {
        Partial& out = partial[begin / kParallelChunk];
        for (std::size_t r = begin; r < end; ++r) {
            const std::size_t s = run_start[r], e = run_start[r + 1];
            const std::uint64_t key = entries[s].key;
            for (std::size_t p = s; p < e; ++p) {
                const std::uint32_t i = entries[p].tri;
                for (std::size_t q = p + 1; q < e; ++q) {
                    const std::uint32_t j = entries[q].tri;
                    if (!boxes_overlap(box[i], box[j])) continue;
                    // Test the pair only in the cell of the low corner of the boxes' intersection:
                    // cell_coord is monotone, so that cell is the max of the two low cells per axis,
                    // and it lies in both triangles' ranges.
                    const std::uint64_t owner =
                        pack(std::max(cell_lo[3 * i], cell_lo[3 * j]), std::max(cell_lo[3 * i + 1], cell_lo[3 * j + 1]),
                             std::max(cell_lo[3 * i + 2], cell_lo[3 * j + 2]));
                    if (owner != key) continue;
                    test_pair(i, j, out);
                }
            }
        }
    });

    // Oversized triangles against every other checked triangle (against an oversized one only once).
    if (!oversized.empty()) {
        std::vector<Partial> over(oversized.size());
        parallel_chunks(oversized.size(), [&](std::size_t begin, std::size_t end) {
            for (std::size_t o = begin; o < end; ++o) {
                const std::uint32_t i = oversized[o];
                for (std::size_t t = 0; t < nt; ++t) {
                    const auto j = static_cast<std::uint32_t>(t);
                    if (j == i || state[t] == State::NonFinite) continue;
                    if (state[t] == State::Oversized && j < i) continue;
                    if (!boxes_overlap(box[i], box[t])) continue;
                    test_pair(i, j, over[o]);
                }
            }
        });
        Partial& out = partial[chunks];
        for (Partial& p : over) {
            out.count += p.count;
            out.candidates += p.candidates;
            out.pairs.insert(out.pairs.end(), p.pairs.begin(), p.pairs.end());
            trim_pairs(out.pairs, keep);
        }
    }

    for (Partial& p : partial) {
        report.intersecting_pairs += p.count;
        report.candidate_pairs += p.candidates;
        trim_pairs(p.pairs, keep);
        report.examples.insert(report.examples.end(), p.pairs.begin(), p.pairs.end());
    }
    std::sort(report.examples.begin(), report.examples.end());
    if (report.examples.size() > keep) report.examples.resize(keep);
    return report;
}

}  // namespace weft::collision
