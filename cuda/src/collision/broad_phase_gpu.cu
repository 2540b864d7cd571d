// The GPU spatial hash (see broad_phase_gpu.h for the pipeline and the float-robustness argument).
// Cells are keyed by their exact packed coordinates, as on the CPU: two different cells never share
// a key, so no pair is invented or lost by a hash collision and the radix sort plays the hash table.
#include "collision/broad_phase_gpu.h"

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <utility>
#include <climits>
#include <string>

#include "cuda_check.h"
#include "grid_size.h"

namespace weft::cuda::collision {
namespace {

// ---- constants and shared state ------------------------------------------------------------------

// 21 bits per axis fit three coordinates in one 64-bit key (as on the CPU). A coordinate is clamped
// to this range; the clamp is monotone, so the search stays exact.
constexpr std::uint32_t kAxisMask = (1U << 21) - 1;
constexpr std::uint8_t kHashed = 0, kNonFinite = 1, kOversized = 2;
constexpr std::uint32_t kNoCloth = 0xFFFFFFFFU;
constexpr unsigned kThreads = 256;
constexpr unsigned kFullMask = 0xFFFFFFFFU;
// Pair slots per lane per warp chunk: a warp takes 32·kSlotsPerLane consecutive slots of the workload
// table at a time. Large enough to amortise the binary search that finds the first row, small enough
// that a few dense cells spread over many warps.
constexpr unsigned kSlotsPerLane = 16;
constexpr unsigned long long kChunk = 32ULL * kSlotsPerLane;

/// The grid of one call, computed on the device (origin from the vertices, cell size from the
/// median edge extent) so that no host round trip is needed.
struct Grid {
    float origin[3];
    float cell, inv_cell;
    std::uint32_t shift[3], mask[3];
    std::uint32_t lo_bits[3], hi_bits[3];  // ordered-float accumulators: min vertex coordinate, max bound
};

/// Counters and grid in one small device block, reset by one kernel at the start of each call.
struct Block {
    GpuBroadPhaseCounters counters;
    Grid grid;
};

/// Everything the kernels read, by value (device pointers and sizes).
struct Params {
    const float* x0;
    const float* x1;
    std::uint32_t n, stride, ne, nt, prims;
    const std::uint32_t* tri;
    const std::uint32_t* edge;
    const std::uint32_t* triangle_cloth;
    std::uint32_t* vertex_cloth;
    bool filter_cloth;
    const std::uint32_t* vertex_patch;
    const std::uint32_t* edge_patch;
    const std::uint32_t* triangle_patch;
    bool cull;
    float thickness;
    const float* padding;  // per vertex, or null
    float4* box_lo;
    float4* box_hi;
    unsigned long long* cell_lo;
    unsigned long long* cell_hi;
    unsigned long long* counts;
    std::uint8_t* state;
    std::uint32_t* oversized;
    std::uint32_t* extent_keys;
    const std::uint32_t* order;  // primitives in (kind, patch, index) order; null: index order
    Block* block;
    std::uint32_t entry_capacity, pair_capacity;
    std::uint32_t key_sort_bits;
    PairEncoding enc;
    std::uint32_t share_index, share_count;  // GpuBroadPhaseInput::share_*
};

// ---- small device helpers ------------------------------------------------------------------------

/// Float ↔ unsigned with the same order, so that min/max over floats become integer atomics (exact
/// and order-independent, hence deterministic).
__device__ inline std::uint32_t ordered(float f) {
    const std::uint32_t u = __float_as_uint(f);
    return (u & 0x80000000U) != 0 ? ~u : (u | 0x80000000U);
}
__device__ inline float from_ordered(std::uint32_t u) {
    return __uint_as_float((u & 0x80000000U) != 0 ? (u & 0x7FFFFFFFU) : ~u);
}

/// Cell coordinate of x along one axis: floor((x − origin)/cell) clamped to [0, 2²¹ − 1]. Each step
/// (a correctly rounded subtraction and product, floor, clamp) is monotone in x, so the whole map is,
/// which is what makes the hash exact: a ≤ b implies cell(a) ≤ cell(b). An infinite bound (a finite
/// position whose inflated bound overflowed) lands in the first or the last cell.
__device__ inline std::uint32_t cell_coord(float x, float origin, float inv_cell) {
    const float c = floorf(__fmul_rn(__fsub_rn(x, origin), inv_cell));
    return c > 0.0F ? (c < static_cast<float>(kAxisMask) ? static_cast<std::uint32_t>(c) : kAxisMask) : 0U;
}

__device__ inline unsigned long long pack(const Grid& g, std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return (static_cast<unsigned long long>(x) << g.shift[0]) | (static_cast<unsigned long long>(y) << g.shift[1]) |
           (static_cast<unsigned long long>(z) << g.shift[2]);
}
__device__ inline std::uint32_t coord(const Grid& g, unsigned long long key, int axis) {
    return static_cast<std::uint32_t>(key >> g.shift[axis]) & g.mask[axis];
}

/// The cell of the minimum corner of two bounds' intersection (the per-axis max of their minimum
/// cells) is this cell: the one cell that reports the pair (docs/methods.md §4).
__device__ inline bool reports_here(const Grid& g, unsigned long long lo_a, unsigned long long lo_b,
                                    unsigned long long cell) {
    for (int k = 0; k < 3; ++k)
        if (max(coord(g, lo_a, k), coord(g, lo_b, k)) != coord(g, cell, k)) return false;
    return true;
}

/// Whether this call's share holds `cell` (multi-GPU detection): cells are dealt to the shares by a
/// mix of their key (splitmix64's finaliser), so that neighbouring cells, and the dense cells of a
/// fold, spread over the GPUs. Every cell is in exactly one share, hence so is the pair it reports.
__device__ inline bool cell_in_share(const Params& p, unsigned long long cell) {
    if (p.share_count == 1) return true;
    unsigned long long z = cell + 0x9E3779B97F4A7C15ULL;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return z % p.share_count == p.share_index;
}

/// Closed boxes: touching bounds overlap. False when either is NaN.
__device__ inline bool overlap(float4 alo, float4 ahi, float4 blo, float4 bhi) {
    return alo.x <= bhi.x && blo.x <= ahi.x && alo.y <= bhi.y && blo.y <= ahi.y && alo.z <= bhi.z && blo.z <= ahi.z;
}

__device__ inline std::uint32_t patch_of(const Params& p, std::uint32_t prim) {
    if (prim < p.n) return p.vertex_patch[prim];
    if (prim < p.n + p.ne) return p.edge_patch[prim - p.n];
    return p.triangle_patch[prim - p.n - p.ne];
}
__device__ inline bool same_patch(const Params& p, std::uint32_t a, std::uint32_t b) {
    if (!p.cull) return false;
    const std::uint32_t pa = patch_of(p, a);
    return pa != kNoPatch && pa == patch_of(p, b);
}
__device__ inline std::uint32_t cloth_of(const Params& p, std::uint32_t prim) {
    if (prim < p.n) return p.vertex_cloth[prim];
    if (prim < p.n + p.ne) return p.vertex_cloth[p.edge[2 * (prim - p.n)]];
    return p.triangle_cloth != nullptr ? p.triangle_cloth[prim - p.n - p.ne] : 0U;
}
/// True when the pair is dropped because both primitives belong to one cloth (self_pairs off).
__device__ inline bool filtered(const Params& p, std::uint32_t a, std::uint32_t b) {
    if (!p.filter_cloth) return false;
    const std::uint32_t ca = cloth_of(p, a);
    return ca != kNoCloth && ca == cloth_of(p, b);
}

/// Entries in use: none after an entry or key-width overflow (the call is rerun; nothing below may
/// read the partly written entries), else the total.
__device__ inline std::uint32_t entries_in_use(const Params& p) {
    const GpuBroadPhaseCounters& c = p.block->counters;
    if ((c.overflow & (kOverflowEntries | kOverflowKeyBits)) != 0) return 0;
    return static_cast<std::uint32_t>(min(c.entries, static_cast<unsigned long long>(p.entry_capacity)));
}

/// Vertex–face candidate test (v a vertex, t a triangle primitive): bounds overlap, v is not a
/// corner of t, and the cloth filter keeps it.
__device__ inline bool vf_candidate(const Params& p, std::uint32_t v, std::uint32_t t) {
    if (!overlap(p.box_lo[v], p.box_hi[v], p.box_lo[t], p.box_hi[t])) return false;
    const std::uint32_t* tv = p.tri + 3 * static_cast<std::size_t>(t - p.n - p.ne);
    if (v == tv[0] || v == tv[1] || v == tv[2]) return false;
    return !filtered(p, v, t);
}
/// Edge–edge candidate test: bounds overlap, no shared vertex, the cloth filter keeps it.
__device__ inline bool ee_candidate(const Params& p, std::uint32_t a, std::uint32_t b) {
    if (!overlap(p.box_lo[a], p.box_hi[a], p.box_lo[b], p.box_hi[b])) return false;
    const std::uint32_t* ea = p.edge + 2 * static_cast<std::size_t>(a - p.n);
    const std::uint32_t* eb = p.edge + 2 * static_cast<std::size_t>(b - p.n);
    if (ea[0] == eb[0] || ea[0] == eb[1] || ea[1] == eb[0] || ea[1] == eb[1]) return false;
    return !filtered(p, a, b);
}

/// One pair from a single thread (the rare oversized path).
__device__ inline void emit_one(const Params& p, unsigned long long key, bool vf, unsigned long long* out) {
    const std::uint32_t idx = atomicAdd(&p.block->counters.pairs, 1U);
    if (vf) atomicAdd(&p.block->counters.vf_pairs, 1U);
    if (idx < p.pair_capacity) out[idx] = key;
}

// ---- bounds, grid, cloth ------------------------------------------------------------------------

__global__ void reset_kernel(Block* b) {
    *b = Block{};
    for (int k = 0; k < 3; ++k) {
        b->grid.lo_bits[k] = 0xFFFFFFFFU;
        b->grid.hi_bits[k] = 0U;
    }
}

// A vertex takes the cloth of the lowest-numbered triangle using it (the CPU takes the first in
// order: the same one). Three launches: reset, atomic minimum (order-free), lookup.
__global__ void cloth_reset_kernel(Params p) {
    const std::uint32_t v = blockIdx.x * blockDim.x + threadIdx.x;
    if (v < p.n) p.vertex_cloth[v] = p.triangle_cloth != nullptr ? 0xFFFFFFFFU : 0U;
}
__global__ void cloth_first_triangle_kernel(Params p) {
    const std::uint32_t t = blockIdx.x * blockDim.x + threadIdx.x;
    if (t >= p.nt) return;
    for (int k = 0; k < 3; ++k) atomicMin(&p.vertex_cloth[p.tri[3 * static_cast<std::size_t>(t) + k]], t);
}
__global__ void cloth_lookup_kernel(Params p) {
    const std::uint32_t v = blockIdx.x * blockDim.x + threadIdx.x;
    if (v >= p.n) return;
    const std::uint32_t first = p.vertex_cloth[v];
    p.vertex_cloth[v] = first == 0xFFFFFFFFU ? kNoCloth : p.triangle_cloth[first];
}

/// Swept, inflated bound of every primitive, rounded outward (the float-robustness argument of the
/// header): the min/max of the exact float positions is exact, then one subtraction rounded down and
/// one addition rounded up. An edge's or triangle's bound computed from its vertices directly is the
/// union of their bounds (rounding is monotone), as on the CPU. Also: the grid's origin (min vertex
/// position) and top (max vertex bound), and each edge's extent for the median cell size.
__global__ void bounds_kernel(Params p) {
    __shared__ std::uint32_t s_lo[3], s_hi[3], s_finite_edges;
    if (threadIdx.x < 3) {
        s_lo[threadIdx.x] = 0xFFFFFFFFU;
        s_hi[threadIdx.x] = 0U;
    }
    if (threadIdx.x == 0) s_finite_edges = 0;
    __syncthreads();
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i < p.prims) {
        std::uint32_t v[3];
        int count = 1;
        v[0] = i;
        if (i >= p.n + p.ne) {
            const std::uint32_t* t = p.tri + 3 * static_cast<std::size_t>(i - p.n - p.ne);
            v[0] = t[0];
            v[1] = t[1];
            v[2] = t[2];
            count = 3;
        } else if (i >= p.n) {
            const std::uint32_t* e = p.edge + 2 * static_cast<std::size_t>(i - p.n);
            v[0] = e[0];
            v[1] = e[1];
            count = 2;
        }
        const float inf = __int_as_float(0x7F800000);
        float lo[3] = {inf, inf, inf}, hi[3] = {-inf, -inf, -inf};
        bool finite = true;
        for (int a = 0; a < count; ++a)
            for (int c = 0; c < 3; ++c) {
                const std::size_t at = v[a] + static_cast<std::size_t>(c) * p.stride;
                const float s = p.x0[at], e = p.x1[at];
                // fminf would silently drop a NaN: a non-finite position poisons the whole box.
                finite = finite && isfinite(s) && isfinite(e);
                lo[c] = fminf(lo[c], fminf(s, e));
                hi[c] = fmaxf(hi[c], fmaxf(s, e));
            }
        const float nan = __int_as_float(0x7FFFFFFF);
        float4 blo{nan, nan, nan, 0.0F}, bhi{nan, nan, nan, 0.0F};
        if (finite) {
            // With padding: thickness + the largest padding of the primitive's vertices, rounded up.
            float grow = p.thickness;
            if (p.padding != nullptr)
                for (int a = 0; a < count; ++a) grow = fmaxf(grow, __fadd_ru(p.thickness, p.padding[v[a]]));
            blo = float4{__fsub_rd(lo[0], grow), __fsub_rd(lo[1], grow), __fsub_rd(lo[2], grow), 0.0F};
            bhi = float4{__fadd_ru(hi[0], grow), __fadd_ru(hi[1], grow), __fadd_ru(hi[2], grow), 0.0F};
        }
        p.box_lo[i] = blo;
        p.box_hi[i] = bhi;
        // The grid's top covers every bound: a padded edge or triangle may reach past its vertices'
        // own bounds (below the origin, cell coordinates clamp to 0, which keeps overlaps).
        if (p.padding != nullptr && i >= p.n && finite) {
            atomicMax(&s_hi[0], ordered(bhi.x));
            atomicMax(&s_hi[1], ordered(bhi.y));
            atomicMax(&s_hi[2], ordered(bhi.z));
        }
        if (i < p.n && finite) {
            for (int c = 0; c < 3; ++c) atomicMin(&s_lo[c], ordered(lo[c]));
            atomicMax(&s_hi[0], ordered(bhi.x));
            atomicMax(&s_hi[1], ordered(bhi.y));
            atomicMax(&s_hi[2], ordered(bhi.z));
        }
        if (i >= p.n && i < p.n + p.ne && p.extent_keys != nullptr) {
            const float extent = fmaxf(bhi.x - blo.x, fmaxf(bhi.y - blo.y, bhi.z - blo.z));
            // Non-negative floats order like their bit patterns; non-finite extents sort last.
            const bool ok = finite && isfinite(extent);
            p.extent_keys[i - p.n] = ok ? __float_as_uint(extent) : 0xFFFFFFFFU;
            if (ok) atomicAdd(&s_finite_edges, 1U);
        }
    }
    __syncthreads();
    Block* b = p.block;
    if (threadIdx.x < 3) {
        if (s_lo[threadIdx.x] != 0xFFFFFFFFU) atomicMin(&b->grid.lo_bits[threadIdx.x], s_lo[threadIdx.x]);
        if (s_hi[threadIdx.x] != 0U) atomicMax(&b->grid.hi_bits[threadIdx.x], s_hi[threadIdx.x]);
    }
    if (threadIdx.x == 0 && s_finite_edges > 0) atomicAdd(&b->counters.finite_edges, s_finite_edges);
}

/// The grid: the cell size (given, or the median edge extent from the sorted extents, as the CPU:
/// cells about as large as the primitives keep both the entries per primitive and the occupants per
/// cell small), the origin and the key packing (each axis in just the bits its range needs).
__global__ void grid_kernel(Params p, const std::uint32_t* sorted_extents, float fixed_cell) {
    Block* b = p.block;
    Grid& g = b->grid;
    GpuBroadPhaseCounters& c = b->counters;
    const bool any = g.lo_bits[0] != 0xFFFFFFFFU;  // some vertex is finite
    float top[3];
    for (int k = 0; k < 3; ++k) {
        g.origin[k] = any ? from_ordered(g.lo_bits[k]) : 0.0F;
        top[k] = any ? from_ordered(g.hi_bits[k]) : 0.0F;
    }
    float cell = fixed_cell;
    if (!(cell > 0.0F) && sorted_extents != nullptr && c.finite_edges > 0)
        cell = __uint_as_float(sorted_extents[c.finite_edges / 2]);
    if (!(cell > 0.0F) || !isfinite(cell)) {
        // No edges, or all of them points: any positive size is correct; a scene-sized cell is cheap.
        cell = fmaxf(top[0] - g.origin[0], fmaxf(top[1] - g.origin[1], top[2] - g.origin[2]));
        if (!(cell > 0.0F) || !isfinite(cell)) cell = 1.0F;
    }
    float inv = 1.0F / cell;
    if (!(inv > 0.0F) || !isfinite(inv)) {  // a subnormal cell: the inverse must stay finite
        cell = 1.0F;
        inv = 1.0F;
    }
    g.cell = cell;
    g.inv_cell = inv;
    std::uint32_t bits = 0;
    for (int k = 0; k < 3; ++k) {
        const std::uint32_t top_cell = any ? cell_coord(top[k], g.origin[k], inv) : 0U;
        const std::uint32_t width = top_cell == 0 ? 0U : 32U - static_cast<std::uint32_t>(__clz(top_cell));
        g.shift[k] = bits;
        g.mask[k] = width == 0 ? 0U : (0xFFFFFFFFU >> (32U - width));
        bits += width;
    }
    c.cell_size = cell;
    c.key_bits = bits;
    if (bits > p.key_sort_bits) c.overflow |= kOverflowKeyBits;
}

/// With culling: each primitive's sort key (kind, patch). Sorted stably with the primitive index as
/// value, it orders the primitives by (kind, patch, index), which the stable cell sort then keeps
/// inside every cell: the cell key extended with the cone id (PSCC), so that a patch's occupants of a
/// cell are one contiguous run the workload can skip as a whole.
__global__ void patch_order_kernel(Params p, unsigned long long* keys, std::uint32_t* values) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= p.prims) return;
    const unsigned long long kind = i < p.n ? 0ULL : (i < p.n + p.ne ? 1ULL : 2ULL);
    keys[i] = (kind << 32) | patch_of(p, i);
    values[i] = i;
}

// ---- count, scan, entries -----------------------------------------------------------------------

/// Cells of each bound, in (patch) order: counts[q] for the q-th primitive, 0 for the skipped ones.
/// A bound over more than kMaxCellsPerPrimitive cells goes to the oversized list instead.
__global__ void count_kernel(Params p) {
    const std::uint32_t q = blockIdx.x * blockDim.x + threadIdx.x;
    if (q > p.prims) return;
    if (q == p.prims) {  // the scan's last element, so that counts[prims] becomes the total
        p.counts[q] = 0;
        return;
    }
    const std::uint32_t prim = p.order != nullptr ? p.order[q] : q;
    const float4 lo = p.box_lo[prim], hi = p.box_hi[prim];
    unsigned long long count = 0;
    std::uint8_t state = kHashed;
    if (!(lo.x == lo.x)) {  // NaN: a non-finite position
        state = kNonFinite;
        atomicAdd(&p.block->counters.nonfinite, 1U);
    } else {
        const Grid& g = p.block->grid;
        const float l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
        std::uint32_t cl[3], ch[3];
        unsigned long long cells = 1;
        for (int k = 0; k < 3; ++k) {
            cl[k] = cell_coord(l[k], g.origin[k], g.inv_cell);
            ch[k] = cell_coord(h[k], g.origin[k], g.inv_cell);
            cells *= ch[k] - cl[k] + 1ULL;  // ≤ 2^63: no overflow
        }
        p.cell_lo[prim] = pack(g, cl[0], cl[1], cl[2]);
        p.cell_hi[prim] = pack(g, ch[0], ch[1], ch[2]);
        if (cells > kMaxCellsPerPrimitive) {
            state = kOversized;
            p.oversized[atomicAdd(&p.block->counters.oversized, 1U)] = prim;
        } else if (p.share_count == 1) {
            count = cells;
        } else {
            // Only the cells of this share are hashed here (at most kMaxCellsPerPrimitive to look at).
            for (std::uint32_t z = cl[2]; z <= ch[2]; ++z)
                for (std::uint32_t y = cl[1]; y <= ch[1]; ++y)
                    for (std::uint32_t x = cl[0]; x <= ch[0]; ++x) count += cell_in_share(p, pack(g, x, y, z)) ? 1 : 0;
        }
    }
    p.state[prim] = state;
    p.counts[q] = count;
}

/// The (cell key, primitive) entries of each hashed primitive at its scanned offset, in (patch)
/// order, so that the stable sort keeps (kind, patch, index) order within a cell as the CPU does.
/// Nothing is written past the capacity; the overflow is flagged and the call rerun.
__global__ void fill_kernel(Params p, unsigned long long* keys, std::uint32_t* prims) {
    const std::uint32_t q = blockIdx.x * blockDim.x + threadIdx.x;
    if (q >= p.prims) return;
    const unsigned long long total = p.counts[p.prims];
    if (q == 0) {
        p.block->counters.entries = total;
        if (total > p.entry_capacity) p.block->counters.overflow |= kOverflowEntries;
    }
    const std::uint32_t prim = p.order != nullptr ? p.order[q] : q;
    if (p.state[prim] != kHashed || total > p.entry_capacity) return;
    const Grid& g = p.block->grid;
    unsigned long long at = p.counts[q];
    const unsigned long long lo = p.cell_lo[prim], hi = p.cell_hi[prim];
    for (std::uint32_t z = coord(g, lo, 2); z <= coord(g, hi, 2); ++z)
        for (std::uint32_t y = coord(g, lo, 1); y <= coord(g, hi, 1); ++y)
            for (std::uint32_t x = coord(g, lo, 0); x <= coord(g, hi, 0); ++x) {
                const unsigned long long key = pack(g, x, y, z);
                if (!cell_in_share(p, key)) continue;
                keys[at] = key;
                prims[at] = prim;
                ++at;
            }
}

/// The unused tail of the entry buffer sorts last and is never read as an entry.
__global__ void pad_entries_kernel(Params p, unsigned long long* keys, std::uint32_t* prims) {
    const std::uint32_t e = blockIdx.x * blockDim.x + threadIdx.x;
    if (e >= p.entry_capacity || e < entries_in_use(p)) return;
    keys[e] = ~0ULL;
    prims[e] = 0xFFFFFFFFU;
}

// ---- cell ranges and the workload table ----------------------------------------------------------

/// 1 where a cell starts; the inclusive sum then numbers the cells (1-based) in every entry.
__global__ void cell_flags_kernel(Params p, const unsigned long long* keys, std::uint32_t* cell_id) {
    const std::uint32_t e = blockIdx.x * blockDim.x + threadIdx.x;
    if (e >= p.entry_capacity) return;
    const std::uint32_t used = entries_in_use(p);
    cell_id[e] = e < used && (e == 0 || keys[e] != keys[e - 1]) ? 1U : 0U;
}

__global__ void cell_begin_kernel(Params p, const std::uint32_t* cell_id, std::uint32_t* cell_begin) {
    const std::uint32_t e = blockIdx.x * blockDim.x + threadIdx.x;
    const std::uint32_t used = entries_in_use(p);
    if (e >= used) return;
    const std::uint32_t c = cell_id[e];
    if (e == 0 || cell_id[e - 1] != c) cell_begin[c - 1] = e;
    if (e == used - 1) {
        cell_begin[c] = used;
        p.block->counters.cells_occupied = c;
    }
}

/// The workload of each occupant ("row") of a cell: the partners it is tested against there, as one
/// or two runs of the cell's entries. Within a cell the occupants are vertices, then edges, then
/// triangles, each kind in (patch, index) order; a vertex row pairs with the cell's triangles except
/// the run of its own patch, an edge row with the edges after it except the run of its own patch
/// right behind it (kNoPatch sorts last and is never skipped), a triangle row with nothing. The
/// exclusive sum of these counts is the workload table: PSCC's per-cell pair counts (Tang et al.
/// 2018; P-Cloth, Tang et al. 2020), kept per row so that a slot's partner follows from its offset
/// in the row without solving for it (which culling, cutting a run out of the partners, would make
/// awkward), and so that one huge cell is shared out row by row and slot by slot.
__global__ void rows_kernel(Params p, const std::uint32_t* prims, const std::uint32_t* cell_id,
                            const std::uint32_t* cell_begin, unsigned long long* row_count, uint4* row_info) {
    const std::uint32_t e = blockIdx.x * blockDim.x + threadIdx.x;
    if (e > p.entry_capacity) return;
    const std::uint32_t used = entries_in_use(p);
    if (e >= used) {
        row_count[e] = 0;  // also the element at `capacity`, which the scan turns into the total
        return;
    }
    const std::uint32_t prim = prims[e];
    const std::uint32_t c = cell_id[e] - 1;
    const std::uint32_t cb = cell_begin[c], ce = cell_begin[c + 1];
    if (e == cb) atomicMax(&p.block->counters.max_cell_entries, ce - cb);
    const std::uint32_t edge0 = p.n, tri0 = p.n + p.ne;
    unsigned long long count = 0;
    uint4 info{0, 0, 0, 0};
    if (prim < tri0) {
        // First triangle of the cell: kinds are in order, so "is a triangle" is monotone.
        std::uint32_t lo = e + 1, hi = ce;
        while (lo < hi) {
            const std::uint32_t mid = lo + (hi - lo) / 2;
            if (prims[mid] >= tri0) hi = mid; else lo = mid + 1;
        }
        const std::uint32_t ft = lo;
        if (prim < edge0) {
            std::uint32_t gb = ce, ge = ce;  // the triangles [gb, ge) share the vertex's patch
            const std::uint32_t patch = p.cull ? p.vertex_patch[prim] : kNoPatch;
            if (patch != kNoPatch) {
                std::uint32_t a = ft, z = ce;
                while (a < z) {
                    const std::uint32_t mid = a + (z - a) / 2;
                    if (p.triangle_patch[prims[mid] - tri0] >= patch) z = mid; else a = mid + 1;
                }
                gb = a;
                z = ce;
                while (a < z) {
                    const std::uint32_t mid = a + (z - a) / 2;
                    if (p.triangle_patch[prims[mid] - tri0] > patch) z = mid; else a = mid + 1;
                }
                ge = a;
            }
            info = uint4{ft, gb - ft, ge, 0};
            count = (gb - ft) + (ce - ge);
        } else {
            std::uint32_t start = e + 1;
            const std::uint32_t patch = p.cull ? p.edge_patch[prim - edge0] : kNoPatch;
            if (patch != kNoPatch) {  // skip the edges of the same patch right behind this one
                std::uint32_t z = ft;
                while (start < z) {
                    const std::uint32_t mid = start + (z - start) / 2;
                    if (p.edge_patch[prims[mid] - edge0] > patch) z = mid; else start = mid + 1;
                }
            }
            info = uint4{start, ft - start, ft, 0};
            count = ft - start;
        }
    }
    row_count[e] = count;
    row_info[e] = info;
}

// ---- pairs ---------------------------------------------------------------------------------------

/// Appends the found pairs of a warp with one atomic (warp-aggregated); all 32 lanes must call it.
__device__ inline void warp_append(const Params& p, bool found, bool vf, unsigned long long key, unsigned long long* out) {
    const unsigned mask = __ballot_sync(kFullMask, found);
    if (mask == 0) return;
    const unsigned vf_mask = __ballot_sync(kFullMask, found && vf);
    const unsigned lane = threadIdx.x & 31U;
    const unsigned leader = static_cast<unsigned>(__ffs(static_cast<int>(mask))) - 1U;
    std::uint32_t base = 0;
    if (lane == leader) {
        base = atomicAdd(&p.block->counters.pairs, static_cast<std::uint32_t>(__popc(mask)));
        if (vf_mask != 0) atomicAdd(&p.block->counters.vf_pairs, static_cast<std::uint32_t>(__popc(vf_mask)));
    }
    base = __shfl_sync(kFullMask, base, static_cast<int>(leader));
    if (found) {
        const std::uint32_t idx = base + static_cast<std::uint32_t>(__popc(mask & ((1U << lane) - 1U)));
        if (idx < p.pair_capacity) out[idx] = key;
    }
}

/// The row of slot s, from the row r of an earlier slot: the last row whose offset is ≤ s (its offset
/// range then holds s, however many empty rows share that offset). Galloping (exponential, then
/// binary) search: a step or two in dense cells, O(log distance) across the long runs of empty rows
/// that culling leaves (every occupant of a cell inside one patch has no partner there), where a
/// row-by-row walk cost a lane thousands of loads (measured: 8× slower pair generation on the culled
/// twist than on the unculled one).
__device__ inline std::uint32_t next_row(const unsigned long long* row_offset, std::uint32_t cap, std::uint32_t r,
                                         unsigned long long s) {
    if (row_offset[r + 1] > s) return r;  // row_offset[cap] = total > s: r + 1 ≤ cap is safe to read
    std::uint32_t lo = r + 1, hi = cap, step = 1;  // row_offset[lo] ≤ s < row_offset[hi]
    while (true) {
        const std::uint32_t probe = lo + step;  // lo < cap ≤ 2^31 and step < 2·cap: no overflow
        if (probe >= cap || row_offset[probe] > s) {
            hi = probe < cap ? probe : cap;
            break;
        }
        lo = probe;
        step <<= 1;
    }
    while (hi - lo > 1) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        if (row_offset[mid] <= s) lo = mid; else hi = mid;
    }
    return lo;
}

/// Pair generation balanced by the workload table. The slots [0, total) are cut into chunks of
/// 32·kSlotsPerLane; a warp takes a chunk at a time (grid-stride), lane l the slots l, l + 32, … of
/// it, so neighbouring lanes test neighbouring partners of one row (coalesced loads). Each lane finds
/// its first row by binary search in the table, then gallops forward (next_row). A dense cell is thus spread over
/// as many warps as its slots fill, instead of serialising one thread (Tang et al. 2018, 2020).
/// Per slot: the min-corner rule first (cheap, and it discards the pairs other cells report), then
/// the bounds, then adjacency and the cloth filter.
__global__ void __launch_bounds__(kThreads) pairs_kernel(Params p, const unsigned long long* keys,
                                                         const std::uint32_t* prims,
                                                         const unsigned long long* row_offset,
                                                         const uint4* row_info, unsigned long long* out) {
    const Grid g = p.block->grid;
    const std::uint32_t cap = p.entry_capacity;
    // Every slot of the table: across GPUs the table holds only this share's cells.
    const unsigned long long first = 0;
    const unsigned long long total = row_offset[cap];
    const unsigned lane = threadIdx.x & 31U;
    const unsigned long long warp = (static_cast<unsigned long long>(blockIdx.x) * blockDim.x + threadIdx.x) >> 5;
    const unsigned long long warps = (static_cast<unsigned long long>(gridDim.x) * blockDim.x) >> 5;
    const std::uint32_t edge0 = p.n, tri0 = p.n + p.ne;
    for (unsigned long long base = first + warp * kChunk; base < total; base += warps * kChunk) {
        // The row of this lane's first slot: the last row whose offset is ≤ the slot.
        std::uint32_t r = 0;
        {
            const unsigned long long s = base + lane;
            std::uint32_t lo = 0, hi = cap;  // row_offset[0] = 0 ≤ s < row_offset[cap] = total
            if (s < total) {
                while (hi - lo > 1) {
                    const std::uint32_t mid = lo + (hi - lo) / 2;
                    if (row_offset[mid] <= s) lo = mid; else hi = mid;
                }
            }
            r = lo;
        }
        std::uint32_t cached = 0xFFFFFFFFU;
        std::uint32_t pa = 0;
        uint4 info{};
        unsigned long long row_start = 0, cell = 0, lo_a = 0;
        for (unsigned k = 0; k < kSlotsPerLane; ++k) {
            const unsigned long long s = base + k * 32ULL + lane;
            bool found = false, vf = false;
            unsigned long long key = 0;
            if (s < total) {
                r = next_row(row_offset, cap, r, s);
                if (r != cached) {
                    cached = r;
                    pa = prims[r];
                    info = row_info[r];
                    row_start = row_offset[r];
                    cell = keys[r];
                    lo_a = p.cell_lo[pa];
                }
                const auto o = static_cast<std::uint32_t>(s - row_start);
                const std::uint32_t j = o < info.y ? info.x + o : info.z + (o - info.y);
                const std::uint32_t pb = prims[j];
                if (reports_here(g, lo_a, p.cell_lo[pb], cell)) {
                    if (pa < edge0) {
                        vf = true;
                        found = vf_candidate(p, pa, pb);
                        if (found) key = p.enc.vf(pa, pb - tri0);
                    } else {
                        found = ee_candidate(p, pa, pb);
                        const std::uint32_t a = pa - edge0, b = pb - edge0;
                        if (found) key = p.enc.ee(min(a, b), max(a, b));
                    }
                }
            }
            warp_append(p, found, vf, key, out);
        }
    }
}

/// Oversized primitives against every partner, as on the CPU: a vertex against all triangles, an
/// edge against all edges (a pair of two oversized edges from the lower one only), a triangle against
/// the hashed vertices (oversized ones were paired from the vertex side). Rare (an exploding vertex,
/// a cell far too small); a fixed grid reads the list's length from the device.
__global__ void oversized_kernel(Params p, unsigned long long* out) {
    const std::uint32_t count = p.block->counters.oversized;
    const std::uint32_t tid = blockIdx.x * blockDim.x + threadIdx.x, stride = gridDim.x * blockDim.x;
    const std::uint32_t edge0 = p.n, tri0 = p.n + p.ne;
    unsigned long long tested = 0;
    for (std::uint32_t o = 0; o < count; ++o) {
        const std::uint32_t a = p.oversized[o];
        // The share by primitive id, not by place in the list: the list's order is the atomics'.
        if (a % p.share_count != p.share_index) continue;
        if (a < edge0) {
            for (std::uint32_t i = tid; i < p.nt; i += stride) {
                const std::uint32_t t = tri0 + i;
                if (p.state[t] == kNonFinite || same_patch(p, a, t)) continue;
                ++tested;
                if (vf_candidate(p, a, t)) emit_one(p, p.enc.vf(a, i), true, out);
            }
        } else if (a < tri0) {
            for (std::uint32_t i = tid; i < p.ne; i += stride) {
                const std::uint32_t b = edge0 + i;
                if (b == a || p.state[b] == kNonFinite || (p.state[b] == kOversized && b < a) || same_patch(p, a, b))
                    continue;
                ++tested;
                if (ee_candidate(p, a, b)) {
                    const std::uint32_t ia = a - edge0;
                    emit_one(p, p.enc.ee(min(ia, i), max(ia, i)), false, out);
                }
            }
        } else {
            for (std::uint32_t v = tid; v < p.n; v += stride) {
                if (p.state[v] != kHashed || same_patch(p, v, a)) continue;
                ++tested;
                if (vf_candidate(p, v, a)) emit_one(p, p.enc.vf(v, a - tri0), true, out);
            }
        }
    }
    if (tested > 0) atomicAdd(&p.block->counters.tested_pairs, tested);
}

__global__ void pad_pairs_kernel(Params p, unsigned long long* keys) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= p.pair_capacity || i < p.block->counters.pairs) return;
    keys[i] = kPadKey;
}

__global__ void finish_kernel(Params p, const unsigned long long* row_offset) {
    GpuBroadPhaseCounters& c = p.block->counters;
    c.tested_pairs += row_offset[p.entry_capacity];  // the slots of this share's cells
    c.ee_pairs = c.pairs - c.vf_pairs;
    if (c.pairs > p.pair_capacity) c.overflow |= kOverflowPairs;
}

// ---- host helpers --------------------------------------------------------------------------------

template <typename T>
void ensure(DeviceArray<T>& a, std::size_t count, MemoryLedger& ledger, const char* purpose) {
    if (count == 0) count = 1;  // keep a valid pointer for kernels that take the array
    if (a.size() < count) a.allocate(count, ledger, purpose);
}

void check_cub(cudaError_t err, const char* what, const char* file, int line) {
    if (err != cudaSuccess) throw_cuda_error(err, what, file, line);
}
#define WEFT_CUB_CHECK(call) check_cub((call), #call, __FILE__, __LINE__)

}  // namespace

// ---- GpuBroadPhase -------------------------------------------------------------------------------

GpuBroadPhase::GpuBroadPhase(Capacities initial)
    : entry_capacity_(initial.entries), pair_capacity_(initial.pairs) {
    counters_host_.allocate(1);
    *counters_host_.get() = GpuBroadPhaseCounters{};
}

GpuBroadPhase::~GpuBroadPhase() { set_stage_timing(false); }

void GpuBroadPhase::set_stage_timing(bool enabled) {
    if (enabled == timing_) return;
    for (cudaEvent_t& e : events_) {
        if (enabled) {
            WEFT_CUDA_CHECK(cudaEventCreate(&e));
        } else if (e != nullptr) {
            cudaEventDestroy(e);
            e = nullptr;
        }
    }
    timing_ = enabled;
}

std::array<float, GpuBroadPhase::kStageCount> GpuBroadPhase::stage_ms() const {
    std::array<float, kStageCount> ms{};
    if (!timing_) return ms;
    for (int s = 0; s < kStageCount; ++s) WEFT_CUDA_CHECK(cudaEventElapsedTime(&ms[s], events_[s], events_[s + 1]));
    return ms;
}

void GpuBroadPhase::mark(Stage stage, cudaStream_t stream) {
    if (timing_) WEFT_CUDA_CHECK(cudaEventRecord(events_[stage + 1], stream));
}

std::size_t GpuBroadPhase::pair_memory_bytes() const { return pair_keys_[0].bytes() + pair_keys_[1].bytes(); }

std::size_t GpuBroadPhase::memory_bytes() const {
    std::size_t b = box_lo_.bytes() + box_hi_.bytes() + cell_lo_.bytes() + cell_hi_.bytes() + counts_.bytes() +
                    state_.bytes() + oversized_.bytes() + vertex_cloth_.bytes() + cell_id_.bytes() +
                    cell_begin_.bytes() + row_offset_.bytes() + row_info_.bytes() + block_.bytes() + temp_.bytes();
    for (int k = 0; k < 2; ++k)
        b += extent_keys_[k].bytes() + order_keys_[k].bytes() + order_[k].bytes() + entry_keys_[k].bytes() +
             entry_prims_[k].bytes() + pair_keys_[k].bytes();
    return b;
}

void GpuBroadPhase::reserve(const GpuBroadPhaseInput& in, std::uint32_t prims) {
    if (entry_capacity_ == 0) entry_capacity_ = std::max<std::size_t>(1024, 8 * std::size_t{prims});
    if (pair_capacity_ == 0) pair_capacity_ = std::max<std::size_t>(1024, 4 * std::size_t{prims});
    // Launch sizes and CUB item counts are 32-bit (kernels index with uint32).
    constexpr std::size_t kMaxItems = std::size_t{INT_MAX} - 1;
    if (entry_capacity_ > kMaxItems || pair_capacity_ > kMaxItems)
        throw Error("GPU broad phase: more than 2^31 entries or pairs needed (entries " + std::to_string(entry_capacity_) +
                    ", pairs " + std::to_string(pair_capacity_) + ")");
    if (trimmed_entries_ != 0 || trimmed_pairs_ != 0) {
        // The last window cut the capacities (needs_rerun): the arrays they size, and the CUB scratch
        // sized by them, are allocated again below at the new sizes. Freeing waits for the device, so
        // nothing of the last call still reads them.
        if (trimmed_entries_ != 0) entry_capacity_ = std::exchange(trimmed_entries_, 0);
        if (trimmed_pairs_ != 0) pair_capacity_ = std::exchange(trimmed_pairs_, 0);
        for (auto& a : entry_keys_) a = {};
        for (auto& a : entry_prims_) a = {};
        for (auto& a : pair_keys_) a = {};
        cell_id_ = {};
        cell_begin_ = {};
        row_offset_ = {};
        row_info_ = {};
        temp_ = {};
        ++trims_;
    }
    const bool cull = in.vertex_patch != nullptr;
    const std::size_t ec = entry_capacity_, pc = pair_capacity_;
    ensure(box_lo_, prims, ledger_, "collision: bounds");
    ensure(box_hi_, prims, ledger_, "collision: bounds");
    ensure(cell_lo_, prims, ledger_, "collision: cells");
    ensure(cell_hi_, prims, ledger_, "collision: cells");
    ensure(counts_, std::size_t{prims} + 1, ledger_, "collision: counts");
    ensure(state_, prims, ledger_, "collision: state");
    ensure(oversized_, prims, ledger_, "collision: oversized");
    if (!in.self_pairs) ensure(vertex_cloth_, in.vertex_count, ledger_, "collision: cloth");
    if (in.cell_size == 0.0)
        for (auto& a : extent_keys_) ensure(a, in.edge_count, ledger_, "collision: extents");
    if (cull) {
        for (auto& a : order_keys_) ensure(a, prims, ledger_, "collision: patch order");
        for (auto& a : order_) ensure(a, prims, ledger_, "collision: patch order");
    }
    for (auto& a : entry_keys_) ensure(a, ec, ledger_, "collision: entries");
    for (auto& a : entry_prims_) ensure(a, ec, ledger_, "collision: entries");
    ensure(cell_id_, ec, ledger_, "collision: cells");
    ensure(cell_begin_, ec + 1, ledger_, "collision: cells");
    ensure(row_offset_, ec + 1, ledger_, "collision: workload");
    ensure(row_info_, ec, ledger_, "collision: workload");
    for (auto& a : pair_keys_) ensure(a, pc, ledger_, "collision: pairs");
    ensure(block_, sizeof(Block), ledger_, "collision: counters");

    // CUB scratch: the largest any call needs at these sizes (a host-side query, no device work).
    std::size_t need = 0, bytes = 0;
    const auto take = [&](cudaError_t err) {
        if (err != cudaSuccess) throw_cuda_error(err, "CUB temporary storage query", __FILE__, __LINE__);
        need = std::max(need, bytes);
    };
    {
        cub::DoubleBuffer<std::uint32_t> k(extent_keys_[0].get(), extent_keys_[1].get());
        take(cub::DeviceRadixSort::SortKeys(nullptr, bytes, k, std::max<std::uint32_t>(in.edge_count, 1), 0, 32));
    }
    if (cull) {
        cub::DoubleBuffer<unsigned long long> k(order_keys_[0].get(), order_keys_[1].get());
        cub::DoubleBuffer<std::uint32_t> v(order_[0].get(), order_[1].get());
        take(cub::DeviceRadixSort::SortPairs(nullptr, bytes, k, v, prims, 0, 34));
    }
    take(cub::DeviceScan::ExclusiveSum(nullptr, bytes, counts_.get(), prims + 1U));
    {
        cub::DoubleBuffer<unsigned long long> k(entry_keys_[0].get(), entry_keys_[1].get());
        cub::DoubleBuffer<std::uint32_t> v(entry_prims_[0].get(), entry_prims_[1].get());
        take(cub::DeviceRadixSort::SortPairs(nullptr, bytes, k, v, static_cast<std::uint32_t>(ec), 0, key_sort_bits_));
    }
    take(cub::DeviceScan::InclusiveSum(nullptr, bytes, cell_id_.get(), static_cast<std::uint32_t>(ec)));
    take(cub::DeviceScan::ExclusiveSum(nullptr, bytes, row_offset_.get(), static_cast<std::uint32_t>(ec + 1)));
    {
        cub::DoubleBuffer<unsigned long long> k(pair_keys_[0].get(), pair_keys_[1].get());
        take(cub::DeviceRadixSort::SortKeys(nullptr, bytes, k, static_cast<std::uint32_t>(pc), 0,
                                            static_cast<int>(encoding_.sort_bits)));
    }
    ensure(temp_, need, ledger_, "collision: CUB scratch");

    if (multiprocessors_ == 0) {
        int device = 0;
        WEFT_CUDA_CHECK(cudaGetDevice(&device));
        WEFT_CUDA_CHECK(cudaDeviceGetAttribute(&multiprocessors_, cudaDevAttrMultiProcessorCount, device));
    }
}

void GpuBroadPhase::enqueue(const GpuBroadPhaseInput& in, cudaStream_t stream) {
    // ---- host-side checks (the device trusts its input) ----
    const std::uint64_t prims64 = std::uint64_t{in.vertex_count} + in.edge_count + in.triangle_count;
    if (prims64 >= 0xFFFFFFFFULL) throw Error("GPU broad phase: more than 2^32 vertices, edges and triangles together");
    if (!std::isfinite(in.thickness) || in.thickness < 0.0)
        throw Error("GPU broad phase: thickness must be finite and non-negative (got " + std::to_string(in.thickness) + ")");
    if (!std::isfinite(in.cell_size) || in.cell_size < 0.0)
        throw Error("GPU broad phase: cell size must be finite and non-negative (got " + std::to_string(in.cell_size) + ")");
    if (in.vertex_count > 0 && (in.x0 == nullptr || in.x1 == nullptr))
        throw Error("GPU broad phase: positions missing");
    if ((in.triangle_count > 0 && in.triangles == nullptr) || (in.edge_count > 0 && in.edges == nullptr))
        throw Error("GPU broad phase: triangles or edges missing");
    if (in.stride != 0 && in.stride < in.vertex_count)
        throw Error("GPU broad phase: component stride " + std::to_string(in.stride) + " below the vertex count " +
                    std::to_string(in.vertex_count));
    if (in.share_count == 0 || in.share_index >= in.share_count)
        throw Error("GPU broad phase: share " + std::to_string(in.share_index) + " of " + std::to_string(in.share_count));
    const bool cull = in.vertex_patch != nullptr || in.edge_patch != nullptr || in.triangle_patch != nullptr;
    if (cull && ((in.vertex_count > 0 && in.vertex_patch == nullptr) || (in.edge_count > 0 && in.edge_patch == nullptr) ||
                 (in.triangle_count > 0 && in.triangle_patch == nullptr)))
        throw Error("GPU broad phase: patch ids must be given for vertices, edges and triangles, or for none");

    const auto prims = static_cast<std::uint32_t>(prims64);
    encoding_ = make_pair_encoding(in.vertex_count, in.edge_count, in.triangle_count);
    const bool auto_cell = in.cell_size == 0.0;
    reserve(in, prims);
    if (timing_) WEFT_CUDA_CHECK(cudaEventRecord(events_[0], stream));

    Block* block = reinterpret_cast<Block*>(block_.get());
    Params p{};
    p.x0 = in.x0;
    p.x1 = in.x1;
    p.n = in.vertex_count;
    p.stride = in.stride != 0 ? in.stride : in.vertex_count;
    p.ne = in.edge_count;
    p.nt = in.triangle_count;
    p.prims = prims;
    p.tri = in.triangles;
    p.edge = in.edges;
    p.triangle_cloth = in.triangle_cloth;
    p.vertex_cloth = vertex_cloth_.get();
    p.filter_cloth = !in.self_pairs;
    p.cull = cull;
    p.vertex_patch = in.vertex_patch;
    p.edge_patch = in.edge_patch;
    p.triangle_patch = in.triangle_patch;
    p.thickness = float_at_least(in.thickness);
    p.padding = in.vertex_padding;
    p.box_lo = box_lo_.get();
    p.box_hi = box_hi_.get();
    p.cell_lo = cell_lo_.get();
    p.cell_hi = cell_hi_.get();
    p.counts = counts_.get();
    p.state = state_.get();
    p.oversized = oversized_.get();
    p.extent_keys = auto_cell ? extent_keys_[0].get() : nullptr;
    p.order = nullptr;
    p.block = block;
    p.entry_capacity = static_cast<std::uint32_t>(entry_capacity_);
    p.pair_capacity = static_cast<std::uint32_t>(pair_capacity_);
    p.key_sort_bits = static_cast<std::uint32_t>(key_sort_bits_);
    p.enc = encoding_;
    p.share_index = in.share_index;
    p.share_count = in.share_count;
    void* temp = temp_.get();
    // A fresh size for each CUB call (the argument is in/out).
    struct Scratch {
        std::size_t allocated, bytes = 0;
        std::size_t& operator()() {
            bytes = allocated;
            return bytes;
        }
    } scratch{temp_.bytes()};

    // ---- bounds ----
    reset_kernel<<<1, 1, 0, stream>>>(block);
    WEFT_CUDA_CHECK_LAUNCH("reset_kernel");
    if (p.filter_cloth && p.n > 0) {
        cloth_reset_kernel<<<blocks_for(p.n, kThreads), kThreads, 0, stream>>>(p);
        WEFT_CUDA_CHECK_LAUNCH("cloth_reset_kernel");
        if (in.triangle_cloth != nullptr) {
            if (p.nt > 0) {
                cloth_first_triangle_kernel<<<blocks_for(p.nt, kThreads), kThreads, 0, stream>>>(p);
                WEFT_CUDA_CHECK_LAUNCH("cloth_first_triangle_kernel");
            }
            cloth_lookup_kernel<<<blocks_for(p.n, kThreads), kThreads, 0, stream>>>(p);
            WEFT_CUDA_CHECK_LAUNCH("cloth_lookup_kernel");
        }
    }
    if (prims > 0) {
        bounds_kernel<<<blocks_for(prims, kThreads), kThreads, 0, stream>>>(p);
        WEFT_CUDA_CHECK_LAUNCH("bounds_kernel");
    }
    mark(Bounds, stream);

    // ---- cell size (median edge extent) and grid ----
    const std::uint32_t* sorted_extents = nullptr;
    if (auto_cell && p.ne > 0) {
        cub::DoubleBuffer<std::uint32_t> k(extent_keys_[0].get(), extent_keys_[1].get());
        WEFT_CUB_CHECK(cub::DeviceRadixSort::SortKeys(temp, scratch(), k, p.ne, 0, 32, stream));
        sorted_extents = k.Current();
    }
    grid_kernel<<<1, 1, 0, stream>>>(p, sorted_extents, auto_cell ? 0.0F : static_cast<float>(in.cell_size));
    WEFT_CUDA_CHECK_LAUNCH("grid_kernel");
    mark(CellSize, stream);

    // ---- primitives in (kind, patch, index) order ----
    if (cull && prims > 0) {
        patch_order_kernel<<<blocks_for(prims, kThreads), kThreads, 0, stream>>>(p, order_keys_[0].get(),
                                                                                 order_[0].get());
        WEFT_CUDA_CHECK_LAUNCH("patch_order_kernel");
        cub::DoubleBuffer<unsigned long long> k(order_keys_[0].get(), order_keys_[1].get());
        cub::DoubleBuffer<std::uint32_t> v(order_[0].get(), order_[1].get());
        WEFT_CUB_CHECK(cub::DeviceRadixSort::SortPairs(temp, scratch(), k, v, prims, 0, 34, stream));
        p.order = v.Current();
    }
    mark(PatchOrder, stream);

    // ---- count ----
    count_kernel<<<blocks_for(std::uint64_t{prims} + 1, kThreads), kThreads, 0, stream>>>(p);
    WEFT_CUDA_CHECK_LAUNCH("count_kernel");
    mark(Count, stream);

    // ---- scan and entries ----
    WEFT_CUB_CHECK(cub::DeviceScan::ExclusiveSum(temp, scratch(), counts_.get(), prims + 1U, stream));
    if (prims > 0) {
        fill_kernel<<<blocks_for(prims, kThreads), kThreads, 0, stream>>>(p, entry_keys_[0].get(),
                                                                          entry_prims_[0].get());
        WEFT_CUDA_CHECK_LAUNCH("fill_kernel");
    }
    pad_entries_kernel<<<blocks_for(p.entry_capacity, kThreads), kThreads, 0, stream>>>(p, entry_keys_[0].get(),
                                                                                        entry_prims_[0].get());
    WEFT_CUDA_CHECK_LAUNCH("pad_entries_kernel");
    mark(Scan, stream);

    // ---- sort by cell (stable: primitive order within a cell) ----
    cub::DoubleBuffer<unsigned long long> ek(entry_keys_[0].get(), entry_keys_[1].get());
    cub::DoubleBuffer<std::uint32_t> ev(entry_prims_[0].get(), entry_prims_[1].get());
    WEFT_CUB_CHECK(cub::DeviceRadixSort::SortPairs(temp, scratch(), ek, ev, p.entry_capacity, 0, key_sort_bits_, stream));
    const unsigned long long* keys = ek.Current();
    const std::uint32_t* entry_prims = ev.Current();
    mark(Sort, stream);

    // ---- cell ranges ----
    cell_flags_kernel<<<blocks_for(p.entry_capacity, kThreads), kThreads, 0, stream>>>(p, keys, cell_id_.get());
    WEFT_CUDA_CHECK_LAUNCH("cell_flags_kernel");
    WEFT_CUB_CHECK(cub::DeviceScan::InclusiveSum(temp, scratch(), cell_id_.get(), p.entry_capacity, stream));
    cell_begin_kernel<<<blocks_for(p.entry_capacity, kThreads), kThreads, 0, stream>>>(p, cell_id_.get(),
                                                                                       cell_begin_.get());
    WEFT_CUDA_CHECK_LAUNCH("cell_begin_kernel");
    mark(Ranges, stream);

    // ---- workload table ----
    rows_kernel<<<blocks_for(std::uint64_t{p.entry_capacity} + 1, kThreads), kThreads, 0, stream>>>(
        p, entry_prims, cell_id_.get(), cell_begin_.get(), row_offset_.get(), row_info_.get());
    WEFT_CUDA_CHECK_LAUNCH("rows_kernel");
    WEFT_CUB_CHECK(cub::DeviceScan::ExclusiveSum(temp, scratch(), row_offset_.get(), p.entry_capacity + 1U, stream));
    mark(Workload, stream);

    // ---- pairs ----
    // Eight blocks of 256 per multiprocessor fill an H100/H200 (2048 threads each); the grid strides.
    pairs_kernel<<<static_cast<unsigned>(8 * multiprocessors_), kThreads, 0, stream>>>(
        p, keys, entry_prims, row_offset_.get(), row_info_.get(), pair_keys_[0].get());
    WEFT_CUDA_CHECK_LAUNCH("pairs_kernel");
    oversized_kernel<<<static_cast<unsigned>(2 * multiprocessors_), kThreads, 0, stream>>>(p, pair_keys_[0].get());
    WEFT_CUDA_CHECK_LAUNCH("oversized_kernel");
    mark(Pairs, stream);

    // ---- canonical order ----
    pad_pairs_kernel<<<blocks_for(p.pair_capacity, kThreads), kThreads, 0, stream>>>(p, pair_keys_[0].get());
    WEFT_CUDA_CHECK_LAUNCH("pad_pairs_kernel");
    cub::DoubleBuffer<unsigned long long> pk(pair_keys_[0].get(), pair_keys_[1].get());
    WEFT_CUB_CHECK(cub::DeviceRadixSort::SortKeys(temp, scratch(), pk, p.pair_capacity, 0,
                                                  static_cast<int>(encoding_.sort_bits), stream));
    sorted_pairs_ = pk.Current();
    finish_kernel<<<1, 1, 0, stream>>>(p, row_offset_.get());
    WEFT_CUDA_CHECK_LAUNCH("finish_kernel");
    mark(Canonical, stream);
}

const GpuBroadPhaseCounters& GpuBroadPhase::read_back(cudaStream_t stream) {
    if (block_.get() == nullptr) throw Error("GPU broad phase: read_back before enqueue");
    const Block* block = reinterpret_cast<const Block*>(block_.get());
    WEFT_CUDA_CHECK(cudaMemcpyAsync(counters_host_.get(), &block->counters, sizeof(GpuBroadPhaseCounters),
                                    cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    return counters();
}

bool GpuBroadPhase::needs_rerun() {
    const GpuBroadPhaseCounters& c = counters();
    bool rerun = false;
    if ((c.overflow & kOverflowEntries) != 0) {
        entry_capacity_ = grown_capacity(static_cast<std::size_t>(c.entries));
        rerun = true;
    }
    if ((c.overflow & kOverflowPairs) != 0) {
        pair_capacity_ = grown_capacity(c.pairs);
        rerun = true;
    }
    // Key width: from the first measurement on, just the digits the grid needs (two bits of margin
    // for a scene that grows); widened on demand.
    if ((c.overflow & kOverflowKeyBits) != 0 || !key_bits_known_) {
        const int bits = entry_sort_bits(c.key_bits + 2);
        if ((c.overflow & kOverflowKeyBits) != 0) rerun = true;
        if (bits > key_sort_bits_ || !key_bits_known_) key_sort_bits_ = bits;
        key_bits_known_ = true;
    }
    if (rerun) {
        ++reruns_;
        return true;
    }
    // A call that fit: the trim windows (weft/backend/buffer_trim.h). Bytes per slot: an entry's two
    // keys and primitives, cell id and start, workload offset and row; a pair's two keys.
    constexpr std::size_t kEntryBytes = 2 * sizeof(unsigned long long) + 2 * sizeof(std::uint32_t) + 2 * sizeof(std::uint32_t) +
                                        sizeof(unsigned long long) + sizeof(uint4);
    constexpr std::size_t kPairBytes = 2 * sizeof(unsigned long long);
    record_for_trim(entry_trim_, static_cast<std::size_t>(c.entries), entry_capacity_, kEntryBytes, trimmed_entries_);
    record_for_trim(pair_trim_, c.pairs, pair_capacity_, kPairBytes, trimmed_pairs_);
    return false;
}

const GpuBroadPhaseCounters& GpuBroadPhase::find(const GpuBroadPhaseInput& in, cudaStream_t stream) {
    // Each rerun grows at least one size to what was measured (plus headroom); the entries must fit
    // before the pairs can be counted, so a cold start may take two reruns.
    rerun_until_fits(*this, stream, "GPU broad phase: buffers", 8, [&](int) { enqueue(in, stream); });
    return counters();
}

GpuPairList GpuBroadPhase::pairs() const {
    GpuPairList list;
    list.keys = sorted_pairs_;
    list.count = block_.get() != nullptr ? &reinterpret_cast<const Block*>(block_.get())->counters.pairs : nullptr;
    list.capacity = static_cast<std::uint32_t>(pair_capacity_);
    list.encoding = encoding_;
    return list;
}

void GpuBroadPhase::download(std::vector<std::uint64_t>& keys, cudaStream_t stream) const {
    const std::size_t count = std::min<std::size_t>(counters().pairs, pair_capacity_);
    keys.resize(count);
    if (count == 0) return;
    static_assert(sizeof(std::uint64_t) == sizeof(unsigned long long));
    WEFT_CUDA_CHECK(cudaMemcpyAsync(keys.data(), sorted_pairs_, count * sizeof(std::uint64_t), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
}

}  // namespace weft::cuda::collision
