// Colouring and sliced-ELL layout of the flattened model for the CUDA backend.
#include "device_layout.h"

#include <algorithm>
#include <bit>

#include "weft/error.h"

namespace weft::cuda {

Coloring color_elements(const std::vector<std::uint32_t>& vertex_ids, std::size_t corners, std::size_t vertex_count) {
    const std::size_t count = corners == 0 ? 0 : vertex_ids.size() / corners;
    // used[v] is a bit set of the colours already taken by elements touching v; 64 colours cover any
    // mesh whose vertices touch fewer than 64 elements (a valence-12 vertex touches about 36 hinges);
    // beyond that further 64-colour banks are opened.
    std::vector<std::uint32_t> color(count, 0);
    std::uint32_t colors = 0;
    std::vector<std::uint64_t> used;
    for (std::uint32_t bank = 0;; ++bank) {
        used.assign(vertex_count, 0);
        bool pending = false;
        for (std::size_t e = 0; e < count; ++e) {
            if (bank > 0 && color[e] != 64 * bank) continue;  // only elements that overflowed the last bank
            std::uint64_t taken = 0;
            for (std::size_t a = 0; a < corners; ++a) taken |= used[vertex_ids[corners * e + a]];
            if (taken == ~std::uint64_t{0}) {
                color[e] = 64 * (bank + 1);
                pending = true;
                continue;
            }
            const auto c = static_cast<std::uint32_t>(std::countr_one(taken));
            color[e] = 64 * bank + c;
            colors = std::max(colors, color[e] + 1);
            for (std::size_t a = 0; a < corners; ++a) used[vertex_ids[corners * e + a]] |= std::uint64_t{1} << c;
        }
        if (!pending) break;
    }
    Coloring out;
    out.color_start.assign(colors + 1, 0);
    for (std::uint32_t c : color) ++out.color_start[c + 1];
    for (std::uint32_t c = 0; c < colors; ++c) out.color_start[c + 1] += out.color_start[c];
    out.order.resize(count);
    std::vector<std::uint32_t> fill(out.color_start.begin(), out.color_start.end() - 1);
    for (std::size_t e = 0; e < count; ++e) out.order[fill[color[e]]++] = static_cast<std::uint32_t>(e);
    return out;
}

EllLayout make_ell_layout(const BlockPattern& pattern) {
    EllLayout ell;
    const std::size_t rows = pattern.diagonal.size();
    const std::size_t slices = (rows + kSliceRows - 1) / kSliceRows;
    ell.slice_start.assign(slices + 1, 0);
    for (std::size_t s = 0; s < slices; ++s) {
        std::uint32_t width = 0;
        for (std::size_t i = s * kSliceRows; i < std::min(rows, (s + 1) * kSliceRows); ++i)
            width = std::max(width, pattern.row_start[i + 1] - pattern.row_start[i]);
        ell.slice_start[s + 1] = ell.slice_start[s] + width * kSliceRows;
    }
    ell.column.resize(ell.slice_start[slices]);
    ell.slot_position.resize(pattern.block_count());
    ell.diagonal.resize(rows);
    for (std::size_t s = 0; s < slices; ++s) {
        const std::uint32_t width = ell.width(s);
        for (std::uint32_t lane = 0; lane < kSliceRows; ++lane) {
            const std::size_t i = s * kSliceRows + lane;
            for (std::uint32_t k = 0; k < width; ++k) {
                const std::uint32_t pos = ell.slice_start[s] + k * kSliceRows + lane;
                const std::uint32_t slot = i < rows ? pattern.row_start[i] + k : 0;
                if (i < rows && slot < pattern.row_start[i + 1]) {
                    ell.column[pos] = pattern.column[slot];
                    ell.slot_position[slot] = pos;
                } else {
                    // Padding multiplies a zero block by the row's own entry: no branch in the SpMV, and
                    // the load hits a line the warp reads anyway. Rows past the end point at row 0.
                    ell.column[pos] = i < rows ? static_cast<std::uint32_t>(i) : 0;
                }
            }
        }
    }
    for (std::size_t i = 0; i < rows; ++i) ell.diagonal[i] = ell.slot_position[pattern.diagonal[i]];
    return ell;
}

namespace {

// CSR of (element, corner) incidences per vertex: entry 4·element + corner, elements in order.
void incidence(const std::uint32_t* ids, std::size_t corners, std::size_t count, std::size_t vertex_count,
               std::vector<std::uint32_t>& start, std::vector<std::uint32_t>& entries) {
    if (count >= (std::size_t{1} << 30)) throw Error("CUDA backend: more than 2^30 elements in one world");
    start.assign(vertex_count + 1, 0);
    for (std::size_t e = 0; e < count * corners; ++e) ++start[ids[e] + 1];
    for (std::size_t i = 0; i < vertex_count; ++i) start[i + 1] += start[i];
    entries.resize(count * corners);
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t e = 0; e < count; ++e)
        for (std::size_t a = 0; a < corners; ++a)
            entries[fill[ids[corners * e + a]]++] = static_cast<std::uint32_t>(4 * e + a);
}

}  // namespace

namespace {

// Colours elements of `corners` vertices each (`ids`, element-major), and, in colour order, maps each
// element's corner pairs to ELL positions through its CSR `slots` and lists its corners per vertex.
void lay_out_elements(const std::vector<std::uint32_t>& ids, std::size_t corners, const std::vector<std::uint32_t>& slots,
                      const EllLayout& ell, std::size_t vertex_count, Coloring& colors,
                      std::vector<std::uint32_t>& positions, std::vector<std::uint32_t>& start,
                      std::vector<std::uint32_t>& entries) {
    const std::size_t count = ids.size() / corners, blocks = corners * corners;
    colors = color_elements(ids, corners, vertex_count);
    std::vector<std::uint32_t> ordered(ids.size());
    positions.resize(blocks * count);
    for (std::size_t j = 0; j < count; ++j) {
        const std::uint32_t e = colors.order[j];
        for (std::size_t a = 0; a < corners; ++a) ordered[corners * j + a] = ids[corners * e + a];
        for (std::size_t b = 0; b < blocks; ++b) positions[blocks * j + b] = ell.slot_position[slots[blocks * e + b]];
    }
    incidence(ordered.data(), corners, count, vertex_count, start, entries);
}

}  // namespace

DeviceLayout make_device_layout(const FlatModel& flat) {
    DeviceLayout d;
    d.ell = make_ell_layout(flat.pattern);
    for (std::size_t s = 0; s < d.ell.slices(); ++s) d.max_row_width = std::max(d.max_row_width, d.ell.width(s));
    // Elements in colour order from here on: positions and incidence use colour-order ids.
    std::vector<std::uint32_t> ids;
    for (const Triangle& t : flat.triangles) ids.insert(ids.end(), t.v, t.v + 3);
    lay_out_elements(ids, 3, flat.pattern.triangle_slots, d.ell, flat.vertex_count, d.triangle_colors,
                     d.triangle_positions, d.vertex_triangle_start, d.vertex_triangle);
    ids.clear();
    for (const Hinge& h : flat.hinges) ids.insert(ids.end(), h.v, h.v + 4);
    lay_out_elements(ids, 4, flat.pattern.hinge_slots, d.ell, flat.vertex_count, d.hinge_colors, d.hinge_positions,
                     d.vertex_hinge_start, d.vertex_hinge);
    return d;
}
}  // namespace weft::cuda
