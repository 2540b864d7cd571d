// Normal-cone culling on the GPU: refit, top-down pass tests and patch ids (see normal_cone_gpu.h for
// the pipeline; normal_cone_float.h for the float arithmetic and its rounding allowances). The CPU
// reference is runtime/src/collision/normal_cone_front.cpp (NormalConeFront::rebuild) over the same
// PatchHierarchy (weft/backend/patch_hierarchy.h).
#include "collision/normal_cone_gpu.h"

#include <algorithm>
#include <string>

#include "collision/normal_cone_float.h"
#include "collision/pair_keys.h"
#include "weft/backend/patch_hierarchy.h"
#include "cuda_check.h"
#include "grid_size.h"
#include "weft/error.h"

namespace weft::cuda::collision {
namespace {

// ---- constants -----------------------------------------------------------------------------------

constexpr std::uint32_t kNone = 0xFFFFFFFFU;  // no node / no triangle (weft::collision::kNone)
static_assert(kNone == weft::collision::kNone);
static_assert(kNoPatch == weft::collision::kNone, "a primitive without a patch is never culled");

// What a node's `top` holds after the classify pass of its level: the passing node above it (its
// patch; itself when it is on the front), or one of these three markers. Node ids stay below them.
constexpr std::uint32_t kOpen = kNone;           // no passing node at or above it: children are examined
constexpr std::uint32_t kPending = 0xFFFFFFFEU;  // its contour is being tested (resolved by `failed`)
constexpr std::uint32_t kClosed = 0xFFFFFFFDU;   // no cloth in it: never examined, never culled

// Node flags (host-computed at build).
constexpr std::uint8_t kFlagDisk = 1;      // PatchHierarchy::kDisk: the contour test applies
constexpr std::uint8_t kFlagLeaf = 2;      // a single triangle
constexpr std::uint8_t kFlagAllCloth = 4;  // every triangle below is a cloth triangle
constexpr std::uint8_t kFlagAnyCloth = 8;  // some triangle below is

constexpr unsigned kThreads = 256;         // refit, classify, assign
constexpr unsigned kContourThreads = 128;  // contour: 4 warps per block
constexpr unsigned kTile = 32;             // contour edges per tile: one per lane
constexpr unsigned kFullMask = 0xFFFFFFFFU;

static_assert(sizeof(GpuNormalConeCounters) == 2 * sizeof(unsigned long long));
static_assert(sizeof(GpuCone) == sizeof(float4));

/// Contour tile pairs of a contour of m edges: every unordered pair of 32-edge tiles, and each tile
/// with itself.
[[nodiscard]] __host__ __device__ inline std::uint64_t tile_pairs(std::uint32_t m) {
    const std::uint64_t tiles = (std::uint64_t{m} + kTile - 1) / kTile;
    return tiles * (tiles + 1) / 2;
}

// ---- device helpers ------------------------------------------------------------------------------

__device__ inline Vec3f load_position(const float* x, std::uint32_t stride, std::uint32_t v) {
    return {x[v], x[static_cast<std::size_t>(stride) + v], x[2 * static_cast<std::size_t>(stride) + v]};
}

__device__ inline FloatCone load_cone(const float4* cones, std::uint32_t n) {
    const float4 c = cones[n];
    FloatCone out;
    out.axis = {c.x, c.y, c.z};
    out.half_angle = c.w;
    return out;
}

/// Counter words of GpuNormalConeCounters in the device block.
struct CounterWords {
    unsigned* front_size;
    unsigned* contour_tests;
    unsigned* contour_failed;
    unsigned* contour_items;
};

__host__ __device__ inline CounterWords counter_words(unsigned long long* block) {
    auto* w = reinterpret_cast<unsigned*>(block);
    return {w, w + 1, w + 2, w + 3};
}

// ---- refit: bottom-up, one launch per level ------------------------------------------------------

struct RefitParams {
    const float* x0;
    const float* x1;
    std::uint32_t stride;
    const std::uint32_t* link;
    const std::uint8_t* flags;
    const std::uint32_t* triangles;
    float4* cones;
    std::uint32_t first, count;
};

/// The continuous normal cone of every node of one level: a leaf's from its triangle's motion, an
/// inner node's as the merge of its two children's (refitted by the previous launch, one level
/// deeper). Nodes that are not all cloth get the infinite cone without reading a position.
__global__ void refit_kernel(RefitParams p) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= p.count) return;
    const std::uint32_t n = p.first + i;
    const std::uint8_t f = p.flags[n];
    FloatCone c;
    if ((f & kFlagAllCloth) != 0) {
        const std::uint32_t l = p.link[n];
        if ((f & kFlagLeaf) != 0) {
            const std::uint32_t a = p.triangles[3 * static_cast<std::size_t>(l)];
            const std::uint32_t b = p.triangles[3 * static_cast<std::size_t>(l) + 1];
            const std::uint32_t d = p.triangles[3 * static_cast<std::size_t>(l) + 2];
            c = float_triangle_cone(load_position(p.x0, p.stride, a), load_position(p.x0, p.stride, b),
                                    load_position(p.x0, p.stride, d), load_position(p.x1, p.stride, a),
                                    load_position(p.x1, p.stride, b), load_position(p.x1, p.stride, d));
        } else {
            c = float_merge_cones(load_cone(p.cones, l), load_cone(p.cones, l + 1));
        }
    }
    p.cones[n] = make_float4(c.axis.x, c.axis.y, c.axis.z, c.half_angle);
}

// ---- classify: top-down, one launch per level ----------------------------------------------------

struct ClassifyParams {
    const std::uint32_t* parent;
    const std::uint32_t* link;
    const std::uint8_t* flags;
    const std::uint32_t* contour_first;
    const float4* cones;
    std::uint32_t* top;
    std::uint32_t* failed;
    uint2* entries;
    unsigned long long* level_counter;  // (entries << 32) | items of this level's work list
    CounterWords counters;
    std::uint32_t first, count;
};

/// Each node of one level: covered by a passing ancestor (it takes its patch), closed (no cloth),
/// passing at once (a leaf, or a narrow disk with no contour), queued for its contour test (a
/// narrow, all-cloth disk), or open. The parent was classified by the previous launch; a queued
/// parent is resolved here from its failure flag, which the contour launch in between has set.
/// The result is NormalConeFront::rebuild's cut: a node is examined only if no ancestor passes.
__global__ void classify_kernel(ClassifyParams p) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= p.count) return;
    const std::uint32_t n = p.first + i;
    const std::uint32_t par = p.parent[n];
    std::uint32_t above = kOpen;
    if (par != kNone) {
        above = p.top[par];
        if (above == kPending) {
            const bool passed = p.failed[par] == 0;
            above = passed ? par : kOpen;
            // The queued parent joins the front: counted once, by its left child.
            if (passed && p.link[par] == n) atomicAdd(p.counters.front_size, 1U);
        }
    }
    if (above != kOpen) {
        p.top[n] = above;  // a passing ancestor's patch, or closed
        return;
    }
    const std::uint8_t f = p.flags[n];
    std::uint32_t mine = kOpen;
    if ((f & kFlagAnyCloth) == 0) {
        mine = kClosed;
    } else if ((f & kFlagLeaf) != 0) {
        mine = n;  // a single triangle cannot collide with itself
    } else if ((f & kFlagAllCloth) != 0 && (f & kFlagDisk) != 0 && float_cone_is_narrow(load_cone(p.cones, n))) {
        const std::uint32_t m = p.contour_first[n + 1] - p.contour_first[n];
        if (m == 0) {
            mine = n;  // nothing to test (as contour_stays_simple on an empty contour)
        } else {
            mine = kPending;
            p.failed[n] = 0;
            const auto items = static_cast<std::uint32_t>(tile_pairs(m));
            // Entry index and first item in one atomic: entries come out ordered by their items.
            const unsigned long long old = atomicAdd(p.level_counter, (1ULL << 32) | items);
            p.entries[old >> 32] = make_uint2(n, static_cast<std::uint32_t>(old));
            atomicAdd(p.counters.contour_tests, 1U);
            atomicAdd(p.counters.contour_items, items);
        }
    }
    if (mine == n) atomicAdd(p.counters.front_size, 1U);
    p.top[n] = mine;
}

// ---- contour tests: a warp per tile pair ---------------------------------------------------------

struct ContourParams {
    const float* x0;
    const float* x1;
    std::uint32_t stride;
    const std::uint32_t* contour_first;
    const uint2* contour_edges;
    const float4* cones;
    std::uint32_t* failed;
    const uint2* entries;
    const unsigned long long* level_counter;
    unsigned* failed_count;
};

__device__ inline SweptEdge shuffle_edge(const SweptEdge& s, int lane) {
    SweptEdge o;
    for (int k = 0; k < 4; ++k)
        for (int c = 0; c < 2; ++c) o.p[k][c] = __shfl_sync(kFullMask, s.p[k][c], lane);
    o.scale = __shfl_sync(kFullMask, s.scale, lane);
    o.finite = true;  // every edge of both tiles was checked finite before the loop
    return o;
}

/// The contour test of one level's queued nodes (contour_test.cpp's contour_stays_simple, in float,
/// without the sort: a tile pair's 32 × 32 boxes are compared directly). Warps stride over the work
/// list; item `w` belongs to the last entry whose first item is ≤ w. A node's contour is projected
/// relative to the x0 position of its first edge's first vertex, along its cone axis. Lane k holds
/// edge k of tile ti and edge k of tile tj; tile tj's edges are broadcast one by one, so each lane
/// tests its own edge against all of them (within one tile, only against later ones). Any pair that
/// may touch, or any non-finite position, marks the node failed. A warp skips a node already marked
/// by another (only work is saved: the outcome is the OR over all pairs either way).
__global__ void contour_kernel(ContourParams p) {
    const unsigned lane = threadIdx.x & 31U;
    const unsigned warp = (blockIdx.x * blockDim.x + threadIdx.x) >> 5;
    const unsigned warps = (gridDim.x * blockDim.x) >> 5;
    const unsigned long long packed = *p.level_counter;
    const auto entries = static_cast<std::uint32_t>(packed >> 32);
    const auto total = static_cast<std::uint32_t>(packed);
    for (std::uint32_t item = warp; item < total; item += warps) {
        std::uint32_t lo = 0, hi = entries - 1;
        while (lo < hi) {
            const std::uint32_t mid = lo + (hi - lo + 1) / 2;
            if (p.entries[mid].y <= item)
                lo = mid;
            else
                hi = mid - 1;
        }
        const std::uint32_t node = p.entries[lo].x;
        std::uint32_t local = item - p.entries[lo].y;
        std::uint32_t already = 0;
        if (lane == 0) already = *static_cast<volatile const std::uint32_t*>(p.failed + node);
        if (__shfl_sync(kFullMask, already, 0) != 0) continue;

        const std::uint32_t first = p.contour_first[node];
        const std::uint32_t m = p.contour_first[node + 1] - first;
        const std::uint32_t tiles = (m + kTile - 1) / kTile;
        std::uint32_t ti = 0;
        while (local >= tiles - ti) {  // row ti holds the pairs (ti, ti), ..., (ti, tiles − 1)
            local -= tiles - ti;
            ++ti;
        }
        const std::uint32_t tj = ti + local;
        const FloatCone cone = load_cone(p.cones, node);
        const ProjectionBasis basis = projection_basis(cone.axis);
        const Vec3f r = load_position(p.x0, p.stride, p.contour_edges[first].x);

        const std::uint32_t i = ti * kTile + lane, j = tj * kTile + lane;
        const bool has_i = i < m, has_j = j < m;
        SweptEdge a{}, b{};
        uint2 ea = make_uint2(kNone, kNone), eb = make_uint2(kNone, kNone);
        if (has_i) {
            ea = p.contour_edges[first + i];
            a = project_edge(basis, r, load_position(p.x0, p.stride, ea.x), load_position(p.x1, p.stride, ea.x),
                             load_position(p.x0, p.stride, ea.y), load_position(p.x1, p.stride, ea.y));
        }
        if (has_j) {
            eb = p.contour_edges[first + j];
            b = project_edge(basis, r, load_position(p.x0, p.stride, eb.x), load_position(p.x1, p.stride, eb.x),
                             load_position(p.x0, p.stride, eb.y), load_position(p.x1, p.stride, eb.y));
        }
        bool fail = __any_sync(kFullMask, (has_i && !a.finite) || (has_j && !b.finite));
        for (unsigned k = 0; k < kTile && !fail; ++k) {
            if (__shfl_sync(kFullMask, has_j ? 1U : 0U, static_cast<int>(k)) == 0) break;  // past the contour's end
            const SweptEdge bk = shuffle_edge(b, static_cast<int>(k));
            const std::uint32_t kx = __shfl_sync(kFullMask, eb.x, static_cast<int>(k));
            const std::uint32_t ky = __shfl_sync(kFullMask, eb.y, static_cast<int>(k));
            bool touch = false;
            const bool adjacent = ea.x == kx || ea.x == ky || ea.y == kx || ea.y == ky;
            if (has_i && (ti != tj || k > lane) && !adjacent && swept_boxes_overlap(a, bk))
                touch = !swept_edges_separated(a, bk);
            fail = __any_sync(kFullMask, touch);
        }
        if (fail && lane == 0 && atomicExch(p.failed + node, 1U) == 0) atomicAdd(p.failed_count, 1U);
    }
}

// ---- patch ids ----------------------------------------------------------------------------------

__device__ inline std::uint32_t patch_of_leaf(const std::uint32_t* top, std::uint32_t leaf) {
    if (leaf == kNone) return kNoPatch;
    const std::uint32_t t = top[leaf];
    return t < kClosed ? t : kNoPatch;
}

struct AssignParams {
    const std::uint32_t* top;
    const std::uint32_t* vertex_leaf;
    const std::uint32_t* edge_leaf;
    const std::uint32_t* triangle_leaf;
    std::uint32_t* vertex_patch;
    std::uint32_t* edge_patch;
    std::uint32_t* triangle_patch;
    std::uint32_t nv, ne, nt;
};

/// Each primitive takes the patch of its reference leaf (its own for a triangle; for a vertex or an
/// edge the leaf of the lowest-index triangle using it, as PatchHierarchy::vertex_triangle and
/// edge_triangle say): the top-most passing node above that leaf.
__global__ void assign_kernel(AssignParams p) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i < p.nv) p.vertex_patch[i] = patch_of_leaf(p.top, p.vertex_leaf[i]);
    if (i < p.ne) p.edge_patch[i] = patch_of_leaf(p.top, p.edge_leaf[i]);
    if (i < p.nt) p.triangle_patch[i] = patch_of_leaf(p.top, p.triangle_leaf[i]);
}

}  // namespace

// ---- host side -----------------------------------------------------------------------------------

GpuNormalConeCulling::GpuNormalConeCulling() {
    counters_host_.allocate(1);
    *counters_host_.get() = {};
}

GpuNormalConeCulling::~GpuNormalConeCulling() = default;

void GpuNormalConeCulling::release() {
    built_ = false;
    layout_ = {};
    hierarchy_vertices_ = 0;
    nodes_ = 0;
    level_first_.clear();
    level_items_.clear();
    level_has_contours_.clear();
    ledger_.clear();
    parent_ = {};
    link_ = {};
    flags_ = {};
    contour_first_ = {};
    contour_edges_ = {};
    cones_ = {};
    top_ = {};
    failed_ = {};
    triangles_ = {};
    vertex_leaf_ = {};
    edge_leaf_ = {};
    triangle_leaf_ = {};
    vertex_patch_ = {};
    edge_patch_ = {};
    triangle_patch_ = {};
    entries_ = {};
    counters_ = {};
}

void GpuNormalConeCulling::build(const weft::collision::PatchHierarchy& h, const GpuNormalConeLayout& layout) {
    release();
    const auto fail = [](const std::string& what) { throw Error("GPU normal-cone culling: " + what); };
    if (layout.cloth_vertices > layout.vertex_count || layout.cloth_edges > layout.edge_count ||
        layout.cloth_triangles > layout.triangle_count)
        fail("a cloth count exceeds its total");
    if (h.vertex_count > layout.vertex_count || h.triangle_count > layout.triangle_count ||
        h.edge_triangle.size() > layout.edge_count)
        fail("the hierarchy covers " + std::to_string(h.vertex_count) + " vertices, " +
             std::to_string(h.edge_triangle.size()) + " edges and " + std::to_string(h.triangle_count) +
             " triangles, more than the layout's " + std::to_string(layout.vertex_count) + ", " +
             std::to_string(layout.edge_count) + " and " + std::to_string(layout.triangle_count));
    const std::size_t nodes = h.node_size();
    if (nodes >= kClosed) fail("too many hierarchy nodes (" + std::to_string(nodes) + ")");
    const std::size_t levels = h.levels();

    // ---- Nodes: link (left child or leaf triangle), flags, bottom-up ----
    const std::uint32_t cloth_triangles = std::min(layout.cloth_triangles, h.triangle_count);
    std::vector<std::uint8_t> flags(nodes, 0);
    std::vector<std::uint32_t> link(nodes, kNone);
    for (std::size_t k = nodes; k-- > 0;) {
        if (h.is_leaf(static_cast<std::uint32_t>(k))) {
            const std::uint32_t t = h.triangle_order[h.node_first[k]];
            link[k] = t;
            flags[k] = kFlagLeaf;
            if (t < cloth_triangles) flags[k] |= kFlagAllCloth | kFlagAnyCloth;
        } else {
            const std::uint32_t l = h.node_child[k];
            link[k] = l;
            flags[k] = static_cast<std::uint8_t>((flags[l] & flags[l + 1] & kFlagAllCloth) |
                                                 ((flags[l] | flags[l + 1]) & kFlagAnyCloth));
            if ((h.node_flags[k] & weft::collision::PatchHierarchy::kDisk) != 0) flags[k] |= kFlagDisk;
        }
    }

    // ---- Levels: launch sizes and the worst case of each level's contour work ----
    level_first_.assign(h.level_first.begin(), h.level_first.end());
    level_items_.assign(levels, 0);
    level_has_contours_.assign(levels, 0);
    std::size_t max_entries = 1;
    for (std::size_t k = 0; k < levels; ++k) {
        std::uint64_t items = 0;
        std::size_t testable = 0;
        for (std::uint32_t n = h.level_first[k]; n < h.level_first[k + 1]; ++n) {
            const std::uint8_t f = flags[n];
            if ((f & kFlagLeaf) != 0 || (f & kFlagAllCloth) == 0 || (f & kFlagDisk) == 0) continue;
            const std::uint32_t m = h.contour_first[n + 1] - h.contour_first[n];
            if (m == 0) continue;
            items += tile_pairs(m);
            ++testable;
        }
        if (items > 0xFFFFFFFFULL)
            fail("level " + std::to_string(k) + " needs " + std::to_string(items) +
                 " contour tile pairs, more than 2^32");
        level_items_[k] = static_cast<std::uint32_t>(items);
        level_has_contours_[k] = testable > 0 ? 1 : 0;
        max_entries = std::max(max_entries, testable);
    }

    // ---- Primitives: the leaf each takes its patch from (kNone: never culled) ----
    std::vector<std::uint32_t> vertex_leaf(layout.vertex_count, kNone), edge_leaf(layout.edge_count, kNone),
        triangle_leaf(layout.triangle_count, kNone);
    const auto leaf_of = [&](std::uint32_t t) {
        return t != kNone && t < cloth_triangles ? h.triangle_leaf[t] : kNone;
    };
    for (std::uint32_t t = 0; t < cloth_triangles; ++t) triangle_leaf[t] = h.triangle_leaf[t];
    const std::uint32_t cloth_vertices = std::min(layout.cloth_vertices, h.vertex_count);
    for (std::uint32_t v = 0; v < cloth_vertices; ++v) vertex_leaf[v] = leaf_of(h.vertex_triangle[v]);
    const auto cloth_edges = std::min<std::size_t>(layout.cloth_edges, h.edge_triangle.size());
    for (std::size_t e = 0; e < cloth_edges; ++e) edge_leaf[e] = leaf_of(h.edge_triangle[e]);

    // ---- Upload ----
    std::vector<std::uint32_t> ids(3 * std::size_t{h.triangle_count});
    for (std::size_t t = 0; t < h.triangle_count; ++t)
        for (int c = 0; c < 3; ++c) ids[3 * t + static_cast<std::size_t>(c)] = h.triangles[t].v[c];
    std::vector<uint2> contour(h.contour_edges.size());
    for (std::size_t e = 0; e < contour.size(); ++e)
        contour[e] = make_uint2(h.contour_edges[e].a, h.contour_edges[e].b);
    std::vector<std::uint32_t> contour_first(h.contour_first.begin(), h.contour_first.end());
    if (contour_first.empty()) contour_first.assign(nodes + 1, 0);

    parent_.upload(h.node_parent, ledger_, "normal cones: hierarchy");
    link_.upload(link, ledger_, "normal cones: hierarchy");
    flags_.upload(flags, ledger_, "normal cones: hierarchy");
    contour_first_.upload(contour_first, ledger_, "normal cones: contours");
    contour_edges_.upload(contour, ledger_, "normal cones: contours");
    triangles_.upload(ids, ledger_, "normal cones: triangles");
    vertex_leaf_.upload(vertex_leaf, ledger_, "normal cones: primitive leaves");
    edge_leaf_.upload(edge_leaf, ledger_, "normal cones: primitive leaves");
    triangle_leaf_.upload(triangle_leaf, ledger_, "normal cones: primitive leaves");
    cones_.allocate(nodes, ledger_, "normal cones: per node");
    top_.allocate(nodes, ledger_, "normal cones: per node");
    failed_.allocate(nodes, ledger_, "normal cones: per node");
    vertex_patch_.allocate(layout.vertex_count, ledger_, "normal cones: patch ids");
    edge_patch_.allocate(layout.edge_count, ledger_, "normal cones: patch ids");
    triangle_patch_.allocate(layout.triangle_count, ledger_, "normal cones: patch ids");
    entries_.allocate(max_entries, ledger_, "normal cones: work list");
    counters_.allocate(2 + levels, ledger_, "normal cones: counters");

    int device = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&device));
    WEFT_CUDA_CHECK(cudaDeviceGetAttribute(&multiprocessors_, cudaDevAttrMultiProcessorCount, device));
    layout_ = layout;
    hierarchy_vertices_ = h.vertex_count;
    nodes_ = static_cast<std::uint32_t>(nodes);
    built_ = true;
}

void GpuNormalConeCulling::enqueue(const float* x0, const float* x1, std::uint32_t stride, cudaStream_t stream) {
    if (!built_) throw Error("GPU normal-cone culling: enqueue before build");
    if (stride == 0) stride = layout_.vertex_count;
    if (hierarchy_vertices_ > 0 && (x0 == nullptr || x1 == nullptr))
        throw Error("GPU normal-cone culling: null position arrays");
    if (stride < hierarchy_vertices_)
        throw Error("GPU normal-cone culling: component stride " + std::to_string(stride) + " below the hierarchy's " +
                    std::to_string(hierarchy_vertices_) + " vertices");
    const std::size_t levels = this->levels();
    unsigned long long* block = counters_.get();
    WEFT_CUDA_CHECK(cudaMemsetAsync(block, 0, counters_.bytes(), stream));

    // Refit, deepest level first: a node's children are one level below it.
    for (std::size_t k = levels; k-- > 0;) {
        const RefitParams p{.x0 = x0,
                            .x1 = x1,
                            .stride = stride,
                            .link = link_.get(),
                            .flags = flags_.get(),
                            .triangles = triangles_.get(),
                            .cones = cones_.get(),
                            .first = level_first_[k],
                            .count = level_first_[k + 1] - level_first_[k]};
        refit_kernel<<<blocks_for(p.count, kThreads), kThreads, 0, stream>>>(p);
        WEFT_CUDA_CHECK_LAUNCH("refit_kernel");
    }
    // Classify and test, root level first.
    const CounterWords words = counter_words(block);
    for (std::size_t k = 0; k < levels; ++k) {
        unsigned long long* level_counter = block + 2 + k;
        const ClassifyParams c{.parent = parent_.get(),
                               .link = link_.get(),
                               .flags = flags_.get(),
                               .contour_first = contour_first_.get(),
                               .cones = cones_.get(),
                               .top = top_.get(),
                               .failed = failed_.get(),
                               .entries = entries_.get(),
                               .level_counter = level_counter,
                               .counters = words,
                               .first = level_first_[k],
                               .count = level_first_[k + 1] - level_first_[k]};
        classify_kernel<<<blocks_for(c.count, kThreads), kThreads, 0, stream>>>(c);
        WEFT_CUDA_CHECK_LAUNCH("classify_kernel");
        if (level_has_contours_[k] == 0) continue;
        // A warp per item up to the level's worst case, at most 16 blocks of 4 warps per
        // multiprocessor; the warps stride over the items the classify pass actually queued.
        const unsigned wanted = blocks_for(level_items_[k], kContourThreads / 32);
        const unsigned grid =
            std::max(1U, std::min(wanted, 16U * static_cast<unsigned>(std::max(multiprocessors_, 1))));
        const ContourParams t{.x0 = x0,
                              .x1 = x1,
                              .stride = stride,
                              .contour_first = contour_first_.get(),
                              .contour_edges = contour_edges_.get(),
                              .cones = cones_.get(),
                              .failed = failed_.get(),
                              .entries = entries_.get(),
                              .level_counter = level_counter,
                              .failed_count = words.contour_failed};
        contour_kernel<<<grid, kContourThreads, 0, stream>>>(t);
        WEFT_CUDA_CHECK_LAUNCH("contour_kernel");
    }
    // Patch ids.
    const std::uint32_t prims = std::max({layout_.vertex_count, layout_.edge_count, layout_.triangle_count});
    if (prims > 0) {
        const AssignParams a{.top = top_.get(),
                             .vertex_leaf = vertex_leaf_.get(),
                             .edge_leaf = edge_leaf_.get(),
                             .triangle_leaf = triangle_leaf_.get(),
                             .vertex_patch = vertex_patch_.get(),
                             .edge_patch = edge_patch_.get(),
                             .triangle_patch = triangle_patch_.get(),
                             .nv = layout_.vertex_count,
                             .ne = layout_.edge_count,
                             .nt = layout_.triangle_count};
        assign_kernel<<<blocks_for(prims, kThreads), kThreads, 0, stream>>>(a);
        WEFT_CUDA_CHECK_LAUNCH("assign_kernel");
    }
}

const GpuNormalConeCounters& GpuNormalConeCulling::read_back(cudaStream_t stream) {
    if (built_) {
        WEFT_CUDA_CHECK(cudaMemcpyAsync(counters_host_.get(), counters_.get(), sizeof(GpuNormalConeCounters),
                                        cudaMemcpyDeviceToHost, stream));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    }
    return *counters_host_.get();
}

void GpuNormalConeCulling::download(std::vector<std::uint32_t>& vertex, std::vector<std::uint32_t>& edge,
                                    std::vector<std::uint32_t>& triangle, cudaStream_t stream) const {
    const auto copy = [&](std::vector<std::uint32_t>& out, const DeviceArray<std::uint32_t>& from) {
        out.resize(from.size());
        if (!out.empty())
            WEFT_CUDA_CHECK(cudaMemcpyAsync(out.data(), from.get(), from.bytes(), cudaMemcpyDeviceToHost, stream));
    };
    copy(vertex, vertex_patch_);
    copy(edge, edge_patch_);
    copy(triangle, triangle_patch_);
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
}

void GpuNormalConeCulling::download_cones(std::vector<GpuCone>& cones, cudaStream_t stream) const {
    cones.resize(cones_.size());
    if (!cones.empty())
        WEFT_CUDA_CHECK(cudaMemcpyAsync(cones.data(), cones_.get(), cones_.bytes(), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
}

}  // namespace weft::cuda::collision
