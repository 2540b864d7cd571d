// A part of a partitioned world as a model of its own (weft/backend/part_model.h): owned rows that
// are the global rows exactly (columns, slot sums and force gathers in the same order, so a backend
// gets the same bits on any number of parts), elements that touch an owned vertex and no other, pins
// of owned vertices, and clear errors for a partition of another model.
#include <gtest/gtest.h>

#include <set>

#include "weft/backend/flat_model.h"
#include "weft/backend/part_model.h"
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

TEST(PartModel, OwnedRowsAreTheGlobalRowsInTheSameOrder) {
    const FlatModel flat = two_cloths();
    const std::vector<std::uint32_t> none;
    for (const std::uint32_t parts : {1U, 3U, 6U}) {
        const VertexPartition vp = partition(flat, parts);
        std::size_t owned_total = 0;
        std::set<std::uint32_t> pinned;
        for (std::uint32_t p = 0; p < parts; ++p) {
            SCOPED_TRACE("part " + std::to_string(p) + " of " + std::to_string(parts));
            const PartModel pm = extract_part(flat, vp, p);
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
            // Exactly the elements that touch an owned vertex.
            std::size_t touching = 0;
            for (const Triangle& t : flat.triangles) {
                bool owns = false;
                for (const std::uint32_t v : t.v) owns = owns || vp.part_of[v] == p;
                touching += owns ? 1 : 0;
            }
            EXPECT_EQ(m.triangles.size(), touching);
            for (const std::uint32_t s : m.pattern.triangle_slots) EXPECT_LT(s, m.pattern.block_count());
            for (const std::uint32_t s : m.pattern.hinge_slots) EXPECT_LT(s, m.pattern.block_count());
            // Ghost pins stay with their owners.
            for (const std::uint32_t v : m.pin_vertex) EXPECT_LT(v, pm.owned);
        }
        EXPECT_EQ(owned_total, flat.vertex_count);
        EXPECT_EQ(pinned, std::set<std::uint32_t>(flat.pin_vertex.begin(), flat.pin_vertex.end())) << "every pin on its owner";
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
