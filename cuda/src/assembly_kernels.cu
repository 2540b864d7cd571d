// Assembly of A·Δv = b into the sliced-ELL matrix, in the two strategies device_layout.h describes.
// Neither uses atomics (but for the integer contact count) or per-element scratch, and each sums every
// block in a fixed order, so a strategy gives the same bits on every run. The two differ from each
// other only in that order (float rounding, ~1e-7 relative).
#include "cuda_check.h"
#include "element_terms.cuh"

namespace weft::cuda {
namespace {

constexpr unsigned kFullMask = 0xffffffffu;

/// Sum over the warp in a fixed butterfly order; every lane receives the same total.
__device__ inline float warp_sum(float v) {
    for (int offset = 16; offset > 0; offset >>= 1) v += __shfl_xor_sync(kFullMask, v, offset);
    return v;
}

/// Adds the block's active-contact counts with one atomic (integers: the order does not matter).
__device__ inline void add_contacts(const DeviceView& d, int active) {
    using Reduce = cub::BlockReduce<int, kBlockSize>;
    __shared__ typename Reduce::TempStorage storage;
    const int block_active = Reduce(storage).Sum(active);
    if (threadIdx.x == 0 && block_active > 0) atomicAdd(&d.stats->contacts, block_active);
}

// ---- row gather: one warp per row -------------------------------------------------------------------
// Lane l takes the row's l-th (element, corner) pair (triangles first, then hinges), evaluates the
// element and keeps the corner's force and blocks; for each slot k of the row the warp sums the lanes'
// blocks with a butterfly and lane k keeps the sum. Rows wider than 32 slots repeat the evaluation
// per 32 slots; rows with more than 32 pairs take several rounds.
__global__ void assemble_rows_kernel(DeviceView d) {
    const std::uint32_t lane = threadIdx.x % 32;
    const std::uint32_t i = (blockIdx.x * blockDim.x + threadIdx.x) / 32;
    int active = 0;         // this lane's centroid contacts
    int vertex_active = 0;  // the row's vertex contacts (every lane holds them)
    bool row_face = false;  // a triangle of this lane's at the row has a centroid contact
    if (i < d.rows) {  // uniform over the warp
        const StepParams& sp = step_params(d);
        V3 vertex_rhs;
        M3 vertex_block;
        vertex_active = vertex_terms(d, sp, i, vertex_rhs, vertex_block);  // every lane: broadcast loads
        const std::uint32_t slice = i / kSliceRowsDevice, row_lane = i % kSliceRowsDevice;
        const std::uint32_t first = d.slice_start[slice], width = (d.slice_start[slice + 1] - first) / kSliceRowsDevice;
        const std::uint32_t diag_slot = (d.diagonal[i] - first - row_lane) / kSliceRowsDevice;
        const std::uint32_t tri_first = d.vertex_triangle_start[i], tri_count = d.vertex_triangle_start[i + 1] - tri_first;
        const std::uint32_t hinge_first = d.vertex_hinge_start[i];
        const std::uint32_t total = tri_count + d.vertex_hinge_start[i + 1] - hinge_first;
        V3 rhs{};
        for (std::uint32_t chunk = 0; chunk * 32 < width; ++chunk) {
            const std::uint32_t my_slot = chunk * 32 + lane;
            M3 acc = my_slot == diag_slot ? vertex_block : M3{};  // the vertex block first, as on the CPU
            for (std::uint32_t round = 0; round * 32 < total; ++round) {
                const std::uint32_t e = round * 32 + lane;
                M3 block[4];
                std::uint32_t slot[4] = {~0u, ~0u, ~0u, ~0u};
                if (e < tri_count) {
                    const std::uint32_t entry = d.vertex_triangle[tri_first + e];
                    const std::uint32_t t = entry >> 2, a = entry & 3u;
                    TriangleTerms terms;
                    const int faces = triangle_terms(d, sp, t, terms);
                    if (chunk == 0 && a == 0) active += faces;  // a centroid contact counted at its first corner's row
                    row_face = row_face || faces > 0;
                    if (chunk == 0) rhs += terms.rhs[a];
                    for (int b = 0; b < 3; ++b) {
                        block[b] = terms.block[a][b];
                        slot[b] = (d.triangle_positions[9 * t + 3 * a + b] - first - row_lane) / kSliceRowsDevice;
                    }
                } else if (e < total) {
                    const std::uint32_t entry = d.vertex_hinge[hinge_first + e - tri_count];
                    const std::uint32_t k = entry >> 2, a = entry & 3u;
                    HingeTerms terms;
                    if (hinge_terms(d, sp, k, terms)) {
                        if (chunk == 0) rhs += terms.rhs[a];
                        for (int b = 0; b < 4; ++b) {
                            block[b] = terms.block[a][b];
                            slot[b] = (d.hinge_positions[16 * k + 4 * a + b] - first - row_lane) / kSliceRowsDevice;
                        }
                    }
                }
                const std::uint32_t last = min(width, chunk * 32 + 32);
                for (std::uint32_t k = chunk * 32; k < last; ++k) {
                    M3 sum{};
                    for (int b = 0; b < 4; ++b)
                        if (slot[b] == k) sum += block[b];
                    for (int r = 0; r < 3; ++r)
                        for (int c = 0; c < 3; ++c) sum.m[r][c] = warp_sum(sum.m[r][c]);
                    if (my_slot == k) acc += sum;
                }
            }
            if (my_slot < width) store_block(d.blocks, first + my_slot * kSliceRowsDevice + row_lane, acc);
        }
        rhs = V3{warp_sum(rhs.x), warp_sum(rhs.y), warp_sum(rhs.z)};
        if (lane == 0) store3(d.b, i, d.n, vertex_rhs + rhs);
        const bool face = __any_sync(kFullMask, row_face);  // i < d.rows is the whole warp's
        if (lane == 0) d.collider_contact[i] = vertex_active > 0 || face ? 1 : 0;
    }
    add_contacts(d, active + (lane == 0 ? vertex_active : 0));
}

// ---- colour passes -----------------------------------------------------------------------------------
// The vertex kernel writes every row (its diagonal block, zeros in the other slots) and b; then one
// launch per colour adds element blocks and forces with plain read-modify-writes: elements of one colour
// share no vertex, so no two threads touch the same block.
__global__ void vertex_rows_kernel(DeviceView d) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    int active = 0;
    if (i < d.n) {
        V3 rhs;
        M3 block;
        active = vertex_terms(d, step_params(d), i, rhs, block);
        store3(d.b, i, d.n, rhs);
        d.collider_contact[i] = active > 0 ? 1 : 0;  // the triangle passes after it add the face contacts
        const std::uint32_t slice = i / kSliceRowsDevice;
        const std::uint32_t first = d.slice_start[slice], width = (d.slice_start[slice + 1] - first) / kSliceRowsDevice;
        const std::uint32_t diag = d.diagonal[i];
        for (std::uint32_t k = 0; k < width; ++k) {
            const std::uint32_t pos = first + k * kSliceRowsDevice + i % kSliceRowsDevice;
            store_block(d.blocks, pos, pos == diag ? block : M3{});
        }
    }
    add_contacts(d, i < d.rows ? active : 0);  // a ghost's contacts are its owner's to count
}

__global__ void triangle_pass_kernel(DeviceView d, std::uint32_t first, std::uint32_t last) {
    const std::uint32_t t = first + blockIdx.x * blockDim.x + threadIdx.x;
    int active = 0;
    if (t < last) {
        TriangleTerms terms;
        active = triangle_terms(d, step_params(d), t, terms);
        const bool face = active > 0;
        if (d.triangle_vertices[3 * t] >= d.rows) active = 0;  // a part counts what its first corner's owner counts
        for (int a = 0; a < 3; ++a) {
            const std::uint32_t v = d.triangle_vertices[3 * t + a];
            if (face) d.collider_contact[v] = 1;  // one colour's triangles share no vertex
            for (int c = 0; c < 3; ++c) d.b[c * d.n + v] += terms.rhs[a][c];
            for (int b = 0; b < 3; ++b) add_block(d.blocks, d.triangle_positions[9 * t + 3 * a + b], terms.block[a][b]);
        }
    }
    // Without face contacts a triangle has none to count: skip the block reduction (the flag is one
    // value for the whole launch, so every thread of the block takes the same branch).
    if (step_params(d).face_contacts != 0) add_contacts(d, active);
}

__global__ void hinge_pass_kernel(DeviceView d, std::uint32_t first, std::uint32_t last) {
    const std::uint32_t k = first + blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= last) return;
    HingeTerms terms;
    if (!hinge_terms(d, step_params(d), k, terms)) return;
    for (int a = 0; a < 4; ++a) {
        const std::uint32_t v = d.hinge_vertices[4 * k + a];
        for (int c = 0; c < 3; ++c) d.b[c * d.n + v] += terms.rhs[a][c];
        for (int b = 0; b < 4; ++b) add_block(d.blocks, d.hinge_positions[16 * k + 4 * a + b], terms.block[a][b]);
    }
}

}  // namespace

void launch_assemble_rows(const DeviceView& d, cudaStream_t stream) {
    const std::uint64_t threads = 32ull * d.rows;
    const auto blocks = static_cast<unsigned>((threads + kBlockSize - 1) / kBlockSize);
    assemble_rows_kernel<<<blocks, kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("assemble_rows_kernel");
}

void launch_assemble_colors(const DeviceView& d, const Coloring& triangles, const Coloring& hinges, cudaStream_t stream) {
    vertex_rows_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("vertex_rows_kernel");
    for (std::size_t c = 0; c < triangles.color_count(); ++c) {
        const std::uint32_t first = triangles.color_start[c], last = triangles.color_start[c + 1];
        triangle_pass_kernel<<<grid_for(last - first), kBlockSize, 0, stream>>>(d, first, last);
        WEFT_CUDA_CHECK_LAUNCH("triangle_pass_kernel");
    }
    for (std::size_t c = 0; c < hinges.color_count(); ++c) {
        const std::uint32_t first = hinges.color_start[c], last = hinges.color_start[c + 1];
        hinge_pass_kernel<<<grid_for(last - first), kBlockSize, 0, stream>>>(d, first, last);
        WEFT_CUDA_CHECK_LAUNCH("hinge_pass_kernel");
    }
}

}  // namespace weft::cuda
