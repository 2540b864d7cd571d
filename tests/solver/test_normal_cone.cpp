// Normal-cone self-collision culling (PSCC): the continuous cone bound against sampled normals, the
// contour test on constructed motions, the patch hierarchy's invariants, the broad phase's culling
// against a filtered unculled run, and the contract: on folds, rolls, twists, crumples, mid-step
// collapses and several cloths, every pair that brute-force CCD finds colliding is still produced.
// Then effectiveness (a flat or gently curved sheet is one patch; the share culled on the twist
// benchmark), the front's incremental update against a rebuild, thread-count independence, and the
// cost of refit + front on a 200×200 sheet.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <numbers>
#include <random>
#include <string>

#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/physics/ccd.h"

#include "collision/broad_phase.h"
#include "collision/contour_test.h"
#include "collision/normal_cone.h"
#include "collision/normal_cone_front.h"
#include "weft/backend/patch_hierarchy.h"
#include "normal_cone_scenes.h"
#include "random_geometry.h"
#include "sheet_deformations.h"

namespace weft::collision {
namespace {

constexpr double kPi = std::numbers::pi;
using Scene = test::GridScene;
using test::grid_scene;

using Field = test::SmoothField;

using test::fold;
using test::roll;
using test::twist;

// ---- Brute force (normal_cone_scenes.h) -----------------------------------------------------------

using Colliding = test::CollidingPairs;
using test::brute_force_ccd;

BroadPhaseInput culled_input(const Scene& s, const NormalConeFront& front, double thickness) {
    BroadPhaseInput in{.x0 = s.x0,
                       .x1 = s.x1,
                       .triangles = s.triangles,
                       .edges = s.edges,
                       .triangle_cloth = s.triangle_cloth,
                       .thickness = thickness};
    in.vertex_patch = front.vertex_patch();
    in.edge_patch = front.edge_patch();
    in.triangle_patch = front.triangle_patch();
    return in;
}

/// What one scene showed: colliding pairs (CCD at eta = 0), those kept by the culled broad phase,
/// the pairs culled and the patches.
struct Outcome {
    std::size_t colliding = 0, missed = 0, culled = 0, candidates = 0, patches = 0, largest_patch = 0;
    std::size_t colliding_thick = 0, missed_thick = 0;
    double max_rest_gap = 0.0;  ///< of the pairs within the thickness inside one patch: rest distance, m
};

/// Runs the front over the scene (one update from the rest pose, then the step), the culled broad
/// phase, and brute-force CCD at eta = 0 and eta = `thickness`; counts colliding pairs the culled
/// broad phase lost, and also checks the patches of each colliding pair directly.
Outcome check_scene(const Scene& s, double thickness, const char* name) {
    const PatchHierarchy h = build_patch_hierarchy(s.rest, s.triangles, s.edges, s.triangle_cloth);
    NormalConeFront front(h);
    front.update(s.rest, s.x0);  // the previous step: exercises the incremental path below
    front.update(s.x0, s.x1);
    Outcome o;
    o.patches = front.front().size();
    for (std::uint32_t f : front.front()) o.largest_patch = std::max<std::size_t>(o.largest_patch, h.node_count[f]);
    BroadPhase bp;
    BroadPhaseResult out;
    const auto tp = front.triangle_patch(), vp = front.vertex_patch(), ep = front.edge_patch();
    for (const double eta : {0.0, thickness}) {
        bp.find(culled_input(s, front, eta), out);
        if (eta == 0.0) {
            o.culled = out.counters.culled_pairs;
            o.candidates = out.counters.candidate_pairs;
        }
        const Colliding c = brute_force_ccd(s, eta);
        std::size_t missed = 0;
        // How far apart in the rest mesh a pair in one patch was (its closest vertices): small means
        // neighbours pressed together along the surface.
        const auto rest_gap = [&](std::initializer_list<std::uint32_t> a, std::initializer_list<std::uint32_t> b) {
            double d = 1e300;
            for (std::uint32_t i : a)
                for (std::uint32_t j : b) d = std::min(d, physics::length(s.rest[i] - s.rest[j]));
            if (eta > 0.0) o.max_rest_gap = std::max(o.max_rest_gap, d);
        };
        for (const VertexFacePair& p : c.vf) {
            const bool same = vp[p.vertex] != kNoPatch && vp[p.vertex] == tp[p.triangle];
            const bool kept = std::binary_search(out.vf.begin(), out.vf.end(), p);
            if (same || !kept) {
                ++missed;
                const Triangle& t = s.triangles[p.triangle];
                rest_gap({p.vertex}, {t.v[0], t.v[1], t.v[2]});
                if (eta == 0.0)
                    ADD_FAILURE() << name << ": colliding vertex " << p.vertex << " / triangle " << p.triangle
                                  << " culled (patch " << tp[p.triangle] << ")";
            }
        }
        for (const EdgeEdgePair& p : c.ee) {
            const bool same = ep[p.a] != kNoPatch && ep[p.a] == ep[p.b];
            const bool kept = std::binary_search(out.ee.begin(), out.ee.end(), p);
            if (same || !kept) {
                ++missed;
                rest_gap({s.edges[p.a].v[0], s.edges[p.a].v[1]}, {s.edges[p.b].v[0], s.edges[p.b].v[1]});
                if (eta == 0.0)
                    ADD_FAILURE() << name << ": colliding edges " << p.a << " / " << p.b << " culled (patch " << ep[p.a]
                                  << ")";
            }
        }
        (eta == 0.0 ? o.colliding : o.colliding_thick) = c.vf.size() + c.ee.size();
        (eta == 0.0 ? o.missed : o.missed_thick) = missed;
    }
    return o;
}

// ---- The cone bound ----------------------------------------------------------------------------------

TEST(NormalCone, TriangleConeContainsTheNormalAtSampledTimes) {
    std::mt19937 rng(1);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    int bounded = 0, unbounded = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        // Motions from tiny to flipping: the displacement scale ranges over 1e-4 .. 3 triangle sizes.
        const double scale = std::pow(10.0, -4.0 + 4.5 * unit(rng));
        Vec3d p0[3], p1[3];
        for (int k = 0; k < 3; ++k) {
            p0[k] = {g(rng), g(rng), g(rng)};
            p1[k] = p0[k] + scale * Vec3d{g(rng), g(rng), g(rng)};
        }
        const NormalCone c = triangle_normal_cone(p0[0], p0[1], p0[2], p1[0], p1[1], p1[2]);
        if (!(c.half_angle < kPi / 2)) {
            ++unbounded;
            continue;
        }
        ++bounded;
        EXPECT_NEAR(physics::length(c.axis), 1.0, 1e-12);
        for (int i = 0; i <= 200; ++i) {
            const double t = i / 200.0;
            Vec3d q[3];
            for (int k = 0; k < 3; ++k) q[k] = p0[k] + t * (p1[k] - p0[k]);
            const Vec3d n = physics::cross(q[1] - q[0], q[2] - q[0]);
            if (physics::length(n) < 1e-9) continue;  // sampled rounding would dominate
            ASSERT_LE(angle_between(c.axis, n), c.half_angle + 1e-9) << "trial " << trial << " t " << t;
        }
    }
    std::printf("triangle cones: %d bounded, %d unbounded (degenerate or flipping over the step)\n", bounded,
                unbounded);
    EXPECT_GT(bounded, 2000);
    EXPECT_GT(unbounded, 100);
}

TEST(NormalCone, DegeneratingAndFlippingTrianglesAreNeverNarrow) {
    const Vec3d a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    // Turned by π in its plane: the linear motion collapses it to a point at t = ½, though its
    // normal is +z at both ends; the middle control vector N1 = −N0 gives it away.
    const NormalCone turned = triangle_normal_cone(a, b, c, -a, -b, -c);
    EXPECT_FALSE(turned.half_angle < kPi / 2);
    // Flipped (c moves through the opposite edge).
    const NormalCone flipped = triangle_normal_cone(a, b, c, a, b, Vec3d{0, -1, 0});
    EXPECT_FALSE(cone_is_narrow(flipped));
    // Non-finite.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_FALSE(cone_is_narrow(triangle_normal_cone(a, b, c, a, b, Vec3d{nan, 0, 0})));
    // A still triangle: a cone of (almost) zero width around +z.
    const NormalCone still = triangle_normal_cone(a, b, c, a, b, c);
    EXPECT_LT(still.half_angle, 1e-12);
    EXPECT_NEAR(still.axis.z, 1.0, 1e-15);
    // Merges: containment, the tangent cone, and refusal beyond a hemisphere.
    const NormalCone x{{1, 0, 0}, 0.1}, y{{0, 1, 0}, 0.2};
    const NormalCone xy = merge_cones(x, y);
    EXPECT_NEAR(xy.half_angle, (kPi / 2 + 0.3) / 2, 1e-12);
    EXPECT_LE(angle_between(xy.axis, x.axis) + x.half_angle, xy.half_angle + 1e-15);
    EXPECT_LE(angle_between(xy.axis, y.axis) + y.half_angle, xy.half_angle + 1e-15);
    EXPECT_FALSE(cone_is_narrow(merge_cones(NormalCone{{1, 0, 0}, 0.8}, NormalCone{{-1, 0, 0}, 0.1})));
    EXPECT_FALSE(cone_is_narrow(merge_cones(x, NormalCone{})));
}

TEST(NormalCone, NodeConesContainEveryNormalOfTheirTriangles) {
    Scene s = grid_scene(24, 16);
    std::mt19937 rng(2);
    const Field f0(rng, 0.02, 0.08, 0.3), f1(rng, 0.02, 0.08, 0.3);
    for (std::size_t v = 0; v < s.rest.size(); ++v) {
        s.x0[v] = s.rest[v] + f0.at(s.rest[v]);
        s.x1[v] = twist(s.rest[v], 0.24, 1.0) + f1.at(s.rest[v]);
    }
    const PatchHierarchy h = build_patch_hierarchy(s.rest, s.triangles, s.edges);
    NormalConeFront front(h);
    front.update(s.x0, s.x1);
    std::size_t narrow = 0;
    for (std::uint32_t n = 0; n < h.node_size(); ++n) {
        const NormalCone& c = front.cone(n);
        if (h.is_leaf(n) || !cone_is_narrow(c)) continue;
        ++narrow;
        for (std::uint32_t k = h.node_first[n]; k < h.node_first[n] + h.node_count[n]; ++k) {
            const Triangle& t = s.triangles[h.triangle_order[k]];
            for (int i = 0; i <= 20; ++i) {
                const double u = i / 20.0;
                const auto at = [&](std::uint32_t v) { return s.x0[v] + u * (s.x1[v] - s.x0[v]); };
                const Vec3d nrm = physics::cross(at(t.v[1]) - at(t.v[0]), at(t.v[2]) - at(t.v[0]));
                ASSERT_LE(angle_between(c.axis, nrm), c.half_angle + 1e-9) << "node " << n;
                ASSERT_GT(physics::dot(c.axis, nrm), 0.0);
            }
        }
    }
    EXPECT_GT(narrow, h.node_size() / 4);
}

// ---- The contour test ------------------------------------------------------------------------------

TEST(NormalCone, ContourTestFollowsTheMotion) {
    // A square contour 0-1-2-3 in the plane z = 0 (projected along +z).
    const std::vector<ContourEdge> square = {{0, 1}, {1, 2}, {2, 3}, {3, 0}};
    const std::vector<Vec3d> x0 = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    ContourTestScratch scratch;
    ContourTestCounters counters;
    const Vec3d z{0, 0, 1};
    // Shrinking and moving, lifted out of the plane: stays simple.
    std::vector<Vec3d> x1;
    for (const Vec3d& p : x0) x1.push_back(0.5 * p + Vec3d{3.0, 0.2, 5.0 * p.x});
    EXPECT_TRUE(contour_stays_simple(square, z, x0, x1, scratch, counters));
    // Vertex 2 swept through edge 0-1 and beyond: edges 1-2 and 3-0... the polygon turns into a
    // bow tie during the step though both ends look different; here the end is non-simple too.
    x1 = x0;
    x1[2] = {0.5, -1.0, 0.0};
    x1[3] = {0.5, 2.0, 0.0};
    EXPECT_FALSE(contour_stays_simple(square, z, x0, x1, scratch, counters));
    // Non-simple only mid-step: edge 2-3 passes through edge 0-1 and comes back out of the other
    // side... by a motion whose ends are both simple squares: the top edge moves down through the
    // bottom one and the bottom edge up, swapping (the square is mirrored, orientation reversed).
    x1 = {{0, 1, 0}, {1, 1, 0}, {1, 0, 0}, {0, 0, 0}};
    EXPECT_FALSE(contour_stays_simple(square, z, x0, x1, scratch, counters));
    // Projection matters: along +x the square collapses onto a segment.
    EXPECT_FALSE(contour_stays_simple(square, Vec3d{1, 0, 0}, x0, x0, scratch, counters));
    // A thin gap: a long U whose arms stay 1e-6 apart is simple; touching arms are not.
    const std::vector<ContourEdge> u = {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 5}, {5, 0}};
    std::vector<Vec3d> ux = {{0, 0, 0}, {1, 0, 0}, {1, 1e-6, 0}, {0.01, 1e-6, 0}, {0.01, 2e-6, 0}, {0, 2e-6, 0}};
    EXPECT_TRUE(contour_stays_simple(u, z, ux, ux, scratch, counters));
    std::vector<Vec3d> ux1 = ux;
    ux1[2].y = ux1[3].y = 0.0;  // the middle arm pressed onto the bottom one at t = 1
    EXPECT_FALSE(contour_stays_simple(u, z, ux, ux1, scratch, counters));
    const double nan = std::numeric_limits<double>::quiet_NaN();
    ux1 = ux;
    ux1[4].x = nan;
    EXPECT_FALSE(contour_stays_simple(u, z, ux, ux1, scratch, counters));
    // A 400-gon (radius 1, edges 1.6 % of it) turning by 0.3 rad and flying 10 radii during the
    // step: every pair's swept boxes overlap, and the edge differences, which the motion barely
    // changes, settle nearly all of them at once.
    std::vector<ContourEdge> ring;
    std::vector<Vec3d> r0, r1;
    for (std::uint32_t i = 0; i < 400; ++i) {
        const double a = 2.0 * kPi * i / 400.0;
        ring.push_back({i, (i + 1) % 400});
        r0.push_back({std::cos(a), std::sin(a), 0.0});
        r1.push_back(Vec3d{std::cos(a + 0.3), std::sin(a + 0.3), 0.1 * std::sin(3.0 * a)} + Vec3d{10.0, 3.0, 0.0});
    }
    counters = {};
    EXPECT_TRUE(contour_stays_simple(ring, z, r0, r1, scratch, counters));
    std::printf("turning, flying 400-gon: %zu box pairs, %zu exclusion tests\n", counters.box_pairs,
                counters.hull_tests);
    EXPECT_GT(counters.box_pairs, 50000U);
    EXPECT_LT(counters.hull_tests, 2 * counters.box_pairs);
}

// ---- The hierarchy ---------------------------------------------------------------------------------

TEST(NormalCone, HierarchyNodesAreConnectedDisksWithinOneCloth) {
    Scene s;
    (void)s.add_grid(20, 13);
    (void)s.add_grid(7, 9);
    (void)s.add_grid(1, 1);
    const PatchHierarchy h = build_patch_hierarchy(s.rest, s.triangles, s.edges, s.triangle_cloth);
    ASSERT_EQ(h.levels() > 0 ? h.level_first[1] : 0U, 3U);  // one root per cloth
    // Every triangle in exactly one leaf; children partition their parent; one cloth per node.
    std::vector<int> seen(s.triangles.size(), 0);
    std::size_t disks = 0, internal = 0;
    for (std::uint32_t n = 0; n < h.node_size(); ++n) {
        const std::uint32_t b = h.node_first[n], c = h.node_count[n];
        ASSERT_GE(c, 1U);
        for (std::uint32_t k = b; k < b + c; ++k)
            ASSERT_EQ(s.triangle_cloth[h.triangle_order[k]], s.triangle_cloth[h.triangle_order[b]]);
        if (h.is_leaf(n)) {
            ASSERT_EQ(c, 1U);
            ++seen[h.triangle_order[b]];
            ASSERT_EQ(h.triangle_leaf[h.triangle_order[b]], n);
            continue;
        }
        ++internal;
        const std::uint32_t l = h.node_child[n];
        ASSERT_GT(l, n);
        ASSERT_EQ(h.node_parent[l], n);
        ASSERT_EQ(h.node_parent[l + 1], n);
        ASSERT_EQ(h.node_first[l], b);
        ASSERT_EQ(h.node_first[l + 1], b + h.node_count[l]);
        ASSERT_EQ(h.node_count[l] + h.node_count[l + 1], c);
        // Connected through shared edges.
        std::vector<std::uint32_t> tris(h.triangle_order.begin() + b, h.triangle_order.begin() + b + c);
        std::vector<std::uint32_t> reached = {tris[0]};
        std::vector<bool> in(s.triangles.size(), false), done(s.triangles.size(), false);
        for (std::uint32_t t : tris) in[t] = true;
        done[tris[0]] = true;
        for (std::size_t q = 0; q < reached.size(); ++q)
            for (std::uint32_t t : tris) {
                if (done[t]) continue;
                int shared = 0;
                for (std::uint32_t x : s.triangles[reached[q]].v)
                    for (std::uint32_t y : s.triangles[t].v) shared += x == y ? 1 : 0;
                if (shared == 2) {
                    done[t] = true;
                    reached.push_back(t);
                }
            }
        ASSERT_EQ(reached.size(), tris.size()) << "node " << n << " is not connected";
        if ((h.node_flags[n] & PatchHierarchy::kDisk) != 0) {
            ++disks;
            // The stored contour is the node's boundary: its edges used by exactly one of its triangles.
            std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary;
            for (std::uint32_t t : tris)
                for (int k = 0; k < 3; ++k) {
                    const std::uint32_t a = s.triangles[t].v[k], bb = s.triangles[t].v[(k + 1) % 3];
                    int uses = 0;
                    for (std::uint32_t t2 : tris)
                        for (int k2 = 0; k2 < 3; ++k2) {
                            const std::uint32_t a2 = s.triangles[t2].v[k2], b2 = s.triangles[t2].v[(k2 + 1) % 3];
                            uses += (a2 == a && b2 == bb) || (a2 == bb && b2 == a) ? 1 : 0;
                        }
                    if (uses == 1) boundary.push_back({a, bb});
                }
            std::vector<std::pair<std::uint32_t, std::uint32_t>> stored;
            for (const ContourEdge& e : h.contour(n)) stored.push_back({e.a, e.b});
            std::sort(boundary.begin(), boundary.end());
            std::sort(stored.begin(), stored.end());
            ASSERT_EQ(stored, boundary) << "node " << n;
        } else {
            ASSERT_TRUE(h.contour(n).empty());
        }
    }
    for (int c : seen) ASSERT_EQ(c, 1);
    // Straight median cuts of a grid give disks almost everywhere.
    std::printf("hierarchy: %zu nodes, %zu internal, %zu disks\n", h.node_size(), internal, disks);
    EXPECT_GE(disks, internal * 9 / 10);
    // Vertices and edges map to an incident triangle.
    for (std::uint32_t v = 0; v < s.rest.size(); ++v) {
        const Triangle& t = s.triangles[h.vertex_triangle[v]];
        ASSERT_TRUE(t.v[0] == v || t.v[1] == v || t.v[2] == v);
    }
    for (std::uint32_t e = 0; e < s.edges.size(); ++e) {
        const Triangle& t = s.triangles[h.edge_triangle[e]];
        int hits = 0;
        for (std::uint32_t v : t.v) hits += v == s.edges[e].v[0] || v == s.edges[e].v[1] ? 1 : 0;
        ASSERT_EQ(hits, 2);
    }
}

TEST(NormalCone, NonManifoldAndMisorientedPatchesAreNeverDisks) {
    // A strip of 4 triangles; flipping one makes the orientation inconsistent, and a fan of three
    // triangles on one edge makes the edge non-manifold: no node holding them may be tested.
    Scene s = grid_scene(2, 1);
    Scene flipped = s;
    std::swap(flipped.triangles[1].v[0], flipped.triangles[1].v[1]);
    const PatchHierarchy hf = build_patch_hierarchy(flipped.rest, flipped.triangles, flipped.edges);
    for (std::uint32_t n = 0; n < hf.node_size(); ++n) {
        bool holds = false;
        for (std::uint32_t k = hf.node_first[n]; k < hf.node_first[n] + hf.node_count[n]; ++k)
            holds = holds || hf.triangle_order[k] == 1;
        if (holds && !hf.is_leaf(n)) {
            EXPECT_EQ(hf.node_flags[n] & PatchHierarchy::kDisk, 0) << n;
        }
    }
    Scene fan = s;
    fan.rest.push_back({0.0, 0.0, 0.01});
    const Triangle t0 = fan.triangles[0];
    fan.triangles.push_back({{t0.v[0], t0.v[1], static_cast<std::uint32_t>(fan.rest.size() - 1)}});
    fan.edges = build_edges(fan.triangles);
    const PatchHierarchy hn = build_patch_hierarchy(fan.rest, fan.triangles, fan.edges);
    EXPECT_EQ(hn.node_flags[0] & PatchHierarchy::kDisk, 0);
    EXPECT_THROW((void)build_patch_hierarchy(s.rest, std::vector<Triangle>{{{0, 1, 1}}}), Error);
    EXPECT_THROW((void)build_patch_hierarchy(s.rest, std::vector<Triangle>{{{0, 1, 99}}}), Error);
}

// ---- The broad phase with patch ids ----------------------------------------------------------------

TEST(NormalCone, BroadPhaseCullingRemovesExactlyTheSamePatchPairs) {
    // A crumpled sheet with outliers (oversized bounds), random patch ids: the culled run must equal
    // the unculled run minus its same-patch pairs, and count them.
    Scene s = grid_scene(40, 30);
    std::mt19937 rng(3);
    const Field f(rng, 0.02, 0.05, 0.2);
    std::uniform_real_distribution<double> unit(0.0, 1.0), jump(-0.3, 0.3);
    for (std::size_t v = 0; v < s.rest.size(); ++v) {
        s.x0[v] = s.rest[v] + f.at(s.rest[v]);
        s.x1[v] = s.x0[v] + Vec3d{0.003 * (unit(rng) - 0.5), 0.003 * (unit(rng) - 0.5), -0.002};
        if (unit(rng) < 0.003) s.x1[v] += Vec3d{jump(rng), jump(rng), jump(rng)};
    }
    std::vector<std::uint32_t> tp(s.triangles.size()), vp(s.rest.size()), ep(s.edges.size());
    for (auto* ids : {&tp, &vp, &ep})
        for (std::uint32_t& id : *ids) id = unit(rng) < 0.1 ? kNoPatch : static_cast<std::uint32_t>(unit(rng) * 3);
    BroadPhaseInput in{.x0 = s.x0, .x1 = s.x1, .triangles = s.triangles, .edges = s.edges, .thickness = 0.004};
    BroadPhase bp;
    BroadPhaseResult plain, culled, quiet, none;
    bp.find(in, plain);
    BroadPhaseInput ci = in;
    ci.vertex_patch = vp;
    ci.edge_patch = ep;
    ci.triangle_patch = tp;
    bp.find(ci, culled);
    ci.count_culled = false;
    bp.find(ci, quiet);
    const std::vector<std::uint32_t> all_none_v(vp.size(), kNoPatch), all_none_e(ep.size(), kNoPatch),
        all_none_t(tp.size(), kNoPatch);
    BroadPhaseInput ni = in;
    ni.vertex_patch = all_none_v;
    ni.edge_patch = all_none_e;
    ni.triangle_patch = all_none_t;
    bp.find(ni, none);

    std::vector<VertexFacePair> want_vf;
    std::vector<EdgeEdgePair> want_ee;
    for (const VertexFacePair& p : plain.vf)
        if (vp[p.vertex] == kNoPatch || vp[p.vertex] != tp[p.triangle]) want_vf.push_back(p);
    for (const EdgeEdgePair& p : plain.ee)
        if (ep[p.a] == kNoPatch || ep[p.a] != ep[p.b]) want_ee.push_back(p);
    EXPECT_GT(plain.counters.oversized, 0U);
    EXPECT_LT(want_vf.size(), plain.vf.size());
    EXPECT_TRUE(culled.vf == want_vf);
    EXPECT_TRUE(culled.ee == want_ee);
    EXPECT_TRUE(quiet.vf == want_vf);
    EXPECT_TRUE(quiet.ee == want_ee);
    EXPECT_EQ(culled.counters.candidate_pairs + culled.counters.culled_pairs, plain.counters.candidate_pairs);
    EXPECT_EQ(quiet.counters.culled_pairs, 0U);
    EXPECT_EQ(quiet.counters.candidate_pairs, culled.counters.candidate_pairs);
    EXPECT_EQ(plain.counters.culled_pairs, 0U);
    // All kNoPatch: nothing culled, the same pairs and counts as without ids.
    EXPECT_TRUE(none.vf == plain.vf);
    EXPECT_TRUE(none.ee == plain.ee);
    EXPECT_EQ(none.counters.candidate_pairs, plain.counters.candidate_pairs);
    EXPECT_EQ(none.counters.culled_pairs, 0U);
    // Mismatched sizes are refused.
    ci.edge_patch = {};
    EXPECT_THROW(bp.find(ci, culled), Error);
}

// ---- The contract: no colliding pair is culled ----------------------------------------------------

TEST(NormalCone, CulledBroadPhaseKeepsEveryPairThatCcdFindsColliding) {
    const double thickness = 0.002;
    std::size_t colliding = 0, culled = 0, candidates = 0, missed_thick = 0, colliding_thick = 0;
    double max_rest_gap = 0.0;
    int scenes = 0;
    const auto run = [&](const Scene& s, const std::string& name) {
        SCOPED_TRACE(name);
        const Outcome o = check_scene(s, thickness, name.c_str());
        ++scenes;
        colliding += o.colliding;
        culled += o.culled;
        candidates += o.candidates;
        colliding_thick += o.colliding_thick;
        missed_thick += o.missed_thick;
        max_rest_gap = std::max(max_rest_gap, o.max_rest_gap);
        EXPECT_EQ(o.missed, 0U);
        std::printf(
            "  %-22s %4zu patches (largest %4zu tri): %5zu colliding (eta 0), %6zu kept, %6zu culled; "
            "eta %.0f mm: %5zu colliding, %zu in one patch\n",
            name.c_str(), o.patches, o.largest_patch, o.colliding, o.candidates, o.culled, thickness * 1e3,
            o.colliding_thick, o.missed_thick);
    };
    // Folds, spirals, twists, crumples and mid-step folds (normal_cone_scenes.h), then several cloths
    // from the same random sequence.
    test::MotionRandom random(4);
    test::adversarial_motions<Scene>(random, {.folds = 6, .spirals = 4, .twists = 3, .crumples = 6},
                                     [&](Scene&& s, const std::string& name) { run(s, name); });
    std::mt19937& rng = random.rng;
    std::uniform_real_distribution<double>& unit = random.unit;
    std::normal_distribution<double>& g = random.g;
    // Several cloths: three stacked sheets passing through one another, two of them folding.
    for (int i = 0; i < 3; ++i) {
        Scene s;
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t base = s.add_grid(10 + 2 * k, 9);
            (void)base;
        }
        const double alpha = 2.0 * kPi * unit(rng);
        std::size_t v = 0;
        for (int k = 0; k < 3; ++k) {
            const std::size_t count = static_cast<std::size_t>((11 + 2 * k) * 10);
            const Vec3d shift0{0.01 * g(rng), 0.01 * g(rng), 0.003 * k},
                shift1{0.01 * g(rng), 0.01 * g(rng), 0.003 * (2 - k) - 0.002};
            for (std::size_t j = 0; j < count; ++j, ++v) {
                const Vec3d p = s.rest[v];
                s.x0[v] = (k == 1 ? fold(p, alpha, 0.0, 0.9 * kPi) : p) + shift0;
                s.x1[v] =
                    (k == 1 ? fold(p, alpha, 0.0, 1.05 * kPi) : (k == 2 ? fold(p, -alpha, 0.01, 0.3) : p)) + shift1;
            }
        }
        run(s, "three cloths " + std::to_string(i));
    }
    std::printf(
        "%d scenes: %zu colliding pairs (eta 0), none culled; culling removed %zu of %zu candidates "
        "(%.0f %%); at eta %.0f mm %zu of %zu colliding pairs lie in one patch (proximity skipped by "
        "design), their closest vertices at most %.1f cm apart at rest\n",
        scenes, colliding, culled, culled + candidates, 100.0 * double(culled) / double(culled + candidates),
        thickness * 1e3, missed_thick, colliding_thick, max_rest_gap * 100.0);
    EXPECT_GT(colliding, 10000U);
    EXPECT_GT(culled, 50000U);  // the culling is active in these scenes: the check is not vacuous
}

// ---- Effectiveness ------------------------------------------------------------------------------------

TEST(NormalCone, FlatAndGentlyCurvedSheetsAreOnePatch) {
    Scene s = grid_scene(60, 40);
    for (std::size_t v = 0; v < s.rest.size(); ++v) {
        const Vec3d p = s.rest[v];
        s.x0[v] = p;
        // Translated, turned by 0.1 rad about z and lifted: a rigid motion.
        s.x1[v] = Vec3d{std::cos(0.1) * p.x - std::sin(0.1) * p.y, std::sin(0.1) * p.x + std::cos(0.1) * p.y, 0.0} +
                  Vec3d{0.003, -0.002, 0.004};
    }
    const PatchHierarchy h = build_patch_hierarchy(s.rest, s.triangles, s.edges);
    NormalConeFront front(h);
    front.update(s.x0, s.x1);
    ASSERT_EQ(front.front().size(), 1U);
    EXPECT_EQ(front.front()[0], 0U);
    BroadPhase bp;
    BroadPhaseResult out;
    bp.find(culled_input(s, front, 0.005), out);
    EXPECT_TRUE(out.vf.empty());
    EXPECT_TRUE(out.ee.empty());
    EXPECT_EQ(out.counters.candidate_pairs, 0U);
    EXPECT_GT(out.counters.culled_pairs, 10000U);
    // Bent into a cylinder section (a quarter turn) and bending further (to a third of a turn).
    for (std::size_t v = 0; v < s.rest.size(); ++v) {
        const Vec3d p = s.rest[v];
        const auto bend = [&](double arc) {
            const double r = 0.6 / arc, a = p.x / r;
            return Vec3d{r * std::sin(a), p.y, r * (1.0 - std::cos(a))};
        };
        s.x0[v] = bend(kPi / 2);
        s.x1[v] = bend(2 * kPi / 3);
    }
    front.update(s.x0, s.x1);
    EXPECT_EQ(front.front().size(), 1U);
    bp.find(culled_input(s, front, 0.005), out);
    EXPECT_TRUE(out.vf.empty() && out.ee.empty());
}

/// The twist benchmark at time t (s) on an N×N sheet; step dt.
struct TwistRun {
    Scene s;
    PatchHierarchy h;
    explicit TwistRun(int n) : s(grid_scene(n, n)), h(build_patch_hierarchy(s.rest, s.triangles, s.edges)) {}
    void pose(double t, double dt) {
        const double L = s.rest.empty() ? 0.0 : 2.0 * std::abs(s.rest[0].x);
        for (std::size_t v = 0; v < s.rest.size(); ++v) {
            s.x0[v] = twist(s.rest[v], L, t);
            s.x1[v] = twist(s.rest[v], L, t + dt);
        }
    }
};

TEST(NormalCone, TwistingSheetCullsMostPairs) {
    // 100×100 cells of 1 cm (20K triangles), the two opposite edges turning at π/3 rad/s in opposite
    // directions, steps of 1/100 s; the share of broad-phase candidates culled at 5 mm (Weft's
    // default contact thickness) and 2 mm.
    TwistRun run(100);
    NormalConeFront front(run.h);
    BroadPhase bp;
    BroadPhaseResult out;
    const double dt = 0.01;
    double worst = 1.0;
    for (double t = 0.0; t < 6.0 + 1e-9; t += dt) {
        run.pose(t, dt);
        front.update(run.s.x0, run.s.x1);
        const int centi = static_cast<int>(std::lround(t * 100.0));
        if (centi % 100 != 0 || centi == 0) continue;
        double share[2];
        std::size_t kept[2], total[2];
        for (int k = 0; k < 2; ++k) {
            bp.find(culled_input(run.s, front, k == 0 ? 0.005 : 0.002), out);
            kept[k] = out.counters.candidate_pairs;
            total[k] = kept[k] + out.counters.culled_pairs;
            share[k] = double(out.counters.culled_pairs) / double(total[k]);
        }
        worst = std::min(worst, share[0]);
        std::printf(
            "twist t = %.1f s (relative twist %.2f pi): %4zu patches (%zu single triangles); culled %.1f %% "
            "of %zu candidates at 5 mm (%zu kept), %.1f %% of %zu at 2 mm\n",
            t, 2.0 * t / 3.0, front.front().size(), front.counters().single_triangle_patches, 100.0 * share[0],
            total[0], kept[0], 100.0 * share[1], total[1]);
    }
    EXPECT_GE(worst, 0.8);
}

// ---- Front maintenance -----------------------------------------------------------------------------

/// The front must be the top-most passing nodes: a cut of the hierarchy (every triangle under
/// exactly one front node), every front node passing, no ancestor of one passing.
void expect_top_most_passing(NormalConeFront& front) {
    const PatchHierarchy& h = front.hierarchy();
    std::vector<int> cover(h.triangle_count, 0);
    for (std::uint32_t f : front.front()) {
        ASSERT_TRUE(front.node_passes(f)) << f;
        for (std::uint32_t a = h.node_parent[f]; a != kNone; a = h.node_parent[a]) ASSERT_FALSE(front.node_passes(a));
        for (std::uint32_t k = h.node_first[f]; k < h.node_first[f] + h.node_count[f]; ++k)
            ++cover[h.triangle_order[k]];
    }
    for (int c : cover) ASSERT_EQ(c, 1);
}

TEST(NormalCone, IncrementalFrontEqualsTheFrontBuiltFromScratch) {
    TwistRun run(40);
    NormalConeFront incremental(run.h), scratch(run.h);
    std::mt19937 rng(5);
    std::size_t ascended = 0, descended = 0;
    const auto compare = [&](const char* what, int step) {
        incremental.update(run.s.x0, run.s.x1);
        scratch.rebuild(run.s.x0, run.s.x1);
        ascended += incremental.counters().ascended;
        descended += incremental.counters().descended;
        ASSERT_TRUE(std::ranges::equal(incremental.front(), scratch.front())) << what << " step " << step;
        ASSERT_TRUE(std::ranges::equal(incremental.triangle_patch(), scratch.triangle_patch()));
        ASSERT_TRUE(std::ranges::equal(incremental.vertex_patch(), scratch.vertex_patch()));
        ASSERT_TRUE(std::ranges::equal(incremental.edge_patch(), scratch.edge_patch()));
        expect_top_most_passing(incremental);
    };
    // Twisting up (the front moves down), ...
    for (int i = 0; i < 60; ++i) {
        run.pose(0.1 * i, 0.02);
        compare("twisting", i);
    }
    // ... crumpled at random (jumps both ways), ...
    for (int i = 0; i < 6; ++i) {
        const Field f0(rng, 0.004 * i, 0.05, 0.3), f1(rng, 0.004 * i, 0.05, 0.3);
        for (std::size_t v = 0; v < run.s.rest.size(); ++v) {
            run.s.x0[v] = run.s.rest[v] + f0.at(run.s.rest[v]);
            run.s.x1[v] = run.s.rest[v] + f1.at(run.s.rest[v]);
        }
        compare("crumpled", i);
    }
    // ... and untwisting back to flat (the front moves up to the root).
    for (int i = 40; i >= 0; --i) {
        run.pose(0.1 * i, -0.02);
        compare("untwisting", i);
    }
    EXPECT_EQ(incremental.front().size(), 1U);
    EXPECT_GT(ascended, 20U);
    EXPECT_GT(descended, 20U);
}

TEST(NormalCone, SameFrontOnOneAndTwoThreads) {
    TwistRun run(60);
    const auto go = [&](int threads) {
        NormalConeFront front(run.h);
        tbb::task_arena arena(threads);
        arena.execute([&] {
            for (int i = 0; i < 30; ++i) {
                run.pose(0.15 * i, 0.01);
                front.update(run.s.x0, run.s.x1);
            }
        });
        return std::make_pair(std::vector<std::uint32_t>(front.triangle_patch().begin(), front.triangle_patch().end()),
                              front.counters());
    };
    const auto [one, c1] = go(1);
    const auto [two, c2] = go(2);
    EXPECT_TRUE(one == two);
    EXPECT_EQ(c1.front_size, c2.front_size);
    EXPECT_EQ(c1.contour.tests, c2.contour.tests);
    EXPECT_EQ(c1.contour.box_pairs, c2.contour.box_pairs);
    EXPECT_EQ(c1.contour.hull_tests, c2.contour.hull_tests);
}

// ---- Cost ----------------------------------------------------------------------------------------------

TEST(NormalCone, Timing200x200Sheet) {
    using Clock = std::chrono::steady_clock;
    const auto ms = [](auto d) { return std::chrono::duration<double, std::milli>(d).count(); };
    const auto b0 = Clock::now();
    TwistRun run(200);
    const auto b1 = Clock::now();
    std::printf(
        "200x200 sheet: %zu triangles, hierarchy of %zu nodes (%zu levels, %zu contour edges) built in "
        "%.0f ms\n",
        run.s.triangles.size(), run.h.node_size(), run.h.levels(), run.h.contour_edges.size(), ms(b1 - b0));
    NormalConeFront front(run.h);
    BroadPhase bp;
    BroadPhaseResult out;
    for (const double t : {0.0, 1.5, 3.0, 4.5}) {
        std::vector<double> times, cpu;
        for (int i = 0; i < 5; ++i) {
            run.pose(t + 0.01 * i, 0.01);
            const auto a = Clock::now();
            const std::clock_t ca = std::clock();
            front.update(run.s.x0, run.s.x1);
            cpu.push_back(1e3 * double(std::clock() - ca) / CLOCKS_PER_SEC);
            times.push_back(ms(Clock::now() - a));
        }
        std::sort(times.begin(), times.end());
        std::sort(cpu.begin(), cpu.end());
        const NormalConeFrontCounters& k = front.counters();
        std::printf(
            "  twist t = %.1f s: refit + front %.1f ms wall, %.1f ms CPU (medians of 5; %d threads); %zu "
            "patches, %zu contour tests, %zu edges, %zu exclusion tests\n",
            t, times[2], cpu[2], tbb::this_task_arena::max_concurrency(), k.front_size, k.contour.tests,
            k.contour.edges, k.contour.hull_tests);
        if (t != 3.0) continue;
        const auto c = Clock::now();
        bp.find(culled_input(run.s, front, 0.005), out);
        const double culled_ms = ms(Clock::now() - c);
        BroadPhaseInput plain = culled_input(run.s, front, 0.005);
        plain.vertex_patch = plain.edge_patch = plain.triangle_patch = {};
        const auto d = Clock::now();
        BroadPhaseResult unculled;
        bp.find(plain, unculled);
        const double plain_ms = ms(Clock::now() - d);
        BroadPhaseInput quiet = culled_input(run.s, front, 0.005);
        quiet.count_culled = false;
        const auto e = Clock::now();
        bp.find(quiet, out);
        const double quiet_ms = ms(Clock::now() - e);
        std::printf(
            "    broad phase at 5 mm: %.1f ms unculled, %.1f ms culled (%.1f ms not counting culled pairs), "
            "%zu -> %zu pairs\n",
            plain_ms, culled_ms, quiet_ms, unculled.vf.size() + unculled.ee.size(), out.vf.size() + out.ee.size());
    }
}

}  // namespace
}  // namespace weft::collision
