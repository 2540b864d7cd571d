#pragma once
// How the flattened model is laid out for the GPU (docs/architecture.md, "CUDA backend"). Pure host
// code, so the layout rules are unit-tested on machines without a GPU.
//
// Two decisions shape the device solver:
// - The matrix is stored in sliced ELLPACK order: rows are grouped in slices of 32 (one warp), and
//   the k-th block of every row of a slice is stored next to the k-th block of its neighbours. A warp
//   computing 32 rows of A·x then reads one contiguous run of blocks per k: the SpMV, which bounds
//   the whole solve, streams the matrix at full memory bandwidth.
// - Assembly needs no atomics and no per-element scratch (which would cost more than 1 KB per
//   triangle), in one of two ways (DeviceSolver picks by size; docs/architecture.md measures both):
//   * row gather: each vertex lists the (element, corner) pairs that touch it, and one warp per row
//     evaluates those elements and sums the row's blocks: one launch, each block written once, but
//     every element evaluated once per corner. Best for small and mid-size cloth (latency-bound).
//   * colour passes: elements are coloured so that no two of one colour share a vertex and sorted
//     by colour; one launch per colour adds element blocks with plain read-modify-writes. Each element
//     is evaluated once, but every pass streams the part of the matrix it touches. Best for large cloth.
//   Both sum in a fixed order, so each gives the same bits on every run.

#include <cstdint>
#include <vector>

#include "weft/backend/flat_model.h"

namespace weft::cuda {

/// Rows per ELL slice (one warp).
inline constexpr std::uint32_t kSliceRows = 32;

/// Element colouring: `order` lists element ids colour by colour, `color_start` (size colours+1)
/// delimits each colour in `order`.
struct Coloring {
    std::vector<std::uint32_t> order;
    std::vector<std::uint32_t> color_start;
    [[nodiscard]] std::size_t color_count() const { return color_start.empty() ? 0 : color_start.size() - 1; }
};

/// Greedy colouring of elements given by `corners` vertex ids each (3 for triangles, 4 for hinges):
/// each element takes the smallest colour none of its vertices has used yet. Deterministic.
[[nodiscard]] Coloring color_elements(const std::vector<std::uint32_t>& vertex_ids, std::size_t corners,
                                      std::size_t vertex_count);

/// Sliced ELLPACK positions for a CSR block pattern.
struct EllLayout {
    std::vector<std::uint32_t> slice_start;   ///< size slices+1, first position of each slice
    std::vector<std::uint32_t> slot_position; ///< CSR slot → ELL position
    std::vector<std::uint32_t> column;        ///< ELL position → block column (padding: the row itself)
    std::vector<std::uint32_t> diagonal;      ///< row → ELL position of its diagonal block
    [[nodiscard]] std::size_t positions() const { return column.size(); }
    [[nodiscard]] std::size_t slices() const { return slice_start.empty() ? 0 : slice_start.size() - 1; }
    /// Width (blocks per row) of slice `s`.
    [[nodiscard]] std::uint32_t width(std::size_t s) const { return (slice_start[s + 1] - slice_start[s]) / kSliceRows; }
};

/// ELL position of the k-th block of row `row` in a slice starting at `slice_start`.
inline std::uint32_t ell_position(std::uint32_t slice_start, std::uint32_t row, std::uint32_t k) {
    return slice_start + k * kSliceRows + row % kSliceRows;
}

[[nodiscard]] EllLayout make_ell_layout(const BlockPattern& pattern);

/// Everything the device solver uploads beyond the model's own arrays. The device stores elements in
/// colour order (`triangle_colors.order`, `hinge_colors.order`); every element id below is a
/// colour-order id.
struct DeviceLayout {
    EllLayout ell;
    Coloring triangle_colors;
    Coloring hinge_colors;
    /// Per triangle: 9 ELL positions, [a*3+b] → block (v_a, v_b).
    std::vector<std::uint32_t> triangle_positions;
    /// Per hinge: 16 ELL positions, [a*4+b].
    std::vector<std::uint32_t> hinge_positions;
    /// Vertex → incident triangle corners, CSR; each entry is 4·triangle + corner, in id order.
    std::vector<std::uint32_t> vertex_triangle_start, vertex_triangle;
    /// Vertex → incident hinge corners, CSR; each entry is 4·hinge + corner, in id order.
    std::vector<std::uint32_t> vertex_hinge_start, vertex_hinge;
    std::uint32_t max_row_width = 0;  ///< blocks in the longest row
};

[[nodiscard]] DeviceLayout make_device_layout(const FlatModel& flat);

}  // namespace weft::cuda
