// Vertex partitions for the multi-GPU solve (weft/backend/vertex_partition.h): every vertex owned
// once, interior rows with no neighbour elsewhere, ghosts exactly the off-part pattern neighbours,
// sends that mirror them, balanced cuts along the preconditioner's order, and a product assembled
// part by part through the halo lists that equals the whole product bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "weft/backend/flat_model.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/backend/vertex_partition.h"
#include "weft/error.h"
#include "weft/fabric.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

struct Grid {
    std::shared_ptr<const Fabric> fabric;
    SchwarzHierarchy hierarchy;
};

Grid make_cloth(int cells) {
    Grid g;
    g.fabric = Fabric::cook(make_grid(1.0, 1.0, cells, cells));
    const std::vector<Vec3d> rest(g.fabric->rest_positions().begin(), g.fabric->rest_positions().end());
    g.hierarchy = build_schwarz_hierarchy(rest, g.fabric->pattern());
    return g;
}

VertexPartition partition_along_order(const Grid& g, std::uint32_t parts) {
    const std::vector<double> work = row_work(g.fabric->pattern());
    const std::vector<std::uint32_t> part_of =
        cut_order(g.hierarchy.order, work, parts, SchwarzHierarchy::kDomainSize);
    return build_partition(g.fabric->pattern(), part_of, parts, work);
}

// The structural promises, checked from the pattern alone.
void expect_consistent(const BlockPattern& pattern, const VertexPartition& vp) {
    const std::size_t n = pattern.row_start.size() - 1;
    std::vector<int> owners(n, 0);
    for (std::uint32_t p = 0; p < vp.parts; ++p) {
        const PartitionPart& part = vp.part[p];
        for (std::size_t k = 0; k < part.owned.size(); ++k) {
            const std::uint32_t i = part.owned[k];
            ++owners[i];
            EXPECT_EQ(vp.part_of[i], p);
            EXPECT_EQ(vp.local_index[i], k);
            bool off_part = false;
            for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s)
                off_part = off_part || vp.part_of[pattern.column[s]] != p;
            EXPECT_EQ(off_part, k >= part.interior) << "vertex " << i << " listed on the wrong side";
        }
        // Ghosts: exactly the off-part columns of the part's rows, grouped by owner.
        std::set<std::uint32_t> expected;
        for (const std::uint32_t i : part.owned)
            for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s)
                if (vp.part_of[pattern.column[s]] != p) expected.insert(pattern.column[s]);
        EXPECT_EQ(std::set<std::uint32_t>(part.ghosts.begin(), part.ghosts.end()), expected);
        EXPECT_EQ(part.ghosts.size(), expected.size()) << "a ghost listed twice";
        ASSERT_EQ(part.ghost_start.size(), vp.parts + 1);
        for (std::uint32_t q = 0; q < vp.parts; ++q)
            for (std::uint32_t k = part.ghost_start[q]; k < part.ghost_start[q + 1]; ++k)
                EXPECT_EQ(vp.part_of[part.ghosts[k]], q);
        EXPECT_EQ(part.ghost_start[p + 1] - part.ghost_start[p], 0U) << "a part is its own ghost";
        // Sends: what each receiver lists, in its order.
        ASSERT_EQ(part.send_start.size(), vp.parts + 1);
        for (std::uint32_t q = 0; q < vp.parts; ++q) {
            const PartitionPart& receiver = vp.part[q];
            ASSERT_EQ(part.send_start[q + 1] - part.send_start[q], receiver.ghost_start[p + 1] - receiver.ghost_start[p]);
            for (std::uint32_t k = 0; k < part.send_start[q + 1] - part.send_start[q]; ++k)
                EXPECT_EQ(part.owned[part.send[part.send_start[q] + k]], receiver.ghosts[receiver.ghost_start[p] + k]);
        }
    }
    for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(owners[i], 1) << "vertex " << i;
}

TEST(VertexPartition, CutsAlongThePreconditionerOrderAreConsistentAndBalanced) {
    const Grid g = make_cloth(47);  // 48² vertices
    for (const std::uint32_t parts : {1U, 2U, 3U, 4U, 8U}) {
        const VertexPartition vp = partition_along_order(g, parts);
        SCOPED_TRACE(describe(vp.quality, parts));
        expect_consistent(g.fabric->pattern(), vp);
        // Whole level-0 domains of the preconditioner on each part.
        for (std::size_t p = 0; p + SchwarzHierarchy::kDomainSize <= g.hierarchy.order.size(); p += SchwarzHierarchy::kDomainSize)
            for (std::uint32_t k = 1; k < SchwarzHierarchy::kDomainSize; ++k)
                EXPECT_EQ(vp.part_of[g.hierarchy.order[p + k]], vp.part_of[g.hierarchy.order[p]]) << "domain at " << p;
        // Balanced to within a domain's work per part.
        EXPECT_LT(vp.quality.imbalance, 1.0 + 0.05 * parts);
        if (parts == 1) {
            EXPECT_EQ(vp.quality.cut_blocks, 0U);
            EXPECT_EQ(vp.part[0].interior, g.fabric->vertex_count());
        } else {
            EXPECT_GT(vp.quality.halo_vertices, 0U);
            // A spatially local cut: far fewer halo vertices than vertices.
            EXPECT_LT(vp.quality.halo_vertices, g.fabric->vertex_count() / 3);
        }
    }
}

// What the detections weigh: a part's rows plus its contacts in the same units, busiest over mean.
TEST(VertexPartition, PartWorkImbalanceWeighsContactsAgainstRows) {
    const std::vector<double> rows = {100.0, 100.0};
    EXPECT_DOUBLE_EQ(part_work_imbalance(rows, std::vector<std::size_t>{0, 0}), 1.0);
    // 40 contacts on the first part weigh 4·kContactWorkPerVertex·40 blocks more.
    const double extra = 4.0 * kContactWorkPerVertex * 40.0;
    EXPECT_DOUBLE_EQ(part_work_imbalance(rows, std::vector<std::size_t>{40, 0}), (100.0 + extra) * 2.0 / (200.0 + extra));
    // Fewer rows on the part with the contacts can even it out.
    EXPECT_DOUBLE_EQ(part_work_imbalance(std::vector<double>{100.0 - extra / 2, 100.0 + extra / 2}, std::vector<std::size_t>{40, 0}),
                     1.0);
    EXPECT_DOUBLE_EQ(part_work_imbalance(std::vector<double>{0.0, 0.0}, std::vector<std::size_t>{0, 0}), 1.0);
    EXPECT_THROW((void)part_work_imbalance(rows, std::vector<std::size_t>{1}), Error);
}

// A re-cut by contact load: contacts piled on one corner of the cloth move rows off the part that
// holds it, the parts' row-and-contact work comes out even, and the cut stays consistent.
TEST(VertexPartition, ContactWorkMovesRowsOffTheBusyPart) {
    const Grid g = make_cloth(47);
    const BlockPattern& pattern = g.fabric->pattern();
    const std::size_t n = g.fabric->vertex_count();
    const std::vector<Vec3d> rest(g.fabric->rest_positions().begin(), g.fabric->rest_positions().end());
    std::vector<std::uint32_t> contacts_at(n, 0);
    // A fold over a quarter of the cloth, as heavy (30 pattern blocks a vertex) whatever a contact weighs.
    const auto fold = static_cast<std::uint32_t>(std::lround(30.0 / kContactWorkPerVertex));
    for (std::size_t i = 0; i < n; ++i)
        if (rest[i].x > 0.25 && rest[i].y > 0.25) contacts_at[i] = fold;
    const std::vector<double> rows = row_work(pattern), loaded = row_and_contact_work(pattern, contacts_at);
    for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(loaded[i], rows[i] + kContactWorkPerVertex * contacts_at[i]);
    for (const std::uint32_t parts : {2U, 4U}) {
        const VertexPartition by_rows = partition_along_order(g, parts);
        const VertexPartition by_load =
            build_partition(pattern, cut_order(g.hierarchy.order, loaded, parts, SchwarzHierarchy::kDomainSize), parts, loaded);
        expect_consistent(pattern, by_load);
        // The load of each part under either cut, and the busiest part's.
        const auto busiest = [&](const VertexPartition& vp) {
            std::vector<double> load(parts, 0.0);
            for (std::size_t i = 0; i < n; ++i) load[vp.part_of[i]] += loaded[i];
            double mean = 0.0;
            for (const double l : load) mean += l / parts;
            return *std::max_element(load.begin(), load.end()) / mean;
        };
        std::printf("[ recut    ] %u parts: busiest part's load %.2f × the mean cut by rows, %.2f cut by rows and contacts\n",
                    parts, busiest(by_rows), busiest(by_load));
        EXPECT_GT(busiest(by_rows), 1.1) << parts << " parts: the test's load is not uneven";
        EXPECT_LT(busiest(by_load), 1.0 + 0.05 * parts) << parts << " parts";
        EXPECT_NEAR(by_load.quality.imbalance, busiest(by_load), 1e-9);
    }
    EXPECT_THROW((void)row_and_contact_work(pattern, std::vector<std::uint32_t>(n - 1, 0)), Error);
}

// What lets the preconditioner run across GPUs with the single-GPU result: with the cut along its
// order, every level-1 node (a connected piece of one level-0 domain) has all its vertices in one
// part, and every level-1 coupling block sums pattern slots of rows that the part owning the block's
// row node owns. So each part forms its level-1 residual values and coupling blocks exactly as one GPU
// would, an all-gather (not a reduction) gives every GPU the whole level 1, and the coarser levels
// are computed redundantly with the same bits (docs/multi-gpu.md).
TEST(VertexPartition, LevelOneOfThePreconditionerNeverStraddlesACut) {
    World world;
    world.add_cloth({.name = "a", .fabric = Fabric::cook(make_grid(1.0, 1.0, 40, 40))});
    ClothDesc b{.name = "b", .fabric = Fabric::cook(make_grid(0.5, 0.5, 17, 17))};
    b.transform.translation = {0.2, 0.1, 0.02};  // a second cloth over the first: interleaved in Morton order
    world.add_cloth(b);
    const FlatModel flat = flatten(world.model());
    const SchwarzHierarchy h = build_schwarz_hierarchy(flat.initial_positions, flat.pattern);
    ASSERT_GE(h.levels(), 2);
    const std::vector<double> work = row_work(flat.pattern);
    std::vector<std::uint32_t> slot_row(flat.pattern.block_count());
    for (std::uint32_t i = 0; i < flat.vertex_count; ++i)
        for (std::uint32_t s = flat.pattern.row_start[i]; s < flat.pattern.row_start[i + 1]; ++s) slot_row[s] = i;
    for (const std::uint32_t parts : {2U, 3U, 8U}) {
        const std::vector<std::uint32_t> part_of = cut_order(h.order, work, parts, SchwarzHierarchy::kDomainSize);
        const SchwarzLevel& fine = h.level[0];
        std::vector<std::uint32_t> node_part(h.nodes(1), parts);
        for (std::uint32_t p = 0; p < h.nodes(0); ++p) {
            std::uint32_t& owner = node_part[fine.parent[p]];
            if (owner == parts) owner = part_of[h.order[p]];
            ASSERT_EQ(owner, part_of[h.order[p]]) << "level-1 node " << fine.parent[p] << " straddles a cut, " << parts << " parts";
        }
        const SchwarzLevel& coarse = h.level[1];
        for (std::size_t e = 0; e < coarse.entry_row.size(); ++e)
            for (std::uint32_t k = coarse.source_start[e]; k < coarse.source_start[e + 1]; ++k)
                ASSERT_EQ(part_of[slot_row[coarse.source[k]]], node_part[coarse.entry_row[e]])
                    << "level-1 coupling " << e << " sums a slot of another part's row, " << parts << " parts";
    }
}

TEST(VertexPartition, AnyAssignmentIsConsistentEmptyPartsIncluded) {
    const Grid g = make_cloth(20);
    const std::size_t n = g.fabric->vertex_count();
    std::mt19937 rng(7);
    std::vector<std::uint32_t> part_of(n);
    for (auto& p : part_of) p = static_cast<std::uint32_t>(rng() % 3);  // part 3 of 4 stays empty
    const VertexPartition vp = build_partition(g.fabric->pattern(), part_of, 4, row_work(g.fabric->pattern()));
    expect_consistent(g.fabric->pattern(), vp);
    EXPECT_TRUE(vp.part[3].owned.empty());
}

// y = A·x by parts: each part copies its ghosts' values from the owners' send lists (the halo
// exchange), then multiplies its owned rows with local and ghost values. Equal to the whole product
// bit for bit: every row sums its blocks in the pattern's order either way.
TEST(VertexPartition, ProductThroughTheHaloEqualsTheWholeProduct) {
    const Grid g = make_cloth(31);
    const BlockPattern& pattern = g.fabric->pattern();
    const std::size_t n = g.fabric->vertex_count();
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<double> block(pattern.block_count()), x(n);
    for (double& b : block) b = u(rng);
    for (double& v : x) v = u(rng);
    std::vector<double> whole(n, 0.0);
    for (std::size_t i = 0; i < n; ++i)
        for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s) whole[i] += block[s] * x[pattern.column[s]];

    for (const std::uint32_t parts : {2U, 5U}) {
        const VertexPartition vp = partition_along_order(g, parts);
        // Each part's local vector: owned values, then ghosts (filled only through the exchange).
        std::vector<std::vector<double>> local(parts);
        for (std::uint32_t p = 0; p < parts; ++p) {
            local[p].assign(vp.part[p].owned.size() + vp.part[p].ghosts.size(), std::nan(""));
            for (std::size_t k = 0; k < vp.part[p].owned.size(); ++k) local[p][k] = x[vp.part[p].owned[k]];
        }
        for (std::uint32_t p = 0; p < parts; ++p)  // the exchange: p sends to every q
            for (std::uint32_t q = 0; q < parts; ++q) {
                const PartitionPart& from = vp.part[p];
                const PartitionPart& to = vp.part[q];
                for (std::uint32_t k = 0; k < from.send_start[q + 1] - from.send_start[q]; ++k)
                    local[q][to.owned.size() + to.ghost_start[p] + k] = local[p][from.send[from.send_start[q] + k]];
            }
        std::vector<double> by_parts(n, std::nan(""));
        for (std::uint32_t p = 0; p < parts; ++p) {
            const PartitionPart& part = vp.part[p];
            // Global id → local slot of this part (owned or ghost).
            auto slot = [&](std::uint32_t j) -> std::size_t {
                if (vp.part_of[j] == p) return vp.local_index[j];
                const auto first = part.ghosts.begin() + part.ghost_start[vp.part_of[j]];
                const auto last = part.ghosts.begin() + part.ghost_start[vp.part_of[j] + 1];
                const auto it = std::lower_bound(first, last, j);
                EXPECT_TRUE(it != last && *it == j) << "vertex " << j << " is not a ghost of part " << p;
                return part.owned.size() + static_cast<std::size_t>(it - part.ghosts.begin());
            };
            for (const std::uint32_t i : part.owned) {
                double sum = 0.0;
                for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s)
                    sum += block[s] * local[p][slot(pattern.column[s])];
                by_parts[i] = sum;
            }
        }
        for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(by_parts[i], whole[i]) << "row " << i << ", " << parts << " parts";
    }
}

TEST(VertexPartition, SameInputSameCut) {
    const Grid g = make_cloth(30);
    const VertexPartition a = partition_along_order(g, 4), b = partition_along_order(g, 4);
    EXPECT_EQ(a.part_of, b.part_of);
    for (std::uint32_t p = 0; p < 4; ++p) {
        EXPECT_EQ(a.part[p].owned, b.part[p].owned);
        EXPECT_EQ(a.part[p].ghosts, b.part[p].ghosts);
        EXPECT_EQ(a.part[p].send, b.part[p].send);
    }
}

// The bending model per triangle's reach: a vertex reads the vertices of every hinge of every face
// of every hinge through it, which covers its pattern neighbours and goes a ring further (on a grid,
// a far corner across a face's other edge). Those become ghosts; a reach of another size is refused.
TEST(VertexPartition, PerTriangleBendingReachesARingFurtherAndBecomesGhosts) {
    World world;
    world.add_cloth({.name = "sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, 12, 12))});
    const FlatModel flat = flatten(world.model());
    const BlockPattern& pattern = flat.pattern;
    const VertexReach reach = per_triangle_bending_reach(flat);
    ASSERT_EQ(reach.start.size(), flat.vertex_count + 1);
    std::size_t beyond = 0;
    for (std::uint32_t i = 0; i < flat.vertex_count; ++i) {
        const std::set<std::uint32_t> r(reach.vertex.begin() + reach.start[i], reach.vertex.begin() + reach.start[i + 1]);
        EXPECT_EQ(r.size(), reach.start[i + 1] - reach.start[i]) << "vertex " << i << " lists a vertex twice";
        for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s)
            EXPECT_EQ(r.count(pattern.column[s]), 1U) << "vertex " << i << " does not reach its neighbour " << pattern.column[s];
        beyond += r.size() - (pattern.row_start[i + 1] - pattern.row_start[i]);
    }
    EXPECT_GT(beyond, 0U) << "the reach is the pattern's";
    const SchwarzHierarchy h = build_schwarz_hierarchy(flat.initial_positions, pattern);
    const std::vector<double> work = row_work(pattern);
    const std::vector<std::uint32_t> part_of = cut_order(h.order, work, 3, SchwarzHierarchy::kDomainSize);
    const VertexPartition plain = build_partition(pattern, part_of, 3, work);
    const VertexPartition wide = build_partition(pattern, part_of, 3, work, &reach);
    expect_consistent(pattern, plain);
    EXPECT_GT(wide.quality.halo_vertices, plain.quality.halo_vertices);
    for (std::uint32_t p = 0; p < 3; ++p) {
        EXPECT_EQ(wide.part[p].owned, plain.part[p].owned);
        EXPECT_EQ(wide.part[p].interior, plain.part[p].interior) << "the product still reads one ring";
        const std::set<std::uint32_t> ghosts(wide.part[p].ghosts.begin(), wide.part[p].ghosts.end());
        for (const std::uint32_t i : wide.part[p].owned)
            for (std::uint32_t s = reach.start[i]; s < reach.start[i + 1]; ++s) {
                const std::uint32_t j = reach.vertex[s];
                EXPECT_TRUE(part_of[j] == p || ghosts.count(j) == 1) << "part " << p << " misses vertex " << j;
            }
    }
    VertexReach short_reach = reach;
    short_reach.start.pop_back();
    EXPECT_THROW((void)build_partition(pattern, part_of, 3, work, &short_reach), Error);
}

TEST(VertexPartition, BadInputIsAnErrorNamingTheValue) {
    const Grid g = make_cloth(3);  // 16 vertices: one domain
    const std::vector<double> work = row_work(g.fabric->pattern());
    try {
        (void)cut_order(g.hierarchy.order, work, 2, SchwarzHierarchy::kDomainSize);
        FAIL() << "cut 16 vertices in domains of 16 into 2 parts";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("into 2 parts"), std::string::npos) << e.what();
    }
    EXPECT_THROW((void)cut_order(g.hierarchy.order, work, 0, 1), Error);
    EXPECT_THROW((void)cut_order(g.hierarchy.order, std::vector<double>(3), 1, 1), Error);
    std::vector<std::uint32_t> part_of(g.fabric->vertex_count(), 0);
    part_of[5] = 2;
    try {
        (void)build_partition(g.fabric->pattern(), part_of, 2, work);
        FAIL() << "part 2 of 2 accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("vertex 5 is in part 2"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace weft
