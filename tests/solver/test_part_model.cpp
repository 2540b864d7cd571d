// A part of a partitioned world as a model of its own (weft/backend/part_model.h): owned rows that
// are the global rows exactly (columns, slot sums and force gathers in the same order, so a backend
// gets the same bits on any number of parts), elements that touch an owned vertex and no other, pins
// of owned vertices, and clear errors for a partition of another model.
#include <gtest/gtest.h>

#include <set>

#include "weft/backend/flat_model.h"
#include "weft/backend/part_model.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/backend/vertex_partition.h"
#include "weft/error.h"
#include "weft/fabric.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

// Two cloths side by side (the second shifted), with pins on both: a world's flat model.
FlatModel two_cloths() {
    World world;
    ClothDesc a{.name = "a", .fabric = Fabric::cook(make_grid(1.0, 1.0, 24, 24))};
    a.pins = {{.vertex = 0}, {.vertex = 24}};
    ClothDesc b{.name = "b", .fabric = Fabric::cook(make_grid(0.6, 0.4, 15, 9))};
    b.transform.translation = {0.3, 0.2, 0.05};
    b.pins = {{.vertex = 5}};
    world.add_cloth(a);
    world.add_cloth(b);
    return flatten(world.model());
}

VertexPartition partition(const FlatModel& flat, std::uint32_t parts) { return partition_along_preconditioner(flat, parts); }

/// The multi-GPU solver's partition for the bending model per triangle: the preconditioner's cut,
/// with per_triangle_bending_reach's vertices as ghosts too.
VertexPartition partition_with_reach(const FlatModel& flat, std::uint32_t parts) {
    const SchwarzHierarchy h = build_schwarz_hierarchy(flat.initial_positions, flat.pattern);
    const std::vector<double> work = row_work(flat.pattern);
    const VertexReach reach = per_triangle_bending_reach(flat);
    return build_partition(flat.pattern, cut_order(h.order, work, parts, SchwarzHierarchy::kDomainSize), parts, work, &reach);
}

// The element corner or block behind a gather entry, in global terms: (kind, global element, corner).
struct Source {
    int kind;
    std::uint32_t element, corner;
    bool operator==(const Source&) const = default;
};

Source force_source(const FlatModel& m, const std::vector<std::uint32_t>& tri, const std::vector<std::uint32_t>& hinge,
                    std::uint32_t entry) {
    const auto t3 = static_cast<std::uint32_t>(3 * m.triangles.size());
    if (entry < t3) return {0, tri.empty() ? entry / 3 : tri[entry / 3], entry % 3};
    return {1, hinge.empty() ? (entry - t3) / 4 : hinge[(entry - t3) / 4], (entry - t3) % 4};
}

Source block_source(const FlatModel& m, const std::vector<std::uint32_t>& tri, const std::vector<std::uint32_t>& hinge,
                    std::uint32_t entry) {
    const auto t9 = static_cast<std::uint32_t>(9 * m.triangles.size());
    if (entry < t9) return {0, tri.empty() ? entry / 9 : tri[entry / 9], entry % 9};
    return {1, hinge.empty() ? (entry - t9) / 16 : hinge[(entry - t9) / 16], (entry - t9) % 16};
}

// With the bending model per triangle the parts hold more elements (extract_part), all touching
// ghosts only: the owned rows are the same.
TEST(PartModel, OwnedRowsAreTheGlobalRowsInTheSameOrder) {
    const FlatModel flat = two_cloths();
    const std::vector<std::uint32_t> none;
    for (const bool per_triangle : {false, true})
    for (const std::uint32_t parts : {1U, 3U, 6U}) {
        const VertexPartition vp = per_triangle ? partition_with_reach(flat, parts) : partition(flat, parts);
        std::size_t owned_total = 0;
        std::set<std::uint32_t> pinned;
        for (std::uint32_t p = 0; p < parts; ++p) {
            SCOPED_TRACE("part " + std::to_string(p) + " of " + std::to_string(parts) + (per_triangle ? ", per-triangle bending" : ""));
            const PartModel pm = extract_part(flat, vp, p, per_triangle);
            const FlatModel& m = pm.model;
            ASSERT_EQ(pm.owned, vp.part[p].owned.size());
            ASSERT_EQ(m.vertex_count, pm.owned + vp.part[p].ghosts.size());
            owned_total += pm.owned;
            for (std::uint32_t i = 0; i < m.vertex_count; ++i) {
                const std::uint32_t g = pm.global_vertex[i];
                EXPECT_EQ(m.initial_positions[i], flat.initial_positions[g]);
                EXPECT_EQ(m.mass[i], flat.mass[g]);
                if (i >= pm.owned) continue;
                // The row: same columns, same order; each slot sums the same blocks in the same order.
                ASSERT_EQ(m.pattern.row_start[i + 1] - m.pattern.row_start[i], flat.pattern.row_start[g + 1] - flat.pattern.row_start[g]);
                for (std::uint32_t k = 0; k < m.pattern.row_start[i + 1] - m.pattern.row_start[i]; ++k) {
                    const std::uint32_t ls = m.pattern.row_start[i] + k, gs = flat.pattern.row_start[g] + k;
                    EXPECT_EQ(pm.global_slot[ls], gs);
                    EXPECT_EQ(pm.global_vertex[m.pattern.column[ls]], flat.pattern.column[gs]);
                    ASSERT_EQ(m.slot_block_start[ls + 1] - m.slot_block_start[ls], flat.slot_block_start[gs + 1] - flat.slot_block_start[gs]);
                    for (std::uint32_t e = 0; e < m.slot_block_start[ls + 1] - m.slot_block_start[ls]; ++e)
                        EXPECT_EQ(block_source(m, pm.global_triangle, pm.global_hinge, m.slot_block_index[m.slot_block_start[ls] + e]),
                                  block_source(flat, none, none, flat.slot_block_index[flat.slot_block_start[gs] + e]));
                }
                EXPECT_EQ(pm.global_vertex[m.pattern.column[m.pattern.diagonal[i]]], g);
                // The forces: the same element corners in the same order.
                ASSERT_EQ(m.vertex_force_start[i + 1] - m.vertex_force_start[i], flat.vertex_force_start[g + 1] - flat.vertex_force_start[g]);
                for (std::uint32_t e = 0; e < m.vertex_force_start[i + 1] - m.vertex_force_start[i]; ++e)
                    EXPECT_EQ(force_source(m, pm.global_triangle, pm.global_hinge, m.vertex_force_index[m.vertex_force_start[i] + e]),
                              force_source(flat, none, none, flat.vertex_force_index[flat.vertex_force_start[g] + e]));
                if (m.vertex_pin[i] >= 0) pinned.insert(g);
            }
            // Exactly the elements that touch an owned vertex (with per-triangle bending, at least).
            std::size_t touching = 0;
            for (const Triangle& t : flat.triangles) {
                bool owns = false;
                for (const std::uint32_t v : t.v) owns = owns || vp.part_of[v] == p;
                touching += owns ? 1 : 0;
            }
            if (per_triangle) {
                EXPECT_GE(m.triangles.size(), touching);
            } else {
                EXPECT_EQ(m.triangles.size(), touching);
            }
            for (const std::uint32_t s : m.pattern.triangle_slots) EXPECT_LT(s, m.pattern.block_count());
            for (const std::uint32_t s : m.pattern.hinge_slots) EXPECT_LT(s, m.pattern.block_count());
            // Ghost pins stay with their owners.
            for (const std::uint32_t v : m.pin_vertex) EXPECT_LT(v, pm.owned);
        }
        EXPECT_EQ(owned_total, flat.vertex_count);
        EXPECT_EQ(pinned, std::set<std::uint32_t>(flat.pin_vertex.begin(), flat.pin_vertex.end())) << "every pin on its owner";
    }
}

// The bending model per triangle: a hinge through an owned vertex takes terms from both its faces,
// and each face's terms read its three hinges. Each part holds all of them, with its triangles'
// hinges mapped to the same global hinges and the same rest data, on the same cut as without the
// reach. Without the reach in the partition the part cannot hold them, and says so.
TEST(PartModel, PerTriangleBendingPartsHoldEveryFaceTheirRowsRead) {
    const FlatModel flat = two_cloths();
    std::vector<std::vector<std::uint32_t>> faces_of(flat.hinges.size());
    for (std::uint32_t t = 0; t < flat.triangles.size(); ++t)
        for (const std::int32_t h : flat.triangle_hinges[t].edge)
            if (h >= 0) faces_of[static_cast<std::size_t>(h)].push_back(t);
    for (const std::uint32_t parts : {2U, 3U, 6U}) {
        const VertexPartition vp = partition_with_reach(flat, parts), plain = partition(flat, parts);
        for (std::uint32_t p = 0; p < parts; ++p) {
            SCOPED_TRACE("part " + std::to_string(p) + " of " + std::to_string(parts));
            const PartModel pm = extract_part(flat, vp, p, true);
            const FlatModel& m = pm.model;
            ASSERT_EQ(m.triangle_hinges.size(), m.triangles.size());
            ASSERT_EQ(m.shell_rest.size(), m.triangles.size());
            std::vector<std::int32_t> local_triangle(flat.triangles.size(), -1);
            for (std::size_t t = 0; t < pm.global_triangle.size(); ++t) local_triangle[pm.global_triangle[t]] = static_cast<std::int32_t>(t);
            std::size_t needed = 0;
            for (std::uint32_t h = 0; h < flat.hinges.size(); ++h) {
                bool owned = false;
                for (const std::uint32_t v : flat.hinges[h].v) owned = owned || vp.part_of[v] == p;
                if (!owned) continue;
                for (const std::uint32_t t : faces_of[h]) {
                    ++needed;
                    const std::int32_t lt = local_triangle[t];
                    ASSERT_GE(lt, 0) << "face " << t << " of hinge " << h << " is not in the part";
                    const auto l = static_cast<std::size_t>(lt);
                    EXPECT_EQ(m.shell_rest[l].area, flat.shell_rest[t].area);
                    for (int k = 0; k < 3; ++k) {
                        const std::int32_t g = flat.triangle_hinges[t].edge[k], local = m.triangle_hinges[l].edge[k];
                        ASSERT_EQ(local >= 0, g >= 0) << "triangle " << t << " edge " << k;
                        if (g >= 0) {
                            EXPECT_EQ(pm.global_hinge[static_cast<std::size_t>(local)], static_cast<std::uint32_t>(g));
                        }
                    }
                }
            }
            EXPECT_GT(needed, 0U);
            // The same cut as without the reach, with the pattern's ghosts among its own.
            EXPECT_EQ(vp.part[p].owned, plain.part[p].owned);
            const std::set<std::uint32_t> with(vp.part[p].ghosts.begin(), vp.part[p].ghosts.end());
            for (const std::uint32_t g : plain.part[p].ghosts) EXPECT_EQ(with.count(g), 1U) << "ghost " << g;
        }
        // Without the reach some part misses a far corner and refuses.
        bool refused = false;
        for (std::uint32_t p = 0; p < parts && !refused; ++p) {
            try {
                (void)extract_part(flat, plain, p, true);
            } catch (const Error& e) {
                refused = true;
                EXPECT_NE(std::string(e.what()).find("per-triangle bending"), std::string::npos) << e.what();
            }
        }
        EXPECT_TRUE(refused) << parts << " parts without the reach";
    }
}

TEST(PartModel, APartitionOfAnotherModelIsRefused) {
    const FlatModel flat = two_cloths();
    const VertexPartition vp = partition(flat, 2);
    EXPECT_THROW((void)extract_part(flat, vp, 2), Error);
    World small;
    small.add_cloth({.name = "small", .fabric = Fabric::cook(make_grid(1.0, 1.0, 4, 4))});
    try {
        (void)extract_part(flatten(small.model()), vp, 0);
        FAIL() << "a partition of another model accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("a partition of"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace weft
