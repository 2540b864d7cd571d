// The CUDA backend's host-side layout rules (cuda/src/device_layout.h), checked without a GPU: the
// element colouring that makes the colour passes race-free and deterministic, the per-vertex
// incidence lists the row gather walks, and the sliced-ELL positions
// the matrix, the SpMV and the element slot maps share. A mistake here corrupts the device matrix
// silently (two threads adding into one block, a block landing in another row), so every property
// the kernels rely on is checked directly rather than through a simulation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "weft/backend/flat_model.h"
#include "weft/scene.h"

#include "device_layout.h"
#include "gpu_test_util.h"

namespace weft::cuda {
namespace {

using test::scene_file;

/// The flag scene flattened. 40×24 cells = 1025 vertices: 32 full slices and a last slice of one row,
/// so the padding past the last row is exercised too.
FlatModel flag_model() {
    const auto world = build_world(load_scene(scene_file("flag")));
    return flatten(world->model());
}

std::vector<std::uint32_t> triangle_ids(const FlatModel& f) {
    std::vector<std::uint32_t> ids;
    for (const Triangle& t : f.triangles) ids.insert(ids.end(), t.v, t.v + 3);
    return ids;
}

std::vector<std::uint32_t> hinge_ids(const FlatModel& f) {
    std::vector<std::uint32_t> ids;
    for (const Hinge& h : f.hinges) ids.insert(ids.end(), h.v, h.v + 4);
    return ids;
}

/// Random elements of `corners` distinct vertices each over `vertices` vertices: no mesh structure at
/// all, so high-degree vertices (and more than one 64-colour bank) can occur.
std::vector<std::uint32_t> random_soup(std::size_t elements, std::size_t corners, std::uint32_t vertices,
                                       std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<std::uint32_t> pick(0, vertices - 1);
    std::vector<std::uint32_t> ids;
    for (std::size_t e = 0; e < elements; ++e) {
        std::vector<std::uint32_t> v;
        while (v.size() < corners) {
            const std::uint32_t c = pick(rng);
            if (std::find(v.begin(), v.end(), c) == v.end()) v.push_back(c);
        }
        ids.insert(ids.end(), v.begin(), v.end());
    }
    return ids;
}

/// Checks that `c` is a valid colouring of the elements in `ids`: every element exactly once in
/// `order`, colours delimited consistently, and no vertex shared by two elements of one colour.
void expect_valid_coloring(const Coloring& c, const std::vector<std::uint32_t>& ids, std::size_t corners,
                           std::size_t vertex_count) {
    const std::size_t count = ids.size() / corners;
    ASSERT_EQ(c.order.size(), count);
    ASSERT_FALSE(c.color_start.empty());
    EXPECT_EQ(c.color_start.front(), 0U);
    EXPECT_EQ(c.color_start.back(), count);
    for (std::size_t k = 0; k + 1 < c.color_start.size(); ++k) {
        EXPECT_LT(c.color_start[k], c.color_start[k + 1]) << "colour " << k << " is empty";
    }
    std::vector<int> seen(count, 0);
    for (std::uint32_t e : c.order) {
        ASSERT_LT(e, count);
        ++seen[e];
    }
    for (std::size_t e = 0; e < count; ++e)
        ASSERT_EQ(seen[e], 1) << "element " << e << " appears " << seen[e] << " times";
    // One colour at a time: a vertex may be touched by at most one element of the colour.
    std::vector<std::uint32_t> last_color(vertex_count, ~0U);
    for (std::size_t k = 0; k < c.color_count(); ++k) {
        for (std::uint32_t j = c.color_start[k]; j < c.color_start[k + 1]; ++j) {
            const std::uint32_t e = c.order[j];
            for (std::size_t a = 0; a < corners; ++a) {
                const std::uint32_t v = ids[corners * e + a];
                ASSERT_NE(last_color[v], k) << "colour " << k << ": vertex " << v << " is shared (element " << e << ")";
                last_color[v] = static_cast<std::uint32_t>(k);
            }
        }
    }
}

/// Largest number of elements touching one vertex: a lower bound on the colours any valid colouring needs.
std::size_t max_incidence(const std::vector<std::uint32_t>& ids, std::size_t vertex_count) {
    std::vector<std::size_t> count(vertex_count, 0);
    std::size_t most = 0;
    for (std::uint32_t v : ids) most = std::max(most, ++count[v]);
    return most;
}

void expect_same(const Coloring& a, const Coloring& b) {
    EXPECT_EQ(a.order, b.order);
    EXPECT_EQ(a.color_start, b.color_start);
}

TEST(DeviceLayoutColoring, FlagTrianglesAndHingesAreValidAndDeterministic) {
    const FlatModel f = flag_model();
    ASSERT_EQ(f.vertex_count, 41U * 25U);
    const auto tri = triangle_ids(f);
    const auto hin = hinge_ids(f);
    const Coloring tc = color_elements(tri, 3, f.vertex_count);
    const Coloring hc = color_elements(hin, 4, f.vertex_count);
    expect_valid_coloring(tc, tri, 3, f.vertex_count);
    expect_valid_coloring(hc, hin, 4, f.vertex_count);
    expect_same(tc, color_elements(tri, 3, f.vertex_count));
    expect_same(hc, color_elements(hin, 4, f.vertex_count));
    EXPECT_GE(tc.color_count(), max_incidence(tri, f.vertex_count));
    EXPECT_GE(hc.color_count(), max_incidence(hin, f.vertex_count));
}

TEST(DeviceLayoutColoring, RegularGridNeedsFewColours) {
    // Assembly runs one launch per colour, so the count is a cost per Newton iteration. On make_grid's
    // meshes a vertex touches at most 8 triangles, so no valid colouring uses fewer than 8 triangle
    // colours, and greedy colouring uses exactly 8 (18 for hinges) at every grid size measured. The
    // bounds, 12 and 24, catch a colouring that stops reusing colours without tying the test to the
    // greedy order.
    for (const auto& cells : {"[40, 24]", "[64, 64]", "[33, 7]"}) {
        SCOPED_TRACE(cells);
        const std::vector<std::string> o{std::string("cloth.flag.mesh.grid.cells=") + cells};
        const auto world = build_world(load_scene(scene_file("flag"), o));
        const FlatModel f = flatten(world->model());
        const DeviceLayout d = make_device_layout(f);
        EXPECT_LE(d.triangle_colors.color_count(), 12U);
        EXPECT_GE(d.triangle_colors.color_count(), max_incidence(triangle_ids(f), f.vertex_count));
        EXPECT_LE(d.hinge_colors.color_count(), 24U);
        std::printf("[ layout   ] grid %s: %zu triangle colours, %zu hinge colours\n", cells,
                    d.triangle_colors.color_count(), d.hinge_colors.color_count());
    }
}

TEST(DeviceLayoutColoring, RandomSoupIsValidAndDeterministic) {
    // 300 vertices and 20000 triangles: each vertex touches about 200 elements, beyond the first
    // 64-colour bank, so the overflow path of the greedy colouring runs too.
    for (std::size_t corners : {std::size_t{3}, std::size_t{4}}) {
        SCOPED_TRACE(corners);
        const std::uint32_t vertices = 300;
        const auto ids = random_soup(20000, corners, vertices, 7);
        const Coloring c = color_elements(ids, corners, vertices);
        expect_valid_coloring(c, ids, corners, vertices);
        expect_same(c, color_elements(ids, corners, vertices));
        EXPECT_GT(c.color_count(), 64U);
        EXPECT_GE(c.color_count(), max_incidence(ids, vertices));
    }
    // And a sparse soup, where most colours are small.
    const auto ids = random_soup(500, 3, 1000, 11);
    const Coloring c = color_elements(ids, 3, 1000);
    expect_valid_coloring(c, ids, 3, 1000);
    expect_same(c, color_elements(ids, 3, 1000));
}

TEST(DeviceLayoutColoring, NoElementsGiveNoColours) {
    const Coloring c = color_elements({}, 3, 10);
    EXPECT_TRUE(c.order.empty());
    EXPECT_EQ(c.color_count(), 0U);
}

/// Block pattern of a random triangle soup built directly (rows sorted, diagonal included), so that
/// rows have very different lengths and slices different widths.
BlockPattern random_pattern(std::uint32_t rows, std::size_t triangles, std::uint32_t seed) {
    const auto ids = random_soup(triangles, 3, rows, seed);
    std::vector<std::set<std::uint32_t>> cols(rows);
    for (std::uint32_t i = 0; i < rows; ++i) cols[i].insert(i);
    for (std::size_t t = 0; t < triangles; ++t)
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) cols[ids[3 * t + a]].insert(ids[3 * t + b]);
    BlockPattern p;
    p.row_start.push_back(0);
    for (std::uint32_t i = 0; i < rows; ++i) {
        for (std::uint32_t c : cols[i]) {
            if (c == i) p.diagonal.push_back(static_cast<std::uint32_t>(p.column.size()));
            p.column.push_back(c);
        }
        p.row_start.push_back(static_cast<std::uint32_t>(p.column.size()));
    }
    return p;
}

/// Row of ELL position `pos` found from the slice table alone (independent of the slot map).
std::uint32_t ell_row(const EllLayout& ell, std::uint32_t pos) {
    const auto it = std::upper_bound(ell.slice_start.begin(), ell.slice_start.end(), pos);
    const auto s = static_cast<std::uint32_t>(it - ell.slice_start.begin() - 1);
    return s * kSliceRows + (pos - ell.slice_start[s]) % kSliceRows;
}

void expect_valid_ell(const BlockPattern& p, const EllLayout& ell) {
    const auto rows = static_cast<std::uint32_t>(p.diagonal.size());
    const std::size_t slices = (rows + kSliceRows - 1) / kSliceRows;
    ASSERT_EQ(ell.slices(), slices);
    ASSERT_EQ(ell.slot_position.size(), p.block_count());
    ASSERT_EQ(ell.diagonal.size(), rows);
    EXPECT_EQ(ell.slice_start.front(), 0U);
    EXPECT_EQ(ell.slice_start.back(), ell.positions());
    // Each slice is exactly as wide as its longest row: any wider wastes memory and SpMV bandwidth.
    for (std::size_t s = 0; s < slices; ++s) {
        ASSERT_EQ((ell.slice_start[s + 1] - ell.slice_start[s]) % kSliceRows, 0U);
        std::uint32_t longest = 0;
        for (std::size_t i = s * kSliceRows; i < std::min<std::size_t>(rows, (s + 1) * kSliceRows); ++i)
            longest = std::max(longest, p.row_start[i + 1] - p.row_start[i]);
        EXPECT_EQ(ell.width(s), longest) << "slice " << s;
    }
    // Slots: unique positions, in their own row's lane at k = slot − row_start, carrying their column.
    std::vector<int> used(ell.positions(), 0);
    for (std::uint32_t i = 0; i < rows; ++i) {
        for (std::uint32_t s = p.row_start[i]; s < p.row_start[i + 1]; ++s) {
            const std::uint32_t pos = ell.slot_position[s];
            ASSERT_LT(pos, ell.positions());
            ASSERT_EQ(used[pos]++, 0) << "slot " << s << " shares ELL position " << pos;
            EXPECT_EQ(pos, ell_position(ell.slice_start[i / kSliceRows], i, s - p.row_start[i]));
            EXPECT_EQ(ell_row(ell, pos), i);
            EXPECT_EQ(ell.column[pos], p.column[s]);
        }
        EXPECT_EQ(ell.diagonal[i], ell.slot_position[p.diagonal[i]]);
        EXPECT_EQ(ell.column[ell.diagonal[i]], i);
    }
    // Padding multiplies a zero block by the row's own x (rows past the end: row 0's), so the SpMV
    // needs no branch and reads no memory outside the vector.
    std::size_t padding = 0;
    for (std::uint32_t pos = 0; pos < ell.positions(); ++pos) {
        if (used[pos] != 0) continue;
        ++padding;
        const std::uint32_t row = ell_row(ell, pos);
        EXPECT_EQ(ell.column[pos], row < rows ? row : 0U) << "padding position " << pos << " of row " << row;
    }
    EXPECT_EQ(padding + p.block_count(), ell.positions());
}

TEST(DeviceLayoutEll, FlagPatternMapsEverySlot) {
    const FlatModel f = flag_model();
    expect_valid_ell(f.pattern, make_ell_layout(f.pattern));
}

TEST(DeviceLayoutEll, RandomPatternsMapEverySlot) {
    // 1000 rows (a partial last slice) and 97 rows (fewer than four slices), dense and sparse.
    expect_valid_ell(random_pattern(1000, 3000, 3), make_ell_layout(random_pattern(1000, 3000, 3)));
    expect_valid_ell(random_pattern(97, 40, 5), make_ell_layout(random_pattern(97, 40, 5)));
    expect_valid_ell(random_pattern(64, 0, 5), make_ell_layout(random_pattern(64, 0, 5)));  // diagonal only
}

TEST(DeviceLayoutEll, IsDeterministic) {
    const BlockPattern p = random_pattern(1000, 3000, 3);
    const EllLayout a = make_ell_layout(p), b = make_ell_layout(p);
    EXPECT_EQ(a.slice_start, b.slice_start);
    EXPECT_EQ(a.slot_position, b.slot_position);
    EXPECT_EQ(a.column, b.column);
    EXPECT_EQ(a.diagonal, b.diagonal);
}

TEST(DeviceLayout, ElementPositionsFollowTheSlotMaps) {
    const FlatModel f = flag_model();
    const DeviceLayout d = make_device_layout(f);
    expect_valid_ell(f.pattern, d.ell);
    expect_valid_coloring(d.triangle_colors, triangle_ids(f), 3, f.vertex_count);
    expect_valid_coloring(d.hinge_colors, hinge_ids(f), 4, f.vertex_count);
    const std::size_t nt = f.triangle_count(), nh = f.hinge_count();
    ASSERT_EQ(d.triangle_positions.size(), 9 * nt);
    ASSERT_EQ(d.hinge_positions.size(), 16 * nh);
    // j-th coloured element: its positions are the ELL positions of its CSR slots, and (checked from the
    // ELL tables alone) block (a, b) lies in row v_a and column v_b.
    for (std::size_t j = 0; j < nt; ++j) {
        const std::uint32_t t = d.triangle_colors.order[j];
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                const std::uint32_t pos = d.triangle_positions[9 * j + 3 * a + b];
                ASSERT_EQ(pos, d.ell.slot_position[f.pattern.triangle_slots[9 * t + 3 * a + b]]);
                ASSERT_EQ(ell_row(d.ell, pos), f.triangles[t].v[a]);
                ASSERT_EQ(d.ell.column[pos], f.triangles[t].v[b]);
            }
    }
    for (std::size_t j = 0; j < nh; ++j) {
        const std::uint32_t k = d.hinge_colors.order[j];
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
                const std::uint32_t pos = d.hinge_positions[16 * j + 4 * a + b];
                ASSERT_EQ(pos, d.ell.slot_position[f.pattern.hinge_slots[16 * k + 4 * a + b]]);
                ASSERT_EQ(ell_row(d.ell, pos), f.hinges[k].v[a]);
                ASSERT_EQ(d.ell.column[pos], f.hinges[k].v[b]);
            }
    }
}

/// Checks one incidence CSR: vertex i lists exactly the (element, corner) pairs whose corner is i,
/// as 4·element + corner, in increasing element order (the fixed summation order of the row gather).
void expect_incidence(const std::vector<std::uint32_t>& ids, std::size_t corners, std::size_t vertex_count,
                      const std::vector<std::uint32_t>& start, const std::vector<std::uint32_t>& entries) {
    ASSERT_EQ(start.size(), vertex_count + 1);
    ASSERT_EQ(entries.size(), ids.size());
    std::vector<std::vector<std::uint32_t>> expected(vertex_count);
    for (std::size_t e = 0; e < ids.size() / corners; ++e)
        for (std::size_t a = 0; a < corners; ++a)
            expected[ids[corners * e + a]].push_back(static_cast<std::uint32_t>(4 * e + a));
    for (std::size_t i = 0; i < vertex_count; ++i) {
        const std::vector<std::uint32_t> got(entries.begin() + start[i], entries.begin() + start[i + 1]);
        ASSERT_EQ(got, expected[i]) << "vertex " << i;
    }
}

/// Element vertex ids in colour order (the order the device stores elements in).
std::vector<std::uint32_t> in_color_order(const std::vector<std::uint32_t>& ids, std::size_t corners, const Coloring& c) {
    std::vector<std::uint32_t> out;
    for (std::uint32_t e : c.order) out.insert(out.end(), ids.begin() + corners * e, ids.begin() + corners * (e + 1));
    return out;
}

TEST(DeviceLayout, IncidenceListsEveryElementCornerOnceInOrder) {
    // The row gather sums each row over these lists and the normals sum the triangle list: an element
    // missing or repeated skews the matrix and the normals.
    const FlatModel f = flag_model();
    const DeviceLayout d = make_device_layout(f);
    expect_incidence(in_color_order(triangle_ids(f), 3, d.triangle_colors), 3, f.vertex_count, d.vertex_triangle_start,
                     d.vertex_triangle);
    expect_incidence(in_color_order(hinge_ids(f), 4, d.hinge_colors), 4, f.vertex_count, d.vertex_hinge_start,
                     d.vertex_hinge);
}

TEST(DeviceLayout, MaxRowWidthIsTheWidestRow) {
    const FlatModel f = flag_model();
    const DeviceLayout d = make_device_layout(f);
    std::uint32_t widest = 0;
    for (std::size_t i = 0; i < f.vertex_count; ++i)
        widest = std::max(widest, f.pattern.row_start[i + 1] - f.pattern.row_start[i]);
    EXPECT_EQ(d.max_row_width, widest);
}

}  // namespace
}  // namespace weft::cuda
