// Sorted spatial hash over swept bounds (docs/methods.md §4). Cells are keyed by their exact packed
// coordinates rather than a hash of them, so two different cells never share a key and no pair is
// lost or invented by a hash collision; the sort plays the part of the hash table.
#include "collision/broad_phase.h"

#include "collision/radix_sort.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <string>

#include "weft/error.h"

#include "collision/buffer_trim.h"
#include "deterministic_parallel.h"
#include "weft/physics/vec.h"

namespace weft::collision {
namespace {

// 21 bits per axis fit three coordinates in one 64-bit key. Coordinates are clamped to this range:
// a bound beyond it lands in the boundary cell with every other such bound, which keeps the search
// exact (pairs are still tested box against box) and only costs time in absurdly large scenes.
constexpr int kBits = 21;
constexpr std::uint64_t kMask = (std::uint64_t{1} << kBits) - 1;

constexpr std::uint8_t kHashed = 0, kNonFinite = 1, kOversized = 2;
/// With BroadPhaseInput::vertex_changed: a primitive with no flagged vertex whose bound reaches no
/// changed primitive's region cell cannot be in a pair, and is not hashed.
constexpr std::uint8_t kUnneeded = 3;
/// The changed primitives' region: a coarse grid of kRegionCells per axis over the scene's bounds.
constexpr long kRegionCells = 32;
/// A bound over more region cells than this counts as covering them all (marks, or touches, all).
constexpr long kRegionCellsPerBound = 4096;

/// Packs three cell coordinates into one key, each axis in just the bits its range needs, so that
/// the radix sort makes as few passes as the scene's extent in cells allows.
struct Packing {
    int shift[3]{};
    std::uint64_t mask[3]{};
    int bits = 0;  ///< significant bits of a key

    /// `top`: the largest coordinate on each axis.
    explicit Packing(const std::uint64_t top[3]) {
        for (int k = 0; k < 3; ++k) {
            const auto width = static_cast<int>(std::bit_width(top[k]));
            shift[k] = bits;
            mask[k] = (std::uint64_t{1} << width) - 1;
            bits += width;
        }
    }
    [[nodiscard]] std::uint64_t pack(std::uint64_t x, std::uint64_t y, std::uint64_t z) const {
        return (x << shift[0]) | (y << shift[1]) | (z << shift[2]);
    }
    [[nodiscard]] std::uint64_t coord(std::uint64_t key, int axis) const { return (key >> shift[axis]) & mask[axis]; }
    /// Per-axis maximum of two packed coordinates.
    [[nodiscard]] std::uint64_t max(std::uint64_t a, std::uint64_t b) const {
        return pack(std::max(coord(a, 0), coord(b, 0)), std::max(coord(a, 1), coord(b, 1)),
                    std::max(coord(a, 2), coord(b, 2)));
    }
};

/// Cell coordinate of `x` along one axis. Monotone in x, which the dedup rule relies on.
std::uint64_t cell_coord(double x, double origin, double inv_cell) {
    const double c = std::floor((x - origin) * inv_cell);
    // Clamp in double before converting: the cast of an out-of-range double is undefined.
    return static_cast<std::uint64_t>(std::clamp(c, 0.0, static_cast<double>(kMask)));
}

/// Closed boxes: touching bounds overlap. False whenever a coordinate is NaN.
template <typename Box>
bool overlap(const Box& a, const Box& b) {
    return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z &&
           b.lo.z <= a.hi.z;
}

Vec3d min3(Vec3d a, Vec3d b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
Vec3d max3(Vec3d a, Vec3d b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }

template <typename Box>
bool finite_box(const Box& b) {
    return physics::is_finite(b.lo) && physics::is_finite(b.hi);
}

/// A vertex's bound: the box around x0 and x1 (in the moving frame: x1 − shift), grown by th; NaN
/// where a position is not finite or the box overflows. find and clean_pairs_within_last share it, so the
/// two see the same bits.
template <typename Box>
void vertex_bound(Box& box, const Vec3d& x0, const Vec3d& x1_world, const Vec3d& shift, double th) {
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    // std::min would silently drop a NaN, so a non-finite position poisons the whole box.
    if (!physics::is_finite(x0) || !physics::is_finite(x1_world)) {
        box.lo = box.hi = {nan, nan, nan};
        return;
    }
    const Vec3d x1 = x1_world - shift;  // in the moving frame (BroadPhaseInput::frame_motion)
    box.lo = min3(x0, x1) - Vec3d{th, th, th};
    box.hi = max3(x0, x1) + Vec3d{th, th, th};
    if (!finite_box(box)) box.lo = box.hi = {nan, nan, nan};  // overflowed
}

/// An edge's or triangle's bound: the union of its vertices' bounds (NaN if any is).
template <typename Box>
void united_bound(Box& box, std::span<const Box> vertex_bounds, std::span<const std::uint32_t> vertices) {
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    box = vertex_bounds[vertices[0]];
    bool finite = finite_box(box);
    for (std::size_t k = 1; k < vertices.size(); ++k) {
        const Box& vb = vertex_bounds[vertices[k]];
        finite = finite && finite_box(vb);
        box.lo = min3(box.lo, vb.lo);
        box.hi = max3(box.hi, vb.hi);
    }
    if (!finite) box.lo = box.hi = {nan, nan, nan};
}

bool shares_vertex(const Edge& a, const Edge& b) {
    return a.v[0] == b.v[0] || a.v[0] == b.v[1] || a.v[1] == b.v[0] || a.v[1] == b.v[1];
}
bool is_corner(std::uint32_t v, const Triangle& t) { return v == t.v[0] || v == t.v[1] || v == t.v[2]; }

constexpr std::uint32_t kNoCloth = std::numeric_limits<std::uint32_t>::max();

}  // namespace

std::vector<Edge> build_edges(std::span<const Triangle> triangles) {
    std::vector<Edge> edges;
    edges.reserve(3 * triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t) {
        const Triangle& tri = triangles[t];
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = tri.v[k], b = tri.v[(k + 1) % 3];
            if (a == b)
                throw Error("build_edges: triangle " + std::to_string(t) + " repeats vertex " + std::to_string(a));
            edges.push_back({{std::min(a, b), std::max(a, b)}});
        }
    }
    const auto less = [](const Edge& p, const Edge& q) { return p.v[0] != q.v[0] ? p.v[0] < q.v[0] : p.v[1] < q.v[1]; };
    const auto same = [](const Edge& p, const Edge& q) { return p.v[0] == q.v[0] && p.v[1] == q.v[1]; };
    std::sort(edges.begin(), edges.end(), less);
    edges.erase(std::unique(edges.begin(), edges.end(), same), edges.end());
    return edges;
}

void BroadPhase::find(const BroadPhaseInput& in, BroadPhaseResult& out) {
    last_.reusable = false;  // until this call has finished
    const std::size_t n = in.x0.size(), ne = in.edges.size(), nt = in.triangles.size();
    if (in.x1.size() != n)
        throw Error("broad phase: " + std::to_string(n) + " start positions but " + std::to_string(in.x1.size()) +
                    " end positions");
    if (n + ne + nt >= std::numeric_limits<std::uint32_t>::max())
        throw Error("broad phase: more than 2^32 vertices, edges and triangles together");
    if (!std::isfinite(in.thickness) || in.thickness < 0.0)
        throw Error("broad phase: thickness must be finite and non-negative (got " + std::to_string(in.thickness) +
                    ")");
    if (!std::isfinite(in.cell_size) || in.cell_size < 0.0)
        throw Error("broad phase: cell size must be finite and non-negative (got " + std::to_string(in.cell_size) +
                    ")");
    if (!physics::is_finite(in.frame_motion)) throw Error("broad phase: the frame's motion is not finite");
    for (std::size_t t = 0; t < nt; ++t)
        for (std::uint32_t v : in.triangles[t].v)
            if (v >= n) throw Error("broad phase: triangle " + std::to_string(t) + " uses vertex " + std::to_string(v));
    for (std::size_t e = 0; e < ne; ++e)
        for (std::uint32_t v : in.edges[e].v)
            if (v >= n) throw Error("broad phase: edge " + std::to_string(e) + " uses vertex " + std::to_string(v));
    const bool padded = !in.vertex_padding.empty();
    if (!in.vertex_changed.empty() && in.vertex_changed.size() != n)
        throw Error("broad phase: " + std::to_string(in.vertex_changed.size()) + " changed-vertex flags for " +
                    std::to_string(n) + " vertices");
    if (padded && in.vertex_padding.size() != n)
        throw Error("broad phase: " + std::to_string(in.vertex_padding.size()) + " vertex paddings for " +
                    std::to_string(n) + " vertices");
    for (std::size_t i = 0; padded && i < n; ++i)
        if (!std::isfinite(in.vertex_padding[i]) || in.vertex_padding[i] < 0.0)
            throw Error("broad phase: vertex " + std::to_string(i) + " has padding " +
                        std::to_string(in.vertex_padding[i]) + " (must be finite and non-negative)");
    const bool filter_cloth = !in.self_pairs;
    const bool filter_kinematic =
        in.first_kinematic_group != std::numeric_limits<std::uint32_t>::max() && !in.triangle_cloth.empty();
    if ((filter_cloth || filter_kinematic) && !in.triangle_cloth.empty() && in.triangle_cloth.size() != nt)
        throw Error("broad phase: " + std::to_string(in.triangle_cloth.size()) + " triangle cloth ids for " +
                    std::to_string(nt) + " triangles");

    // Culling is on when any patch list is given; then all three must match the primitives.
    const bool cull = !in.vertex_patch.empty() || !in.edge_patch.empty() || !in.triangle_patch.empty();
    if (cull && (in.vertex_patch.size() != n || in.edge_patch.size() != ne || in.triangle_patch.size() != nt))
        throw Error("broad phase: patch ids for " + std::to_string(in.vertex_patch.size()) + " vertices, " +
                    std::to_string(in.edge_patch.size()) + " edges and " + std::to_string(in.triangle_patch.size()) +
                    " triangles; expected " + std::to_string(n) + ", " + std::to_string(ne) + " and " +
                    std::to_string(nt));

    const std::size_t edge0 = n, tri0 = n + ne, prims = n + ne + nt;
    const auto edge_of = [&](std::uint32_t p) -> const Edge& { return in.edges[p - edge0]; };
    const auto triangle_of = [&](std::uint32_t p) -> const Triangle& { return in.triangles[p - tri0]; };

    // ---- Cloth of each primitive, for the optional cloth–cloth and kinematic filters --------------
    if (filter_cloth || filter_kinematic) {
        // A vertex takes the cloth of the first triangle that uses it (a vertex belongs to one cloth).
        vertex_cloth_.assign(n, in.triangle_cloth.empty() ? 0U : kNoCloth);
        if (!in.triangle_cloth.empty())
            for (std::size_t t = 0; t < nt; ++t)
                for (std::uint32_t v : in.triangles[t].v)
                    if (vertex_cloth_[v] == kNoCloth) vertex_cloth_[v] = in.triangle_cloth[t];
    }
    const auto cloth_of = [&](std::uint32_t p) -> std::uint32_t {
        if (p < edge0) return vertex_cloth_[p];
        if (p < tri0) return vertex_cloth_[edge_of(p).v[0]];
        return in.triangle_cloth.empty() ? 0U : in.triangle_cloth[p - tri0];
    };
    // True when the pair must be dropped: both primitives in one cloth (without self pairs), or both
    // in mesh colliders (BroadPhaseInput::first_kinematic_group).
    const auto filtered = [&](std::uint32_t a, std::uint32_t b) {
        if (!filter_cloth && !filter_kinematic) return false;
        const std::uint32_t ca = cloth_of(a), cb = cloth_of(b);
        if (filter_kinematic && ca != kNoCloth && cb != kNoCloth && ca >= in.first_kinematic_group &&
            cb >= in.first_kinematic_group)
            return true;
        return filter_cloth && ca != kNoCloth && ca == cb;
    };
    // Where the mesh colliders' occupants of a cell start: they come last among the occupants of their
    // kind (their ids follow the cloth's, and the culled order puts their kNoPatch last), so pairs
    // among them can be skipped by range instead of tested and filtered one by one. Only a speed-up:
    // a kinematic occupant before that point is still dropped by `filtered`.
    const auto kinematic_from = [&](const auto& prim_at, std::size_t begin, std::size_t end) {
        if (!filter_kinematic) return end;
        std::size_t k = end;
        while (k > begin) {
            const std::uint32_t c = cloth_of(prim_at(k - 1));
            if (c == kNoCloth || c < in.first_kinematic_group) break;
            --k;
        }
        return k;
    };

    // Patch of each primitive for the optional culling (only read when `cull`).
    const auto patch_of = [&](std::uint32_t p) -> std::uint32_t {
        if (p < edge0) return in.vertex_patch[p];
        if (p < tri0) return in.edge_patch[p - edge0];
        return in.triangle_patch[p - tri0];
    };
    // True when the pair lies inside one self-collision-free patch.
    const auto same_patch = [&](std::uint32_t a, std::uint32_t b) {
        if (!cull) return false;
        const std::uint32_t pa = patch_of(a);
        return pa != kNoPatch && pa == patch_of(b);
    };

    // Which primitives have a flagged vertex (BroadPhaseInput::vertex_changed): a pair is formed
    // only where one of its two has.
    const bool only_changed = !in.vertex_changed.empty();
    if (only_changed) {
        changed_.resize(prims);
        parallel_chunks(prims, [&](std::size_t b, std::size_t e) {
            for (std::size_t p = b; p < e; ++p) {
                const auto& ch = in.vertex_changed;
                if (p < edge0) {
                    changed_[p] = ch[p] != 0;
                } else if (p < tri0) {
                    const Edge& edge = in.edges[p - edge0];
                    changed_[p] = (ch[edge.v[0]] | ch[edge.v[1]]) != 0;
                } else {
                    const Triangle& t = in.triangles[p - tri0];
                    changed_[p] = (ch[t.v[0]] | ch[t.v[1]] | ch[t.v[2]]) != 0;
                }
            }
        });
    }
    const auto unchanged = [&](std::uint32_t a, std::uint32_t b) { return only_changed && !changed_[a] && !changed_[b]; };

    // ---- Bounds ---------------------------------------------------------------------------------
    // Edge and triangle bounds are unions of their vertices' inflated bounds: min(a−t, b−t) equals
    // min(a, b)−t exactly (rounding is monotone), so this is the same box as inflating the union.
    box_.resize(prims);
    state_.resize(prims);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    parallel_chunks(n, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) vertex_bound(box_[i], in.x0[i], in.x1[i], in.frame_motion, in.thickness);
    });
    const std::span<const Box> vertex_bounds(box_.data(), n);
    const auto unite = [&](Box& box, std::span<const std::uint32_t> vertices) { united_bound(box, vertex_bounds, vertices); };
    // With padding, a primitive grows by the largest padding of its vertices: united from the
    // unpadded vertex bounds first, the vertices' own padding last.
    const auto pad = [&](Box& box, double p) {
        box.lo = box.lo - Vec3d{p, p, p};
        box.hi = box.hi + Vec3d{p, p, p};
        if (!finite_box(box)) box.lo = box.hi = {nan, nan, nan};
    };
    const auto largest_padding = [&](std::span<const std::uint32_t> vertices) {
        double p = 0.0;
        for (const std::uint32_t v : vertices) p = std::max(p, in.vertex_padding[v]);
        return p;
    };
    parallel_chunks(ne, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            unite(box_[edge0 + i], in.edges[i].v);
            if (padded) pad(box_[edge0 + i], largest_padding(in.edges[i].v));
        }
    });
    parallel_chunks(nt, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            unite(box_[tri0 + i], in.triangles[i].v);
            if (padded) pad(box_[tri0 + i], largest_padding(in.triangles[i].v));
        }
    });
    if (padded) {
        parallel_chunks(n, [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i)
                if (finite_box(box_[i])) pad(box_[i], in.vertex_padding[i]);
        });
    }

    // ---- Grid: origin and cell size ---------------------------------------------------------------
    // Unpadded, every bound lies inside the union of the vertex bounds, so the vertices give the
    // origin; with padding an edge or triangle may reach further than its vertices' own bounds.
    Vec3d origin{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                 std::numeric_limits<double>::infinity()};
    Vec3d top = -origin;
    for (std::size_t i = 0; i < (padded ? prims : n); ++i) {
        if (!finite_box(box_[i])) continue;
        origin = min3(origin, box_[i].lo);
        top = max3(top, box_[i].hi);
    }
    double cell = in.cell_size;
    if (cell == 0.0) {
        // The median rather than the mean: one exploding vertex must not blow every cell up to the
        // size of its bound (a mean over 300K edges moves 30 % for one 1 km edge among 1 cm ones).
        extent_.resize(ne);
        parallel_chunks(ne, [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i) {
                const Box& box = box_[edge0 + i];
                const Vec3d d = box.hi - box.lo;
                extent_[i] = finite_box(box) ? std::max(d.x, std::max(d.y, d.z)) : nan;
            }
        });
        extent_.erase(std::remove_if(extent_.begin(), extent_.end(), [](double x) { return std::isnan(x); }),
                      extent_.end());
        if (!extent_.empty()) {
            // The k-th smallest value is unique, so nth_element's internal order does not matter.
            const auto mid = extent_.begin() + static_cast<std::ptrdiff_t>(extent_.size() / 2);
            std::nth_element(extent_.begin(), mid, extent_.end());
            cell = *mid;
        }
    }
    if (!(cell > 0.0) || !std::isfinite(cell)) {
        // No edges, or all of them points: any positive size is correct; a scene-sized cell is cheap.
        const Vec3d d = top - origin;
        cell = std::max(d.x, std::max(d.y, d.z));
        if (!(cell > 0.0) || !std::isfinite(cell)) cell = 1.0;
    }
    const double inv_cell = 1.0 / cell;
    std::uint64_t top_cell[3] = {};
    if (origin.x <= top.x)  // some vertex is finite
        for (int k = 0; k < 3; ++k) top_cell[k] = cell_coord(top[k], origin[k], inv_cell);
    const Packing packing(top_cell);

    // ---- What a later round needs (BroadPhaseInput::vertex_changed) ------------------------------
    // A pair needs a changed primitive, and its two bounds overlap, so they share a cell of any grid:
    // the changed bounds mark the cells of a coarse grid, and an unchanged primitive whose bound
    // reaches no marked cell is left out of the hash. The pairs, and their sorted order, are the same.
    if (only_changed) needed_.assign(prims, 1);
    if (only_changed && origin.x <= top.x) {
        const Vec3d extent = top - origin;
        double region = std::max(extent.x, std::max(extent.y, extent.z)) / static_cast<double>(kRegionCells);
        if (!(region > 0.0) || !std::isfinite(region)) region = 1.0;
        const double inv_region = 1.0 / region;
        const auto coord = [&](double x, int k) {
            const double c = std::floor((x - origin[k]) * inv_region);
            return c < 0.0 ? 0L : c >= static_cast<double>(kRegionCells) ? kRegionCells - 1 : static_cast<long>(c);
        };
        // Calls `visit(cell index)` for every region cell `box` covers; false where it covers too many.
        const auto cover = [&](const Box& box, auto&& visit) {
            long lo[3], hi[3], count = 1;
            for (int k = 0; k < 3; ++k) {
                lo[k] = coord(box.lo[k], k);
                hi[k] = coord(box.hi[k], k);
                count *= hi[k] - lo[k] + 1;
            }
            if (count > kRegionCellsPerBound) return false;
            for (long z = lo[2]; z <= hi[2]; ++z)
                for (long y = lo[1]; y <= hi[1]; ++y)
                    for (long x = lo[0]; x <= hi[0]; ++x)
                        if (visit(static_cast<std::size_t>((z * kRegionCells + y) * kRegionCells + x))) return true;
            return true;
        };
        region_.assign(static_cast<std::size_t>(kRegionCells * kRegionCells * kRegionCells), 0);
        bool everywhere = false;
        for (std::size_t p = 0; p < prims && !everywhere; ++p)
            if (changed_[p] && finite_box(box_[p]))
                everywhere = !cover(box_[p], [&](std::size_t at) {
                    region_[at] = 1;
                    return false;
                });
        if (!everywhere)
            parallel_chunks(prims, [&](std::size_t b, std::size_t e) {
                for (std::size_t p = b; p < e; ++p) {
                    if (changed_[p] || !finite_box(box_[p])) continue;
                    bool touches = false;
                    if (!cover(box_[p], [&](std::size_t at) { return touches = region_[at] != 0; })) touches = true;
                    needed_[p] = touches ? 1 : 0;
                }
            });
    }

    // ---- Cells of each bound --------------------------------------------------------------------
    cell_lo_.resize(prims);
    cell_hi_.resize(prims);
    offset_.resize(prims + 1);
    parallel_chunks(prims, [&](std::size_t b, std::size_t e) {
        for (std::size_t p = b; p < e; ++p) {
            const Box& box = box_[p];
            offset_[p] = 0;
            if (!finite_box(box)) {
                state_[p] = kNonFinite;
                continue;
            }
            if (only_changed && !needed_[p]) {
                state_[p] = kUnneeded;
                continue;
            }
            std::uint64_t lo[3], hi[3], cells = 1;
            for (int k = 0; k < 3; ++k) {
                lo[k] = cell_coord(box.lo[k], origin[k], inv_cell);
                hi[k] = cell_coord(box.hi[k], origin[k], inv_cell);
                cells *= hi[k] - lo[k] + 1;  // ≤ 2^63: no overflow
            }
            cell_lo_[p] = packing.pack(lo[0], lo[1], lo[2]);
            cell_hi_[p] = packing.pack(hi[0], hi[1], hi[2]);
            if (cells > kMaxCellsPerPrimitive) {
                state_[p] = kOversized;
                continue;
            }
            state_[p] = kHashed;
            offset_[p] = static_cast<std::size_t>(cells);
        }
    });
    BroadPhaseCounters& c = out.counters;
    c = {};
    c.cell_size = cell;
    oversized_.clear();
    std::size_t total = 0;
    for (std::size_t p = 0; p < prims; ++p) {
        const std::size_t count = offset_[p];
        offset_[p] = total;
        total += count;
        if (state_[p] == kOversized) oversized_.push_back(static_cast<std::uint32_t>(p));
        if (state_[p] == kNonFinite) ++c.nonfinite;
    }
    offset_[prims] = total;
    c.primitives = prims - c.nonfinite;
    c.oversized = oversized_.size();
    c.entries = total;

    // ---- Entries, sorted by cell ----------------------------------------------------------------
    entries_.resize(total);
    parallel_chunks(prims, [&](std::size_t b, std::size_t e) {
        for (std::size_t p = b; p < e; ++p) {
            if (state_[p] != kHashed) continue;
            std::size_t at = offset_[p];
            const std::uint64_t lo = cell_lo_[p], hi = cell_hi_[p];
            for (std::uint64_t z = packing.coord(lo, 2); z <= packing.coord(hi, 2); ++z)
                for (std::uint64_t y = packing.coord(lo, 1); y <= packing.coord(hi, 1); ++y)
                    for (std::uint64_t x = packing.coord(lo, 0); x <= packing.coord(hi, 0); ++x)
                        entries_[at++] = {packing.pack(x, y, z), static_cast<std::uint32_t>(p)};
        }
    });
    // Entries were written in primitive order, and the radix sort is stable: within a cell the
    // primitives stay in index order (vertices, then edges, then triangles), and the result is one
    // fixed sequence whatever the thread count.
    radix_sort_by_key(entries_, sorted_, histogram_, packing.bits, [](const Entry& e) { return e.cell; });
    cell_start_.clear();
    for (std::size_t i = 0; i < total; ++i)
        if (i == 0 || entries_[i].cell != entries_[i - 1].cell) cell_start_.push_back(i);
    c.cells_occupied = cell_start_.size();
    cell_start_.push_back(total);
    for (std::size_t k = 0; k + 1 < cell_start_.size(); ++k)
        c.max_cell_entries = std::max(c.max_cell_entries, cell_start_[k + 1] - cell_start_[k]);

    // ---- Pairs ----------------------------------------------------------------------------------
    for (Local& l : local_) {
        l.vf.clear();
        l.ee.clear();
        l.tested = l.candidates = l.culled = 0;
    }
    // Pair tests: true when the bounds overlap and the primitives are neither adjacent nor filtered
    // out, i.e. a candidate (counted before the dedup rule decides who reports it).
    const auto vf_candidate = [&](Local& l, std::uint32_t v, std::uint32_t t, const Box& bv, const Box& bt) {
        if (unchanged(v, t)) return false;
        ++l.tested;
        if (!overlap(bv, bt) || is_corner(v, triangle_of(t)) || filtered(v, t)) return false;
        ++l.candidates;
        return true;
    };
    const auto ee_candidate = [&](Local& l, std::uint32_t a, std::uint32_t b, const Box& ba, const Box& bb) {
        if (unchanged(a, b)) return false;
        ++l.tested;
        if (!overlap(ba, bb) || shares_vertex(edge_of(a), edge_of(b)) || filtered(a, b)) return false;
        ++l.candidates;
        return true;
    };
    // Culled pairs: counted when they would have been candidates (count_culled), never emitted.
    const auto vf_culled = [&](Local& l, std::uint32_t v, std::uint32_t t, const Box& bv, const Box& bt) {
        if (in.count_culled && !unchanged(v, t) && overlap(bv, bt) && !is_corner(v, triangle_of(t)) && !filtered(v, t))
            ++l.culled;
    };
    const auto ee_culled = [&](Local& l, std::uint32_t a, std::uint32_t b, const Box& ba, const Box& bb) {
        if (in.count_culled && !unchanged(a, b) && overlap(ba, bb) && !shares_vertex(edge_of(a), edge_of(b)) &&
            !filtered(a, b))
            ++l.culled;
    };
    const auto add_vf = [&](Local& l, std::uint32_t v, std::uint32_t t) {
        l.vf.push_back({v, static_cast<std::uint32_t>(t - tri0)});
    };
    const auto add_ee = [&](Local& l, std::uint32_t a, std::uint32_t b) {
        const auto ia = static_cast<std::uint32_t>(a - edge0), ib = static_cast<std::uint32_t>(b - edge0);
        l.ee.push_back({std::min(ia, ib), std::max(ia, ib)});
    };
    // One cell with culling: the occupants are regrouped by (kind, patch, index), the cell key
    // extended with the cone id (PSCC), and only pairs across patch groups are formed; a vertex's
    // own group of triangles and an edge's own group of edges are skipped as whole ranges (and only
    // bound-tested to be counted). kNoPatch sorts last and is never skipped. The dedup rule and the
    // pair tests are those of the plain loops below. (On the device the key would be (cell, patch)
    // and the per-cell workload Σ_{i≠j} n_i·n_j over patch groups, PSCC's workload table.)
    const auto cull_cell = [&](Local& l, std::uint64_t key, std::size_t count, std::size_t first_edge,
                               std::size_t first_tri) {
        auto& occ = l.occ;
        occ.resize(count);
        for (std::size_t i = 0; i < count; ++i) occ[i] = {l.box[i], l.cell_lo[i], l.prim[i], patch_of(l.prim[i])};
        const auto by_patch = [](const Local::Occupant& a, const Local::Occupant& b) {
            return a.patch != b.patch ? a.patch < b.patch : a.prim < b.prim;
        };
        const auto at = [&](std::size_t i) { return occ.begin() + static_cast<std::ptrdiff_t>(i); };
        std::sort(at(0), at(first_edge), by_patch);
        std::sort(at(first_edge), at(first_tri), by_patch);
        std::sort(at(first_tri), at(count), by_patch);
        const auto vf = [&](std::size_t i, std::size_t j) {
            if (vf_candidate(l, occ[i].prim, occ[j].prim, occ[i].box, occ[j].box) &&
                packing.max(occ[i].cell_lo, occ[j].cell_lo) == key)
                add_vf(l, occ[i].prim, occ[j].prim);
        };
        const auto ee = [&](std::size_t i, std::size_t j) {
            if (ee_candidate(l, occ[i].prim, occ[j].prim, occ[i].box, occ[j].box) &&
                packing.max(occ[i].cell_lo, occ[j].cell_lo) == key)
                add_ee(l, occ[i].prim, occ[j].prim);
        };
        const auto occupant = [&](std::size_t i) { return occ[i].prim; };
        const std::size_t kinematic_vertices = kinematic_from(occupant, 0, first_edge);
        const std::size_t kinematic_edges = kinematic_from(occupant, first_edge, first_tri);
        const std::size_t kinematic_triangles = kinematic_from(occupant, first_tri, count);
        // Vertex–face: triangles [group_begin, group_end) share the vertex's patch.
        std::size_t group_begin = first_tri;
        for (std::size_t i = 0; i < first_edge; ++i) {
            const std::uint32_t p = occ[i].patch;
            while (group_begin < count && occ[group_begin].patch < p) ++group_begin;
            std::size_t group_end = group_begin;
            if (p != kNoPatch)
                while (group_end < count && occ[group_end].patch == p) ++group_end;
            const std::size_t last = i < kinematic_vertices ? count : kinematic_triangles;
            for (std::size_t j = first_tri; j < std::min(group_begin, last); ++j) vf(i, j);
            for (std::size_t j = group_end; j < last; ++j) vf(i, j);
            for (std::size_t j = group_begin; j < std::min(group_end, last); ++j)
                vf_culled(l, occ[i].prim, occ[j].prim, occ[i].box, occ[j].box);
        }
        // Edge–edge: edges [i + 1, group_end) share edge i's patch; from the first mesh collider edge on,
        // every later edge is a collider's too.
        std::size_t group_end = first_edge;
        for (std::size_t i = first_edge; i < kinematic_edges; ++i) {
            const std::uint32_t p = occ[i].patch;
            if (p == kNoPatch) {
                group_end = i + 1;
            } else if (group_end <= i) {
                group_end = i + 1;
                while (group_end < first_tri && occ[group_end].patch == p) ++group_end;
            }
            for (std::size_t j = group_end; j < first_tri; ++j) ee(i, j);
            for (std::size_t j = i + 1; j < group_end; ++j)
                ee_culled(l, occ[i].prim, occ[j].prim, occ[i].box, occ[j].box);
        }
    };
    const std::size_t cells = c.cells_occupied;
    // Work stealing balances crowded cells; the grain keeps the per-task overhead small.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells, 64), [&](const tbb::blocked_range<std::size_t>& r) {
        Local& l = local_.local();
        for (std::size_t k = r.begin(); k != r.end(); ++k) {
            const std::size_t begin = cell_start_[k], end = cell_start_[k + 1], count = end - begin;
            const std::uint64_t key = entries_[begin].cell;
            // The occupants' bounds side by side: the all-pairs loops below then stay in cache.
            l.prim.resize(count);
            l.box.resize(count);
            l.cell_lo.resize(count);
            std::size_t first_edge = count, first_tri = count;
            for (std::size_t i = 0; i < count; ++i) {
                const std::uint32_t p = entries_[begin + i].prim;
                l.prim[i] = p;
                l.box[i] = box_[p];
                l.cell_lo[i] = cell_lo_[p];
                if (p >= edge0 && first_edge == count) first_edge = i;
                if (p >= tri0 && first_tri == count) first_tri = i;
            }
            first_edge = std::min(first_edge, first_tri);
            if (only_changed &&
                std::none_of(l.prim.begin(), l.prim.end(), [&](std::uint32_t p) { return changed_[p] != 0; }))
                continue;  // nothing here moved since the last round: no pair to form
            if (cull) {
                cull_cell(l, key, count, first_edge, first_tri);
                continue;
            }
            // Overlapping bounds share every cell of their intersection; the pair is reported only
            // in the cell of the intersection's minimum corner, the per-axis max of the two minimum
            // cells (cell_coord is monotone).
            const auto occupant = [&](std::size_t i) { return l.prim[i]; };
            const std::size_t kinematic_vertices = kinematic_from(occupant, 0, first_edge);
            const std::size_t kinematic_edges = kinematic_from(occupant, first_edge, first_tri);
            const std::size_t kinematic_triangles = kinematic_from(occupant, first_tri, count);
            for (std::size_t i = 0; i < first_edge; ++i) {
                const std::size_t last = i < kinematic_vertices ? count : kinematic_triangles;
                for (std::size_t j = first_tri; j < last; ++j)
                    if (vf_candidate(l, l.prim[i], l.prim[j], l.box[i], l.box[j]) &&
                        packing.max(l.cell_lo[i], l.cell_lo[j]) == key)
                        add_vf(l, l.prim[i], l.prim[j]);
            }
            for (std::size_t i = first_edge; i < kinematic_edges; ++i)
                for (std::size_t j = i + 1; j < first_tri; ++j)
                    if (ee_candidate(l, l.prim[i], l.prim[j], l.box[i], l.box[j]) &&
                        packing.max(l.cell_lo[i], l.cell_lo[j]) == key)
                        add_ee(l, l.prim[i], l.prim[j]);
        }
    });

    // Oversized primitives against every partner. A pair of two oversized primitives is reported
    // from one side only: the vertex for vertex–face, the lower edge for edge–edge.
    for (std::uint32_t p : oversized_) {
        if (p < edge0) {
            parallel_chunks(nt, [&](std::size_t b, std::size_t e) {
                Local& l = local_.local();
                for (std::size_t i = b; i < e; ++i) {
                    const auto t = static_cast<std::uint32_t>(tri0 + i);
                    if (state_[t] == kNonFinite) continue;
                    if (same_patch(p, t)) {
                        vf_culled(l, p, t, box_[p], box_[t]);
                    } else if (vf_candidate(l, p, t, box_[p], box_[t])) {
                        add_vf(l, p, t);
                    }
                }
            });
        } else if (p < tri0) {
            parallel_chunks(ne, [&](std::size_t b, std::size_t e) {
                Local& l = local_.local();
                for (std::size_t i = b; i < e; ++i) {
                    const auto q = static_cast<std::uint32_t>(edge0 + i);
                    if (q == p || state_[q] == kNonFinite || (state_[q] == kOversized && q < p)) continue;
                    if (same_patch(p, q)) {
                        ee_culled(l, p, q, box_[p], box_[q]);
                    } else if (ee_candidate(l, p, q, box_[p], box_[q])) {
                        add_ee(l, p, q);
                    }
                }
            });
        } else {
            parallel_chunks(n, [&](std::size_t b, std::size_t e) {
                Local& l = local_.local();
                for (std::size_t i = b; i < e; ++i) {
                    const auto v = static_cast<std::uint32_t>(i);
                    if (state_[v] != kHashed) continue;
                    if (same_patch(v, p)) {
                        vf_culled(l, v, p, box_[v], box_[p]);
                    } else if (vf_candidate(l, v, p, box_[v], box_[p])) {
                        add_vf(l, v, p);
                    }
                }
            });
        }
    }

    // ---- Merge and sort -------------------------------------------------------------------------
    std::size_t vf_total = 0, ee_total = 0;
    for (const Local& l : local_) {
        vf_total += l.vf.size();
        ee_total += l.ee.size();
        c.tested_pairs += l.tested;
        c.candidate_pairs += l.candidates;
        c.culled_pairs += l.culled;
    }
    out.vf.clear();
    out.ee.clear();
    out.vf.reserve(vf_total);
    out.ee.reserve(ee_total);
    for (const Local& l : local_) {
        out.vf.insert(out.vf.end(), l.vf.begin(), l.vf.end());
        out.ee.insert(out.ee.end(), l.ee.begin(), l.ee.end());
    }
    // Each pair was reported once, so sorting alone gives the unique, thread-count-free order: by
    // (first id, second id), the pairs' own order, with the two ids packed into one radix key.
    const int vertex_bits = bits_for(n), triangle_bits = bits_for(nt), edge_bits = bits_for(ne);
    radix_sort_by_key(out.vf, vf_scratch_, histogram_, vertex_bits + triangle_bits, [triangle_bits](const VertexFacePair& p) {
        return (std::uint64_t{p.vertex} << triangle_bits) | p.triangle;
    });
    radix_sort_by_key(out.ee, ee_scratch_, histogram_, 2 * edge_bits,
                      [edge_bits](const EdgeEdgePair& p) { return (std::uint64_t{p.a} << edge_bits) | p.b; });
    c.vf_pairs = out.vf.size();
    c.ee_pairs = out.ee.size();
    trim_pair_lists(out);
    last_ = {!cull && !only_changed && !padded, n, in.triangles, in.edges, in.triangle_cloth, in.self_pairs,
             in.first_kinematic_group, &out, out.vf.size(), out.ee.size()};
}

bool BroadPhase::clean_pairs_within_last(const BroadPhaseInput& in, const BroadPhaseResult& last, BroadPhaseResult& clean,
                                         std::vector<std::uint8_t>& outside) {
    const std::size_t n = in.x0.size(), ne = in.edges.size(), nt = in.triangles.size();
    const auto same = [](auto a, auto b) { return a.data() == b.data() && a.size() == b.size(); };
    // The pairs' filters (adjacency, cloth, colliders) must be the ones the last call applied.
    const bool filters_kept = same(in.triangles, last_.triangles) && same(in.edges, last_.edges) &&
                              same(in.triangle_cloth, last_.triangle_cloth) && in.self_pairs == last_.self_pairs &&
                              in.first_kinematic_group == last_.first_kinematic_group;
    const bool cull = !in.vertex_patch.empty() || !in.edge_patch.empty() || !in.triangle_patch.empty();
    if (!last_.reusable || !filters_kept || &last != last_.result || &last == &clean || n != last_.n ||
        in.x1.size() != n || last.vf.size() != last_.vf || last.ee.size() != last_.ee || !in.vertex_padding.empty() ||
        !in.vertex_changed.empty() ||
        (cull && (in.count_culled || in.vertex_patch.size() != n || in.edge_patch.size() != ne ||
                  in.triangle_patch.size() != nt)) ||
        !std::isfinite(in.thickness) || in.thickness < 0.0 || !physics::is_finite(in.frame_motion))
        return false;

    // The new vertex bounds, and which lie outside the last call's (a NaN compares false: a
    // position not finite now, or then, counts as outside).
    const std::size_t edge0 = n, tri0 = n + ne, prims = n + ne + nt;
    within_box_.resize(prims);
    outside.resize(n);
    std::atomic<std::size_t> outside_count{0};
    parallel_chunks(n, [&](std::size_t b, std::size_t e) {
        std::size_t count = 0;
        for (std::size_t i = b; i < e; ++i) {
            Box& box = within_box_[i];
            vertex_bound(box, in.x0[i], in.x1[i], in.frame_motion, in.thickness);
            const Box& then = box_[i];
            const bool inside = box.lo.x >= then.lo.x && box.lo.y >= then.lo.y && box.lo.z >= then.lo.z &&
                                box.hi.x <= then.hi.x && box.hi.y <= then.hi.y && box.hi.z <= then.hi.z;
            outside[i] = inside ? 0 : 1;
            count += inside ? 0 : 1;
        }
        outside_count.fetch_add(count, std::memory_order_relaxed);
    });
    // Beyond this share the hash of the vertices outside costs about what hashing everything does.
    if (outside_count.load() * kReuseOutsideShare > n) return false;
    const std::span<const Box> vertex_bounds(within_box_.data(), n);
    parallel_chunks(ne, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) united_bound(within_box_[edge0 + i], vertex_bounds, in.edges[i].v);
    });
    parallel_chunks(nt, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) united_bound(within_box_[tri0 + i], vertex_bounds, in.triangles[i].v);
    });

    // A pair whose primitives have no vertex outside stays where its new bounds overlap and culling
    // keeps it (find's same_patch); kept in order, the lists stay sorted and unique.
    const auto out_of = [&](std::span<const std::uint32_t> vertices) {
        for (const std::uint32_t v : vertices)
            if (outside[v] != 0) return true;
        return false;
    };
    const std::size_t nvf = last.vf.size(), total = nvf + last.ee.size();
    keep_.resize(total);
    parallel_chunks(total, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            std::size_t pa = 0, pb = 0;
            std::uint32_t patch_a = kNoPatch, patch_b = kNoPatch;
            bool moved = false;
            if (i < nvf) {
                const VertexFacePair& p = last.vf[i];
                pa = p.vertex;
                pb = tri0 + p.triangle;
                moved = outside[p.vertex] != 0 || out_of(in.triangles[p.triangle].v);
                if (cull) patch_a = in.vertex_patch[p.vertex], patch_b = in.triangle_patch[p.triangle];
            } else {
                const EdgeEdgePair& p = last.ee[i - nvf];
                pa = edge0 + p.a;
                pb = edge0 + p.b;
                moved = out_of(in.edges[p.a].v) || out_of(in.edges[p.b].v);
                if (cull) patch_a = in.edge_patch[p.a], patch_b = in.edge_patch[p.b];
            }
            const bool culled = patch_a != kNoPatch && patch_a == patch_b;
            keep_[i] = !moved && !culled && overlap(within_box_[pa], within_box_[pb]);
        }
    });
    clean.vf.clear();
    clean.ee.clear();
    for (std::size_t i = 0; i < nvf; ++i)
        if (keep_[i]) clean.vf.push_back(last.vf[i]);
    for (std::size_t i = nvf; i < total; ++i)
        if (keep_[i]) clean.ee.push_back(last.ee[i - nvf]);
    BroadPhaseCounters& c = clean.counters;
    c = {};
    c.primitives = prims;
    c.tested_pairs = total;
    c.candidate_pairs = clean.vf.size() + clean.ee.size();
    c.vf_pairs = clean.vf.size();
    c.ee_pairs = clean.ee.size();
    return true;
}

bool BroadPhase::find_reusing(BroadPhase& earlier, const BroadPhaseResult& earlier_pairs, const BroadPhaseInput& in,
                              BroadPhaseResult& out) {
    if (&earlier == this || !earlier.clean_pairs_within_last(in, earlier_pairs, reuse_clean_, reuse_outside_)) {
        find(in, out);
        return false;
    }
    // The pairs with a primitive that has a vertex outside: hashed on their own (the later rounds'
    // vertex_changed), none of them among the clean ones; the union, merged in the pairs' order, is
    // find(in)'s sorted, unique lists.
    BroadPhaseInput moved_in = in;
    moved_in.vertex_changed = reuse_outside_;
    find(moved_in, reuse_moved_);
    const auto vf_less = [](const VertexFacePair& a, const VertexFacePair& b) {
        return a.vertex != b.vertex ? a.vertex < b.vertex : a.triangle < b.triangle;
    };
    const auto ee_less = [](const EdgeEdgePair& a, const EdgeEdgePair& b) { return a.a != b.a ? a.a < b.a : a.b < b.b; };
    out.vf.resize(reuse_clean_.vf.size() + reuse_moved_.vf.size());
    out.ee.resize(reuse_clean_.ee.size() + reuse_moved_.ee.size());
    std::merge(reuse_clean_.vf.begin(), reuse_clean_.vf.end(), reuse_moved_.vf.begin(), reuse_moved_.vf.end(),
               out.vf.begin(), vf_less);
    std::merge(reuse_clean_.ee.begin(), reuse_clean_.ee.end(), reuse_moved_.ee.begin(), reuse_moved_.ee.end(),
               out.ee.begin(), ee_less);
    BroadPhaseCounters& c = out.counters;
    c = reuse_moved_.counters;
    c.tested_pairs += reuse_clean_.counters.tested_pairs;
    c.candidate_pairs += reuse_clean_.counters.candidate_pairs;
    c.vf_pairs = out.vf.size();
    c.ee_pairs = out.ee.size();
    return true;
}

void BroadPhase::trim_pair_lists(BroadPhaseResult& out) {
    for (Local& l : local_) {
        l.vf_peak = std::max(l.vf_peak, l.vf.size());
        l.ee_peak = std::max(l.ee_peak, l.ee.size());
    }
    out_vf_peak_ = std::max(out_vf_peak_, out.vf.size());
    out_ee_peak_ = std::max(out_ee_peak_, out.ee.size());
    if (++calls_since_trim_ < kTrimPeriod) return;
    for (Local& l : local_) {
        (void)trim_to_peak(l.vf, l.vf_peak);
        (void)trim_to_peak(l.ee, l.ee_peak);
        l.vf_peak = l.ee_peak = 0;
    }
    (void)trim_to_peak(out.vf, out_vf_peak_);
    (void)trim_to_peak(out.ee, out_ee_peak_);
    (void)trim_to_peak(vf_scratch_, out_vf_peak_);
    (void)trim_to_peak(ee_scratch_, out_ee_peak_);
    out_vf_peak_ = out_ee_peak_ = 0;
    calls_since_trim_ = 0;
}

std::size_t BroadPhase::scratch_bytes() const {
    std::size_t bytes = box_.capacity() * sizeof(Box) + (cell_lo_.capacity() + cell_hi_.capacity()) * sizeof(std::uint64_t) +
                        offset_.capacity() * sizeof(std::size_t) +
                        (oversized_.capacity() + vertex_cloth_.capacity()) * sizeof(std::uint32_t) +
                        (entries_.capacity() + sorted_.capacity()) * sizeof(Entry) +
                        vf_scratch_.capacity() * sizeof(VertexFacePair) + ee_scratch_.capacity() * sizeof(EdgeEdgePair) +
                        (histogram_.capacity() + cell_start_.capacity()) * sizeof(std::size_t) +
                        extent_.capacity() * sizeof(double) + state_.capacity();
    for (const Local& l : local_)
        bytes += l.vf.capacity() * sizeof(VertexFacePair) + l.ee.capacity() * sizeof(EdgeEdgePair) +
                 l.prim.capacity() * sizeof(std::uint32_t) + l.box.capacity() * sizeof(Box) +
                 l.cell_lo.capacity() * sizeof(std::uint64_t) + l.occ.capacity() * sizeof(Local::Occupant);
    return bytes;
}

}  // namespace weft::collision
