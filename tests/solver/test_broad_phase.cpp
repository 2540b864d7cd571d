// The spatial-hash broad phase against brute force (every pair of bounds tested), on random triangle
// soups, a simulated frame of the drape scene and a flat grid whose pairs are known; determinism over
// thread counts; and the counts and time on a 200K-triangle grid.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "weft/backend/model.h"
#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/scene.h"
#include "weft/world.h"

#include "collision/broad_phase.h"
#include "collision/buffer_trim.h"
#include "broad_phase_soups.h"
#include "random_geometry.h"

namespace weft::collision {

// Printers so that a failing comparison names the pairs (found by ADL, hence outside the anonymous
// namespace).
std::ostream& operator<<(std::ostream& os, const VertexFacePair& p) {
    return os << "(v " << p.vertex << ", t " << p.triangle << ")";
}
std::ostream& operator<<(std::ostream& os, const EdgeEdgePair& p) { return os << "(e " << p.a << ", e " << p.b << ")"; }

namespace {

// ---- Brute force ---------------------------------------------------------------------------------
// Written independently of the hash: each bound straight from the positions, every pair tested.

struct Bound {
    Vec3d lo, hi;
    bool finite = true;
};

Bound bound(std::span<const Vec3d> x0, std::span<const Vec3d> x1, std::initializer_list<std::uint32_t> vs,
            double thickness) {
    const double inf = std::numeric_limits<double>::infinity();
    Bound b{{inf, inf, inf}, {-inf, -inf, -inf}};
    for (std::uint32_t v : vs)
        for (const Vec3d& p : {x0[v], x1[v]}) {
            b.finite = b.finite && math::is_finite(p);
            for (int k = 0; k < 3; ++k) {
                b.lo[k] = std::min(b.lo[k], p[k]);
                b.hi[k] = std::max(b.hi[k], p[k]);
            }
        }
    for (int k = 0; k < 3; ++k) {
        b.lo[k] -= thickness;
        b.hi[k] += thickness;
    }
    return b;
}

bool overlap(const Bound& a, const Bound& b) {
    if (!a.finite || !b.finite) return false;
    for (int k = 0; k < 3; ++k)
        if (a.lo[k] > b.hi[k] || b.lo[k] > a.hi[k]) return false;
    return true;
}

struct Reference {
    std::vector<VertexFacePair> vf;
    std::vector<EdgeEdgePair> ee;
};

Reference brute_force(const BroadPhaseInput& in, std::span<const std::uint32_t> vertex_cloth = {}) {
    const auto same_cloth = [&](std::uint32_t va, std::uint32_t vb) {
        return !in.self_pairs && vertex_cloth[va] == vertex_cloth[vb];
    };
    std::vector<Bound> vb, eb, tb;
    for (std::uint32_t v = 0; v < in.x0.size(); ++v) vb.push_back(bound(in.x0, in.x1, {v}, in.thickness));
    for (const Edge& e : in.edges) eb.push_back(bound(in.x0, in.x1, {e.v[0], e.v[1]}, in.thickness));
    for (const Triangle& t : in.triangles) tb.push_back(bound(in.x0, in.x1, {t.v[0], t.v[1], t.v[2]}, in.thickness));
    Reference r;
    for (std::uint32_t v = 0; v < vb.size(); ++v)
        for (std::uint32_t t = 0; t < tb.size(); ++t) {
            const Triangle& tri = in.triangles[t];
            if (v == tri.v[0] || v == tri.v[1] || v == tri.v[2] || same_cloth(v, tri.v[0])) continue;
            if (overlap(vb[v], tb[t])) r.vf.push_back({v, t});
        }
    for (std::uint32_t a = 0; a < eb.size(); ++a)
        for (std::uint32_t b = a + 1; b < eb.size(); ++b) {
            const Edge &ea = in.edges[a], &eb2 = in.edges[b];
            if (ea.v[0] == eb2.v[0] || ea.v[0] == eb2.v[1] || ea.v[1] == eb2.v[0] || ea.v[1] == eb2.v[1]) continue;
            if (same_cloth(ea.v[0], eb2.v[0])) continue;
            if (overlap(eb[a], eb[b])) r.ee.push_back({a, b});
        }
    return r;  // generated in sorted order
}

/// The pair lists must be sorted, unique and equal to `want`; on a mismatch the first few missing and
/// extra pairs are named.
template <typename Pair>
void expect_same(const std::vector<Pair>& got, const std::vector<Pair>& want, const char* what) {
    EXPECT_TRUE(std::is_sorted(got.begin(), got.end())) << what;
    EXPECT_EQ(std::adjacent_find(got.begin(), got.end()), got.end()) << what << ": duplicate pair";
    EXPECT_EQ(got.size(), want.size()) << what;
    std::vector<Pair> missing, extra;
    std::set_difference(want.begin(), want.end(), got.begin(), got.end(), std::back_inserter(missing));
    std::set_difference(got.begin(), got.end(), want.begin(), want.end(), std::back_inserter(extra));
    const auto first = [](const std::vector<Pair>& v) {
        std::ostringstream os;
        for (std::size_t i = 0; i < std::min<std::size_t>(v.size(), 5); ++i) os << ' ' << v[i];
        return os.str();
    };
    EXPECT_TRUE(missing.empty()) << what << ": " << missing.size() << " missing:" << first(missing);
    EXPECT_TRUE(extra.empty()) << what << ": " << extra.size() << " extra:" << first(extra);
}

/// Runs the broad phase and checks it against brute force; returns the result for further checks.
BroadPhaseResult check_against_brute_force(const BroadPhaseInput& in,
                                           std::span<const std::uint32_t> vertex_cloth = {}) {
    BroadPhase bp;
    BroadPhaseResult out;
    bp.find(in, out);
    const Reference want = brute_force(in, vertex_cloth);
    expect_same(out.vf, want.vf, "vertex-face");
    expect_same(out.ee, want.ee, "edge-edge");
    EXPECT_EQ(out.counters.vf_pairs, out.vf.size());
    EXPECT_EQ(out.counters.ee_pairs, out.ee.size());
    EXPECT_GE(out.counters.candidate_pairs, out.vf.size() + out.ee.size());
    EXPECT_GE(out.counters.tested_pairs, out.counters.candidate_pairs);
    return out;
}

// ---- Scenes --------------------------------------------------------------------------------------

struct Soup {
    std::vector<Vec3d> x0, x1;
    std::vector<Triangle> triangles;
    std::vector<Edge> edges;
    double thickness = 0.0;

    [[nodiscard]] BroadPhaseInput input(double cell_size = 0.0) const {
        return {
            .x0 = x0, .x1 = x1, .triangles = triangles, .edges = edges, .thickness = thickness, .cell_size = cell_size};
    }
};

/// A random soup (random_geometry.h) with its edges.
Soup random_soup(unsigned seed, int lattice, std::size_t triangles, double motion, double outliers) {
    std::mt19937 rng(seed);
    test::RandomSoup r = test::random_soup(rng, lattice, triangles, motion, outliers);
    Soup s;
    s.x0 = std::move(r.x0);
    s.x1 = std::move(r.x1);
    s.triangles = std::move(r.triangles);
    s.edges = build_edges(s.triangles);
    return s;
}

Soup grid_soup(double width, double height, int cx, int cy, double thickness) {
    const MeshData mesh = make_grid(width, height, cx, cy, GridPlane::XZ);
    Soup s;
    s.x0 = mesh.positions;
    s.x1 = mesh.positions;
    s.triangles = mesh.triangles;
    s.edges = build_edges(s.triangles);
    s.thickness = thickness;
    return s;
}

// ---- Tests ---------------------------------------------------------------------------------------

TEST(BroadPhase, BuildEdgesIsSortedUniqueAndComplete) {
    const MeshData grid = make_grid(1.0, 1.0, 5, 3);
    const auto edges = build_edges(grid.triangles);
    // A cx×cy grid has cx(cy+1) + (cx+1)cy sides and cx·cy diagonals.
    EXPECT_EQ(edges.size(), std::size_t{5 * 4 + 6 * 3 + 5 * 3});
    for (std::size_t i = 0; i < edges.size(); ++i) {
        EXPECT_LT(edges[i].v[0], edges[i].v[1]);
        if (i > 0) {
            const Edge &p = edges[i - 1], &q = edges[i];
            EXPECT_TRUE(p.v[0] < q.v[0] || (p.v[0] == q.v[0] && p.v[1] < q.v[1])) << i;
        }
    }
    const std::vector<Triangle> bad = {{{0, 1, 1}}};
    EXPECT_THROW((void)build_edges(bad), Error);
}

TEST(BroadPhase, RandomSoupsMatchBruteForce) {
    for (const test::SoupCase& c : test::kSoupCases) {
        SCOPED_TRACE("seed " + std::to_string(c.seed));
        Soup s = random_soup(c.seed, c.lattice, c.triangles, c.motion, c.outliers);
        std::mt19937 rng(c.seed + 100);
        s.thickness = std::uniform_real_distribution<double>(0.0, 0.2)(rng);
        const auto out = check_against_brute_force(s.input());
        EXPECT_GT(out.vf.size(), 0U);
        EXPECT_GT(out.ee.size(), 0U);
        if (c.outliers > 0.0) {
            EXPECT_GT(out.counters.oversized, 0U);
        }
    }
}

TEST(BroadPhase, AnyCellSizeGivesTheSameResult) {
    // Tiny cells make most bounds oversized (tested against everything), huge ones put every
    // primitive in one cell; both must still equal brute force.
    Soup s = random_soup(7, 8, 1000, 0.2, 0.01);
    s.thickness = 0.05;
    for (double cell : {0.02, 0.3, 1.0, 3.0, 1000.0}) {
        SCOPED_TRACE("cell " + std::to_string(cell));
        const auto out = check_against_brute_force(s.input(cell));
        EXPECT_EQ(out.counters.cell_size, cell);
    }
}

TEST(BroadPhase, NonFinitePositionsAreSkipped) {
    Soup s = random_soup(8, 8, 800, 0.1, 0.0);
    s.thickness = 0.1;
    test::make_non_finite(s);
    const auto out = check_against_brute_force(s.input());
    EXPECT_GE(out.counters.nonfinite, 3U);
    for (const VertexFacePair& p : out.vf)
        for (const std::uint32_t v : test::kNonFiniteVertices) EXPECT_NE(p.vertex, v);
}

TEST(BroadPhase, FarApartClustersBeyondTheCellRange) {
    // 10⁷ m apart with ~1 m cells: more than 2²¹ cells, so coordinates are clamped at the border.
    Soup s = random_soup(9, 8, 800, 0.1, 0.0);
    s.thickness = 0.05;
    test::split_far_apart(s);
    (void)check_against_brute_force(s.input());
}

TEST(BroadPhase, ClothFilterKeepsOnlyPairsBetweenCloths) {
    // Two interleaved cloths: lattice planes of even x index are cloth 0, odd ones cloth 1. Only
    // triangles within one plane are kept, and with self pairs off only pairs across cloths remain.
    Soup s = random_soup(10, 8, 600, 0.3, 0.0);
    s.thickness = 0.15;
    const auto cloth = [](std::uint32_t v) { return (v % 8) % 2; };  // lattice of 8: v % 8 is the x index
    std::vector<Triangle> kept;
    std::vector<std::uint32_t> triangle_cloth;
    for (const Triangle& t : s.triangles) {
        if (cloth(t.v[0]) != cloth(t.v[1]) || cloth(t.v[1]) != cloth(t.v[2])) continue;
        kept.push_back(t);
        triangle_cloth.push_back(cloth(t.v[0]));
    }
    s.triangles = kept;
    s.edges = build_edges(s.triangles);
    std::vector<std::uint32_t> vertex_cloth(s.x0.size());
    for (std::uint32_t v = 0; v < vertex_cloth.size(); ++v) vertex_cloth[v] = cloth(v);
    // The broad phase knows the cloth of a vertex only through its triangles; move the vertices no
    // triangle uses out of reach so that both sides agree.
    std::vector<bool> used(s.x0.size(), false);
    for (const Triangle& t : s.triangles)
        for (std::uint32_t v : t.v) used[v] = true;
    for (std::size_t v = 0; v < used.size(); ++v)
        if (!used[v]) s.x0[v] = s.x1[v] = {1.0e3 + static_cast<double>(v), 0.0, 0.0};
    BroadPhaseInput in = s.input();
    in.self_pairs = false;
    in.triangle_cloth = triangle_cloth;
    const auto out = check_against_brute_force(in, vertex_cloth);
    EXPECT_GT(out.vf.size(), 0U);
    EXPECT_GT(out.ee.size(), 0U);
}

TEST(BroadPhase, DrapeFrameMatchesBruteForce) {
    const SceneDesc scene = load_scene(std::string(WEFT_SOURCE_DIR) + "/assets/scenes/drape.toml");
    const auto world = build_world(scene);
    for (int frame = 0; frame < 20; ++frame) (void)world->step();
    const std::vector<Vec3d> x0 = world->positions(0);
    (void)world->step();
    const std::vector<Vec3d> x1 = world->positions(0);
    const ClothDesc& cloth = world->model().cloths[0];
    const auto triangles = cloth.fabric->triangles();
    const auto edges = build_edges(triangles);
    const BroadPhaseInput in{
        .x0 = x0, .x1 = x1, .triangles = triangles, .edges = edges, .thickness = cloth.material.contact_thickness};
    const auto out = check_against_brute_force(in);
    std::printf("drape frame 20: %zu vertices, %zu triangles, %zu edges, cell %.4g m: %zu VF + %zu EE pairs\n",
                x0.size(), triangles.size(), edges.size(), out.counters.cell_size, out.vf.size(), out.ee.size());
}

TEST(BroadPhase, FlatGridPairsOnlyTheCornersOfNeighbouringCells) {
    // A 30×20 grid of 5 cm squares, falling 2 cm along its normal during the step, with a thickness
    // of 0.4 of the spacing (2·thickness < spacing, so bounds of primitives a full cell apart never
    // meet). Asserted:
    //  - vertex–face: exactly two pairs per cell, each triangle with the corner of its own square
    //    that it lacks (the triangle's box covers the whole square);
    //  - edge–edge: exactly the edge pairs whose boxes in grid-index space (i, j) touch or overlap
    //    and that share no vertex, i.e. nothing beyond the immediately neighbouring squares.
    const int cx = 30, cy = 20;
    Soup s = grid_soup(1.5, 1.0, cx, cy, 0.4 * 0.05);
    for (Vec3d& p : s.x1) p.y -= 0.02;
    const auto in = s.input();
    const auto out = check_against_brute_force(in);
    const auto ij = [&](std::uint32_t v) { return std::pair<int, int>(int(v % (cx + 1)), int(v / (cx + 1))); };

    std::vector<VertexFacePair> want_vf;
    for (std::uint32_t t = 0; t < s.triangles.size(); ++t) {
        const Triangle& tri = s.triangles[t];
        const std::uint32_t square = t / 2;  // make_grid emits two triangles per square, row by row
        const std::uint32_t a = square / cx * (cx + 1) + square % cx;
        const std::uint32_t corners[4] = {a, a + 1, a + cx + 1, a + cx + 2};
        for (std::uint32_t v : corners)
            if (v != tri.v[0] && v != tri.v[1] && v != tri.v[2]) want_vf.push_back({v, t});
    }
    std::sort(want_vf.begin(), want_vf.end());
    EXPECT_EQ(want_vf.size(), std::size_t{2 * cx * cy});
    expect_same(out.vf, want_vf, "grid vertex-face");

    std::vector<EdgeEdgePair> want_ee;
    for (std::uint32_t a = 0; a < s.edges.size(); ++a)
        for (std::uint32_t b = a + 1; b < s.edges.size(); ++b) {
            const Edge &p = s.edges[a], &q = s.edges[b];
            if (p.v[0] == q.v[0] || p.v[0] == q.v[1] || p.v[1] == q.v[0] || p.v[1] == q.v[1]) continue;
            const auto [pi0, pj0] = ij(p.v[0]);
            const auto [pi1, pj1] = ij(p.v[1]);
            const auto [qi0, qj0] = ij(q.v[0]);
            const auto [qi1, qj1] = ij(q.v[1]);
            const bool touch = std::max(pi0, pi1) >= std::min(qi0, qi1) && std::max(qi0, qi1) >= std::min(pi0, pi1) &&
                               std::max(pj0, pj1) >= std::min(qj0, qj1) && std::max(qj0, qj1) >= std::min(pj0, pj1);
            if (touch) want_ee.push_back({a, b});
        }
    expect_same(out.ee, want_ee, "grid edge-edge");
    std::printf("flat %dx%d grid: %zu VF pairs (2 per cell), %zu EE pairs (%.2f per edge)\n", cx, cy, out.vf.size(),
                out.ee.size(), double(out.ee.size()) / double(s.edges.size()));
}

/// A crumpled sheet: a 160×100 grid folded by a sine in height plus noise, moving randomly.
Soup crumpled_sheet(unsigned seed) {
    Soup s = grid_soup(1.6, 1.0, 160, 100, 0.004);
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, 0.003);
    for (std::size_t i = 0; i < s.x0.size(); ++i) {
        Vec3d& p = s.x0[i];
        p.y = 0.05 * std::sin(40.0 * p.x) * std::cos(25.0 * p.z) + g(rng);
        s.x1[i] = p + Vec3d{g(rng), g(rng) - 0.01, g(rng)};
    }
    return s;
}

TEST(BroadPhase, SameResultOnOneAndTwoThreads) {
    const Soup s = crumpled_sheet(11);
    const auto run = [&](int threads) {
        BroadPhaseResult out;
        tbb::task_arena arena(threads);
        arena.execute([&] {
            BroadPhase bp;
            bp.find(s.input(), out);
        });
        return out;
    };
    const auto one = run(1), two = run(2);
    EXPECT_GT(one.vf.size() + one.ee.size(), 10000U);
    EXPECT_TRUE(one.vf == two.vf);
    EXPECT_TRUE(one.ee == two.ee);
    const BroadPhaseCounters &a = one.counters, &b = two.counters;
    EXPECT_EQ(a.cell_size, b.cell_size);
    EXPECT_EQ(a.entries, b.entries);
    EXPECT_EQ(a.cells_occupied, b.cells_occupied);
    EXPECT_EQ(a.max_cell_entries, b.max_cell_entries);
    EXPECT_EQ(a.tested_pairs, b.tested_pairs);
    EXPECT_EQ(a.candidate_pairs, b.candidate_pairs);
    // A reused object (warm scratch, stale thread-local lists) gives the same again.
    BroadPhase bp;
    BroadPhaseResult again;
    bp.find(crumpled_sheet(12).input(), again);
    bp.find(s.input(), again);
    EXPECT_TRUE(again.vf == one.vf);
    EXPECT_TRUE(again.ee == one.ee);
}

// Mesh colliders are kinematic groups (BroadPhaseInput::first_kinematic_group): three overlapping
// grids, a cloth and two colliders, 1 mm apart. No pair lies within or between the colliders (nothing
// there can move); every pair that involves the cloth is the unfiltered run's.
TEST(BroadPhase, KinematicGroupsDoNotPairAmongThemselves) {
    Soup s;
    std::vector<std::uint32_t> group;
    for (std::uint32_t g = 0; g < 3; ++g) {
        Soup layer = grid_soup(0.5, 0.5, 12, 12, 0.002);
        const auto base = static_cast<std::uint32_t>(s.x0.size());
        for (Vec3d p : layer.x0) {
            p.y += 0.001 * g;
            s.x0.push_back(p);
            s.x1.push_back(p);
        }
        for (Triangle t : layer.triangles) {
            for (std::uint32_t& v : t.v) v += base;
            s.triangles.push_back(t);
            group.push_back(g);
        }
    }
    s.edges = build_edges(s.triangles);
    s.thickness = 0.002;
    const std::size_t per_layer = s.x0.size() / 3;
    const auto layer_of_vertex = [&](std::uint32_t v) { return static_cast<std::uint32_t>(v / per_layer); };

    BroadPhaseInput all = s.input();
    all.triangle_cloth = group;
    BroadPhaseInput filtered = all;
    filtered.first_kinematic_group = 1;
    BroadPhase hash;
    BroadPhaseResult every, kept;
    hash.find(all, every);
    hash.find(filtered, kept);

    std::vector<VertexFacePair> vf_want;
    for (const VertexFacePair& p : every.vf)
        if (layer_of_vertex(p.vertex) == 0 || group[p.triangle] == 0) vf_want.push_back(p);
    std::vector<EdgeEdgePair> ee_want;
    for (const EdgeEdgePair& p : every.ee)
        if (layer_of_vertex(s.edges[p.a].v[0]) == 0 || layer_of_vertex(s.edges[p.b].v[0]) == 0) ee_want.push_back(p);
    ASSERT_LT(vf_want.size() + ee_want.size(), every.vf.size() + every.ee.size()) << "no collider pairs: the test tests nothing";
    ASSERT_FALSE(vf_want.empty());
    expect_same(kept.vf, vf_want, "vertex-face");
    expect_same(kept.ee, ee_want, "edge-edge");
}

// Only the pairs with a flagged vertex (BroadPhaseInput::vertex_changed, the impact zones' later
// detection rounds): exactly the full result's pairs that have one, on random soups (oversized
// primitives included) with every tenth vertex flagged; none with no flag; all with every flag; a
// flag list of the wrong size is an error naming both sizes.
TEST(BroadPhase, OnlyPairsWithAChangedVertexWhenAskedFor) {
    for (const test::SoupCase& c : test::kSoupCases) {
        SCOPED_TRACE("seed " + std::to_string(c.seed));
        Soup s = random_soup(c.seed, c.lattice, c.triangles, c.motion, c.outliers);
        s.thickness = 0.05;
        BroadPhase hash;
        BroadPhaseResult every, some, none, all;
        hash.find(s.input(), every);
        std::vector<std::uint8_t> changed(s.x0.size(), 0);
        BroadPhaseInput flagged = s.input();
        flagged.vertex_changed = changed;
        const auto any = [&](std::initializer_list<std::uint32_t> vs) {
            return std::any_of(vs.begin(), vs.end(), [&](std::uint32_t v) { return changed[v] != 0; });
        };
        // Every tenth vertex (changes all over), then the vertices of one corner of the soup (a local
        // change: most primitives are left out of the hash).
        double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
        for (const Vec3d& p : s.x0)
            if (std::isfinite(p.x)) {
                lowest = std::min(lowest, p.x);
                highest = std::max(highest, p.x);
            }
        const double corner = lowest + 0.2 * (highest - lowest);
        for (const int pattern : {0, 1}) {
            SCOPED_TRACE(pattern == 0 ? "every tenth vertex" : "one corner");
            for (std::size_t v = 0; v < changed.size(); ++v)
                changed[v] = pattern == 0 ? (v % 10 == 0 ? 1 : 0) : (s.x0[v].x < corner ? 1 : 0);
            hash.find(flagged, some);
            std::vector<VertexFacePair> vf_want;
            for (const VertexFacePair& p : every.vf) {
                const Triangle& t = s.triangles[p.triangle];
                if (any({p.vertex, t.v[0], t.v[1], t.v[2]})) vf_want.push_back(p);
            }
            std::vector<EdgeEdgePair> ee_want;
            for (const EdgeEdgePair& p : every.ee)
                if (any({s.edges[p.a].v[0], s.edges[p.a].v[1], s.edges[p.b].v[0], s.edges[p.b].v[1]})) ee_want.push_back(p);
            ASSERT_FALSE(vf_want.empty());
            ASSERT_LT(vf_want.size() + ee_want.size(), every.vf.size() + every.ee.size()) << "the flags filter nothing";
            expect_same(some.vf, vf_want, "vertex-face");
            expect_same(some.ee, ee_want, "edge-edge");
            if (pattern == 1) {
                EXPECT_LT(some.counters.entries, every.counters.entries) << "a local change hashed every primitive";
            }
        }

        std::fill(changed.begin(), changed.end(), std::uint8_t{0});
        hash.find(flagged, none);
        EXPECT_TRUE(none.vf.empty() && none.ee.empty()) << "nothing moved, nothing to pair";
        std::fill(changed.begin(), changed.end(), std::uint8_t{1});
        hash.find(flagged, all);
        expect_same(all.vf, every.vf, "vertex-face, every vertex flagged");
        expect_same(all.ee, every.ee, "edge-edge, every vertex flagged");
    }
    Soup s = random_soup(7, 8, 100, 0.2, 0.0);
    const std::vector<std::uint8_t> short_flags(s.x0.size() - 1, 1);
    BroadPhaseInput bad = s.input();
    bad.vertex_changed = short_flags;
    BroadPhase hash;
    BroadPhaseResult out;
    try {
        hash.find(bad, out);
        ADD_FAILURE() << "a flag list of the wrong size was taken";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(std::to_string(s.x0.size() - 1) + " changed-vertex flags for " +
                                             std::to_string(s.x0.size()) + " vertices"),
                  std::string::npos)
            << e.what();
    }
}

// A common motion taken out of the bounds (BroadPhaseInput::frame_motion): a soup moving 30 cm as a
// whole pairs as if it stood still (the brute force on x1 − T, the same arithmetic), and the world
// frame's swept bounds give a strict superset of those pairs.
TEST(BroadPhase, ReusingAnEarlierCallsPairsGivesFindsPairs) {
    // The impact zones' first detection reuses the proximity detection's pairs: bounds grown by the
    // contact thickness around the predicted motion then, by eta around the solved motion now. The
    // lists must be find's exactly, with culling, a moved frame and some vertices far off the
    // prediction (hashed again); and where the reuse cannot hold it must say so and still give them.
    for (const unsigned seed : {3U, 11U}) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        const Soup s = crumpled_sheet(seed);
        const std::size_t n = s.x0.size();
        BroadPhase proximity;
        BroadPhaseResult predicted;
        proximity.find(s.input(), predicted);

        std::mt19937 rng(seed);
        std::normal_distribution<double> small(0.0, 0.2 * s.thickness);
        std::vector<Vec3d> solved = s.x1;
        for (std::size_t v = 0; v < n; ++v) solved[v] += Vec3d{small(rng), small(rng), small(rng)};
        for (std::size_t v = 0; v < n; v += 97) solved[v] += Vec3d{5.0 * s.thickness, 0.0, 5.0 * s.thickness};  // off the prediction
        // Patches by strips of the sheet, a primitive across two strips in none (kNoPatch).
        const auto strip = [&](std::uint32_t v) { return static_cast<std::uint32_t>((s.x0[v].x + 1.0) / 0.2); };
        std::vector<std::uint32_t> vertex_patch(n), edge_patch, triangle_patch;
        for (std::size_t v = 0; v < n; ++v) vertex_patch[v] = strip(static_cast<std::uint32_t>(v));
        for (const Edge& e : s.edges) edge_patch.push_back(strip(e.v[0]) == strip(e.v[1]) ? strip(e.v[0]) : kNoPatch);
        for (const Triangle& t : s.triangles)
            triangle_patch.push_back(strip(t.v[0]) == strip(t.v[1]) && strip(t.v[1]) == strip(t.v[2]) ? strip(t.v[0])
                                                                                                     : kNoPatch);
        BroadPhaseInput ccd = s.input();
        ccd.x1 = solved;
        ccd.thickness = 0.1 * s.thickness;
        ccd.frame_motion = {0.1 * s.thickness, -0.05 * s.thickness, 0.0};
        for (const bool culled : {false, true}) {
            SCOPED_TRACE(culled ? "culled" : "not culled");
            BroadPhaseInput in = ccd;
            if (culled) {
                in.vertex_patch = vertex_patch;
                in.edge_patch = edge_patch;
                in.triangle_patch = triangle_patch;
                in.count_culled = false;  // as the solver runs it (CollisionSettings::count_culled)
            }
            BroadPhase fresh, zones;
            BroadPhaseResult want, got;
            fresh.find(in, want);
            ASSERT_TRUE(zones.find_reusing(proximity, predicted, in, got));
            expect_same(got.vf, want.vf, "vertex-face");
            expect_same(got.ee, want.ee, "edge-edge");
            EXPECT_EQ(got.counters.vf_pairs, got.vf.size());
            EXPECT_EQ(got.counters.ee_pairs, got.ee.size());
            ASSERT_FALSE(want.vf.empty());
        }
        // Where it cannot reuse: most vertices off the prediction; counting culled pairs; an earlier
        // call that culled, or the reusing object's own. It hashes everything and gives find's lists.
        std::vector<Vec3d> far = s.x1;
        for (Vec3d& p : far) p += Vec3d{5.0 * s.thickness, 0.0, 0.0};
        BroadPhaseInput moved = ccd;
        moved.x1 = far;
        BroadPhaseInput counting = ccd;
        counting.vertex_patch = vertex_patch;
        counting.edge_patch = edge_patch;
        counting.triangle_patch = triangle_patch;
        counting.count_culled = true;
        for (const BroadPhaseInput* in : {&moved, &counting}) {
            BroadPhase fresh, zones;
            BroadPhaseResult want, got;
            fresh.find(*in, want);
            EXPECT_FALSE(zones.find_reusing(proximity, predicted, *in, got));
            expect_same(got.vf, want.vf, "vertex-face");
            expect_same(got.ee, want.ee, "edge-edge");
            EXPECT_EQ(got.counters.culled_pairs, want.counters.culled_pairs);
        }
        BroadPhase culled_earlier;
        BroadPhaseResult culled_pairs, want, got;
        BroadPhaseInput culled_in = s.input();
        culled_in.vertex_patch = vertex_patch;
        culled_in.edge_patch = edge_patch;
        culled_in.triangle_patch = triangle_patch;
        culled_earlier.find(culled_in, culled_pairs);
        BroadPhase zones;
        EXPECT_FALSE(zones.find_reusing(culled_earlier, culled_pairs, ccd, got)) << "culled pairs are no superset";
        BroadPhase fresh;
        fresh.find(ccd, want);
        expect_same(got.vf, want.vf, "vertex-face");
        EXPECT_FALSE(proximity.find_reusing(proximity, predicted, ccd, got)) << "its own last call";
        expect_same(got.vf, want.vf, "vertex-face");
    }
}

TEST(BroadPhase, AMovingFrameTakesACommonMotionOutOfTheBounds) {
    Soup s = random_soup(21, 10, 600, 0.01, 0.0);
    s.thickness = 0.01;
    const Vec3d motion{0.3, -0.2, 0.1};
    std::vector<Vec3d> moved = s.x1, in_frame(s.x1.size());
    for (std::size_t i = 0; i < moved.size(); ++i) {
        moved[i] = s.x1[i] + motion;
        in_frame[i] = moved[i] - motion;
    }
    BroadPhaseInput world = s.input();
    world.x1 = moved;
    BroadPhaseInput framed = world;
    framed.frame_motion = motion;
    BroadPhaseInput still = s.input();
    still.x1 = in_frame;

    BroadPhase hash;
    BroadPhaseResult in_world, with_frame;
    hash.find(world, in_world);
    hash.find(framed, with_frame);
    const Reference want = brute_force(still);
    expect_same(with_frame.vf, want.vf, "vertex-face in the moving frame");
    expect_same(with_frame.ee, want.ee, "edge-edge in the moving frame");
    EXPECT_TRUE(std::includes(in_world.vf.begin(), in_world.vf.end(), with_frame.vf.begin(), with_frame.vf.end()));
    EXPECT_TRUE(std::includes(in_world.ee.begin(), in_world.ee.end(), with_frame.ee.begin(), with_frame.ee.end()));
    std::printf("[ frame    ] %zu pairs in the world frame, %zu in the moving frame\n", in_world.vf.size() + in_world.ee.size(),
                with_frame.vf.size() + with_frame.ee.size());
    EXPECT_LT(3 * (with_frame.vf.size() + with_frame.ee.size()), 2 * (in_world.vf.size() + in_world.ee.size()))
        << "the common motion should have made a third of the world frame's pairs or more";

    framed.frame_motion = {std::numeric_limits<double>::infinity(), 0.0, 0.0};
    EXPECT_THROW(hash.find(framed, with_frame), Error);
}

// A frame that floods the hash with pairs (every vertex of a grid crushed into a few centimetres)
// grows its pair lists; calm frames after it find few pairs. The lists are cut back at the end of the
// first trim window (buffer_trim.h) that did not hold the flood, instead of keeping the flood's size
// for the rest of the run, and the calm frames' results do not change.
TEST(BroadPhase, AFloodOfPairsIsGivenBackAfterATrimWindow) {
    const Soup calm = grid_soup(1.0, 1.0, 40, 40, 0.001);
    Soup flood = calm;
    for (std::size_t i = 0; i < flood.x0.size(); ++i) {
        flood.x0[i] = 0.01 * flood.x0[i];
        flood.x1[i] = flood.x0[i];
    }
    BroadPhase hash;
    BroadPhaseResult out;
    hash.find(flood.input(), out);
    const std::size_t flooded_pairs = out.vf.size() + out.ee.size();
    const std::size_t flooded_bytes = hash.scratch_bytes() + out.vf.capacity() * sizeof(VertexFacePair) +
                                      out.ee.capacity() * sizeof(EdgeEdgePair);
    hash.find(calm.input(), out);
    const Reference expected = brute_force(calm.input());
    const std::size_t calm_pairs = out.vf.size() + out.ee.size();
    // The flood's window ends at call kTrimPeriod (its peak is the flood's: nothing cut), the next at
    // 2·kTrimPeriod.
    for (std::size_t call = 2; call <= 2 * kTrimPeriod; ++call) hash.find(calm.input(), out);
    EXPECT_EQ(out.vf, expected.vf);
    EXPECT_EQ(out.ee, expected.ee);
    const std::size_t trimmed_bytes = hash.scratch_bytes() + out.vf.capacity() * sizeof(VertexFacePair) +
                                      out.ee.capacity() * sizeof(EdgeEdgePair);
    std::printf("[ trim     ] flood %zu pairs, %.1f MB; calm %zu pairs; after %zu calls %.1f MB\n", flooded_pairs,
                static_cast<double>(flooded_bytes) / 1e6, calm_pairs, 2 * kTrimPeriod, static_cast<double>(trimmed_bytes) / 1e6);
    ASSERT_GT(flooded_pairs, 20 * calm_pairs) << "the flood did not flood: the test tests nothing";
    EXPECT_LT(trimmed_bytes, flooded_bytes / 4);
    // One more call, and the next window's first: nothing to cut, the same result.
    hash.find(calm.input(), out);
    EXPECT_EQ(out.vf, expected.vf);
}

TEST(BroadPhase, Timing200KTriangleGrid) {
    // 400×250 cells of 1 cm, gently waved and falling, 3 mm thickness. Prints; asserts no timing.
    Soup s = grid_soup(4.0, 2.5, 400, 250, 0.003);
    for (std::size_t i = 0; i < s.x0.size(); ++i) {
        Vec3d& p = s.x0[i];
        p.y = 0.02 * std::sin(6.0 * p.x) * std::cos(4.0 * p.z);
        s.x1[i] = p + Vec3d{0.001 * std::cos(3.0 * p.z), -0.004, 0.0};
    }
    ASSERT_EQ(s.triangles.size(), 200000U);
    BroadPhase bp;
    BroadPhaseResult out;
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    bp.find(s.input(), out);
    const auto t1 = Clock::now();
    bp.find(s.input(), out);
    const auto t2 = Clock::now();
    const auto ms = [](auto d) { return std::chrono::duration<double, std::milli>(d).count(); };
    const BroadPhaseCounters& c = out.counters;
    std::printf("200K grid: %zu vertices, %zu edges, %zu triangles; cell %.4g m\n", s.x0.size(), s.edges.size(),
                s.triangles.size(), c.cell_size);
    std::printf("  entries %zu, cells %zu (max %zu per cell), tested %zu, candidates %zu, VF %zu, EE %zu\n", c.entries,
                c.cells_occupied, c.max_cell_entries, c.tested_pairs, c.candidate_pairs, c.vf_pairs, c.ee_pairs);
    std::printf("  first call %.1f ms, warm call %.1f ms (%d threads)\n", ms(t1 - t0), ms(t2 - t1),
                tbb::this_task_arena::max_concurrency());
    EXPECT_GT(c.vf_pairs, 0U);
}

}  // namespace
}  // namespace weft::collision
