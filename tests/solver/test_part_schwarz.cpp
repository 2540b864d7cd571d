// One part's share of the multilevel Schwarz preconditioner (weft/backend/part_schwarz.h): the
// parts' level-0 domains tile the whole hierarchy's, each part's level-0 tables are the whole's in
// its own vertex and slot ids, the parts' level-1 coupling entries tile the whole's with the same
// sources in the same order, and the levels above are the whole's: so a device computing its part
// and gathering level 1 builds exactly the single-GPU preconditioner.
#include <gtest/gtest.h>

#include "weft/backend/flat_model.h"
#include "weft/backend/part_model.h"
#include "weft/backend/part_schwarz.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/backend/vertex_partition.h"
#include "weft/error.h"
#include "weft/fabric.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

// A sheet and a smaller one beside it: several levels, and domains with more than one piece.
FlatModel two_sheets() {
    World world;
    world.add_cloth(ClothDesc{.name = "a", .fabric = Fabric::cook(make_grid(1.0, 0.6, 70, 42))});
    ClothDesc b{.name = "b", .fabric = Fabric::cook(make_grid(0.5, 0.5, 20, 20))};
    b.transform.translation = {0.2, 0.1, 0.02};
    world.add_cloth(b);
    return flatten(world.model());
}

TEST(PartSchwarz, PartsComputeTheWholePreconditionerBetweenThem) {
    const FlatModel flat = two_sheets();
    const SchwarzHierarchy whole = build_schwarz_hierarchy(flat.initial_positions, flat.pattern);
    ASSERT_GE(whole.levels(), 3);
    const SchwarzLevel& w0 = whole.level[0];
    const SchwarzLevel& w1 = whole.level[1];
    for (const std::uint32_t parts : {1U, 2U, 5U}) {
        const VertexPartition vp = partition_along_preconditioner(flat, parts);
        std::uint32_t next_domain = 0, next_node = 0, next_entry = 0;
        std::size_t dense = 0;
        for (std::uint32_t p = 0; p < parts; ++p) {
            const PartModel pm = extract_part(flat, vp, p);
            const PartSchwarz ps = extract_part_schwarz(whole, pm);
            const SchwarzHierarchy& h = ps.levels;
            ASSERT_EQ(h.levels(), whole.levels());
            // Level 0: the next run of whole domains, in local ids.
            EXPECT_EQ(ps.first_domain, next_domain);
            const std::uint32_t first_node = ps.first_domain * SchwarzHierarchy::kDomainSize;
            ASSERT_EQ(h.level[0].nodes, pm.owned);
            for (std::uint32_t k = 0; k < pm.owned; ++k) {
                ASSERT_LT(h.order[k], pm.owned);
                EXPECT_EQ(pm.global_vertex[h.order[k]], whole.order[first_node + k]);
                EXPECT_EQ(h.rank[h.order[k]], k);
                EXPECT_EQ(h.level[0].parent[k], w0.parent[first_node + k]);
            }
            next_domain += h.level[0].domains();
            for (std::size_t k = 0; k < h.level[0].dense_entry.size(); ++k, ++dense) {
                EXPECT_EQ(pm.global_slot[h.level[0].dense_entry[k]], w0.dense_entry[dense]);
                EXPECT_EQ(h.level[0].dense_block[k] + (ps.first_domain << (2 * SchwarzHierarchy::kDomainBits)), w0.dense_block[dense]);
            }
            // Level 1: the part's row nodes and their entries follow on from the last part's.
            EXPECT_EQ(ps.node_begin, next_node);
            EXPECT_EQ(ps.entry_begin, next_entry);
            next_node = ps.node_end;
            next_entry = ps.entry_end;
            const SchwarzLevel& l1 = h.level[1];
            ASSERT_EQ(l1.source_start.size(), ps.entry_end - ps.entry_begin + 1);
            for (std::uint32_t e = ps.entry_begin; e < ps.entry_end; ++e) {
                EXPECT_GE(w1.entry_row[e], ps.node_begin);
                EXPECT_LT(w1.entry_row[e], ps.node_end);
                const std::uint32_t a = l1.source_start[e - ps.entry_begin], b = l1.source_start[e - ps.entry_begin + 1];
                ASSERT_EQ(b - a, w1.source_start[e + 1] - w1.source_start[e]);
                for (std::uint32_t k = 0; k < b - a; ++k) {
                    const std::uint32_t slot = l1.source[a + k];
                    ASSERT_LT(slot, pm.model.pattern.row_start[pm.owned]) << "a source outside the part's owned rows";
                    EXPECT_EQ(pm.global_slot[slot], w1.source[w1.source_start[e] + k]);
                }
            }
            EXPECT_EQ(l1.entry_row, w1.entry_row);  // whole: it sizes the gathered couplings
            EXPECT_EQ(l1.dense_entry, w1.dense_entry);
            for (int l = 2; l < whole.levels(); ++l) {
                const SchwarzLevel& a = h.level[static_cast<std::size_t>(l)];
                const SchwarzLevel& b = whole.level[static_cast<std::size_t>(l)];
                EXPECT_EQ(a.nodes, b.nodes);
                EXPECT_EQ(a.source, b.source);
                EXPECT_EQ(a.dense_block, b.dense_block);
            }
        }
        EXPECT_EQ(next_domain, w0.domains()) << parts << " parts";
        EXPECT_EQ(dense, w0.dense_entry.size());
        EXPECT_EQ(next_node, w1.nodes);
        EXPECT_EQ(next_entry, w1.entry_row.size());
    }
}

TEST(PartSchwarz, APartOfAnotherCutIsAnError) {
    const FlatModel flat = two_sheets();
    const SchwarzHierarchy whole = build_schwarz_hierarchy(flat.initial_positions, flat.pattern);
    // Every other vertex: not whole domains of the hierarchy's order.
    std::vector<std::uint32_t> part_of(flat.vertex_count);
    for (std::size_t i = 0; i < part_of.size(); ++i) part_of[i] = static_cast<std::uint32_t>(i % 2);
    const VertexPartition vp = build_partition(flat.pattern, part_of, 2, row_work(flat.pattern));
    EXPECT_THROW((void)extract_part_schwarz(whole, extract_part(flat, vp, 0)), Error);
}

}  // namespace
}  // namespace weft
