// Normal-cone culling on the GPU (cuda/src/collision/normal_cone_gpu.*) against the CPU reference
// (runtime/src/collision/normal_cone_front.*, PSCC's front), on float-representable positions:
//  - the float arithmetic (normal_cone_float.h, shared by the kernels): cones contain every sampled
//    normal of their triangles, merges contain both inputs, the contour pair test refuses motions
//    that touch; these run on the host, without a device;
//  - the same float semantics emulated on the host (refit, top-down cut, every contour pair tested),
//    and then the device itself, on folds, spirals, twists, crumples, mid-step collapses and random
//    soups: no pair that brute-force CCD finds colliding has both primitives in one patch;
//  - agreement with NormalConeFront::rebuild on the same state: at least 90 % as many pairs culled,
//    kNoPatch wherever the CPU has it, and on mesh-collider primitives; the patches form a cut of
//    the hierarchy (every cloth triangle under exactly one patch node above its leaf);
//  - the twisting sheet: at least 40 % of the broad phase's candidates culled;
//  - device cones contain the sampled normals, the same bits on every call and any stride, errors.
// Device tests skip without a GPU; the host ones (float arithmetic, emulation) run everywhere.
#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/physics/ccd.h"

#include "collision/broad_phase.h"
#include "collision/contour_test.h"
#include "collision/normal_cone.h"
#include "collision/normal_cone_float.h"
#include "collision/normal_cone_front.h"
#include "collision/normal_cone_gpu.h"
#include "weft/backend/patch_hierarchy.h"
#include "cuda_check.h"
#include "device_array.h"
#include "float_positions.h"
#include "gpu_test_util.h"
#include "normal_cone_scenes.h"
#include "random_geometry.h"
#include "sheet_deformations.h"

namespace weft::collision {
namespace {

namespace gpu = weft::cuda::collision;
using gpu::FloatCone;

constexpr double kPi = std::numbers::pi;
constexpr double kSpacing = test::kGridSpacing;
constexpr double kThickness = 0.005;

// ---- Scenes ---------------------------------------------------------------------------------------

/// Cloths (grids: test::GridScene::add_grid, before `add_collider`) and optionally a mesh collider
/// after them in one collision index space, moving x0 → x1.
struct Scene : test::GridScene {
    /// A vertex no triangle uses, in the cloth's range (kNoPatch on both sides).
    void add_loose_vertex(const Vec3d& p) {
        rest.push_back(p);
        x0.push_back(p);
        x1.push_back(p);
        cloth_vertices = static_cast<std::uint32_t>(rest.size());
    }
    /// A static cx × cy mesh collider at `offset`, after the cloth in the index space.
    void add_collider(int cx, int cy, const Vec3d& offset) {
        const MeshData m = make_grid(cx * kSpacing, cy * kSpacing, cx, cy, GridPlane::XZ);
        const auto base = static_cast<std::uint32_t>(rest.size());
        const auto group = triangle_cloth.back() + 1;
        for (const Vec3d& p : m.positions) {
            rest.push_back(p + offset);
            x0.push_back(p + offset);
            x1.push_back(p + offset);
        }
        for (Triangle t : m.triangles) {
            for (std::uint32_t& v : t.v) v += base;
            triangles.push_back(t);
            triangle_cloth.push_back(group);
        }
        edges = build_edges(triangles);
    }
    [[nodiscard]] std::uint32_t cloth_edges() const {
        // build_edges sorts by (v0, v1): the cloth's edges (both ends below cloth_vertices) come first.
        std::uint32_t e = 0;
        while (e < edges.size() && edges[e].v[0] < cloth_vertices) ++e;
        return e;
    }
    /// Rounds every coordinate to float: the device and the CPU then see the very same positions.
    void snap() { test::snap_to_float(*this); }
    [[nodiscard]] PatchHierarchy hierarchy() const {
        // Over every triangle, mesh colliders included, as CpuCollisions builds it.
        return build_patch_hierarchy(rest, triangles, edges, triangle_cloth);
    }
    [[nodiscard]] gpu::GpuNormalConeLayout layout() const {
        gpu::GpuNormalConeLayout l;
        l.vertex_count = static_cast<std::uint32_t>(x0.size());
        l.edge_count = static_cast<std::uint32_t>(edges.size());
        l.triangle_count = static_cast<std::uint32_t>(triangles.size());
        l.cloth_vertices = cloth_vertices;
        l.cloth_edges = cloth_edges();
        l.cloth_triangles = cloth_triangles;
        return l;
    }
};

Scene grid_scene(int cx, int cy) { return test::grid_scene<Scene>(cx, cy); }

using Field = test::SmoothField;

using test::fold;
using test::roll;
using test::twist;

/// An n × n twisting sheet at time t over a step dt, optionally crumpled by `crumple` metres.
Scene twist_scene(int n, double t, double dt, double crumple = 0.0, unsigned seed = 1) {
    Scene s = grid_scene(n, n);
    const double L = n * kSpacing;
    std::mt19937 rng(seed);
    const Field f0(rng, crumple, 0.04, 0.15), f1(rng, crumple, 0.04, 0.15);
    for (std::size_t v = 0; v < s.rest.size(); ++v) {
        s.x0[v] = twist(s.rest[v], L, t) + f0.at(s.rest[v]);
        s.x1[v] = twist(s.rest[v], L, t + dt) + f1.at(s.rest[v]);
    }
    s.snap();
    return s;
}

// ---- Patch ids: CPU front, float emulation, device ---------------------------------------------------

struct Patches {
    std::vector<std::uint32_t> vertex, edge, triangle;
};

/// NormalConeFront::rebuild, the CPU reference (double).
Patches cpu_patches(const PatchHierarchy& h, const Scene& s) {
    NormalConeFront front(h);
    front.rebuild(s.x0, s.x1);
    return {{front.vertex_patch().begin(), front.vertex_patch().end()},
            {front.edge_patch().begin(), front.edge_patch().end()},
            {front.triangle_patch().begin(), front.triangle_patch().end()}};
}

Vec3f to_float(const Vec3d& p) { return {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)}; }

/// Does the contour stay simple, by normal_cone_float.h's test (every non-adjacent pair whose boxes
/// overlap, relative to the x0 position of the first edge's first vertex)?
bool float_contour_simple(std::span<const ContourEdge> contour, const Vec3f& axis, const std::vector<Vec3f>& x0,
                          const std::vector<Vec3f>& x1) {
    if (contour.empty()) return true;
    const gpu::ProjectionBasis basis = gpu::projection_basis(axis);
    const Vec3f r = x0[contour[0].a];
    std::vector<gpu::SweptEdge> swept;
    for (const ContourEdge& e : contour) {
        swept.push_back(gpu::project_edge(basis, r, x0[e.a], x1[e.a], x0[e.b], x1[e.b]));
        if (!swept.back().finite) return false;
    }
    for (std::size_t i = 0; i < contour.size(); ++i)
        for (std::size_t j = i + 1; j < contour.size(); ++j) {
            const ContourEdge &a = contour[i], &b = contour[j];
            if (a.a == b.a || a.a == b.b || a.b == b.a || a.b == b.b) continue;
            if (gpu::swept_boxes_overlap(swept[i], swept[j]) && !gpu::swept_edges_separated(swept[i], swept[j]))
                return false;
        }
    return true;
}

/// The device's semantics on the host with the same float arithmetic (normal_cone_gpu.h): cones
/// refitted bottom-up, then the top-most passing nodes top-down (a node is examined only when no
/// ancestor passed), nodes with a non-cloth triangle never passing, primitives beyond the cloth's
/// counts without a patch.
Patches emulated_patches(const PatchHierarchy& h, const Scene& s) {
    const gpu::GpuNormalConeLayout layout = s.layout();
    std::vector<Vec3f> x0(s.x0.size()), x1(s.x1.size());
    for (std::size_t v = 0; v < x0.size(); ++v) {
        x0[v] = to_float(s.x0[v]);
        x1[v] = to_float(s.x1[v]);
    }
    const std::size_t nodes = h.node_size();
    std::vector<FloatCone> cones(nodes);
    std::vector<std::uint8_t> all_cloth(nodes, 0), any_cloth(nodes, 0);
    for (std::size_t k = nodes; k-- > 0;) {  // children have larger ids than their parent
        const auto n = static_cast<std::uint32_t>(k);
        if (h.is_leaf(n)) {
            const std::uint32_t t = h.triangle_order[h.node_first[n]];
            all_cloth[n] = any_cloth[n] = t < layout.cloth_triangles ? 1 : 0;
            const Triangle& tri = h.triangles[t];
            if (all_cloth[n] != 0)
                cones[n] = gpu::float_triangle_cone(x0[tri.v[0]], x0[tri.v[1]], x0[tri.v[2]], x1[tri.v[0]],
                                                    x1[tri.v[1]], x1[tri.v[2]]);
        } else {
            const std::uint32_t l = h.node_child[n];
            all_cloth[n] = static_cast<std::uint8_t>(all_cloth[l] & all_cloth[l + 1]);
            any_cloth[n] = static_cast<std::uint8_t>(any_cloth[l] | any_cloth[l + 1]);
            if (all_cloth[n] != 0) cones[n] = gpu::float_merge_cones(cones[l], cones[l + 1]);
        }
    }
    constexpr std::uint32_t kOpen = kNone, kClosed = kNone - 1;
    std::vector<std::uint32_t> top(nodes, kOpen);
    for (std::uint32_t n = 0; n < nodes; ++n) {  // parents first
        const std::uint32_t above = h.node_parent[n] == kNone ? kOpen : top[h.node_parent[n]];
        if (above != kOpen) {
            top[n] = above;
        } else if (any_cloth[n] == 0) {
            top[n] = kClosed;
        } else if (h.is_leaf(n)) {
            top[n] = n;
        } else if (all_cloth[n] != 0 && (h.node_flags[n] & PatchHierarchy::kDisk) != 0 &&
                   gpu::float_cone_is_narrow(cones[n]) && float_contour_simple(h.contour(n), cones[n].axis, x0, x1)) {
            top[n] = n;
        }
    }
    const auto patch = [&](std::uint32_t t) {
        if (t == kNone || t >= layout.cloth_triangles) return kNoPatch;
        const std::uint32_t p = top[h.triangle_leaf[t]];
        return p == kClosed ? kNoPatch : p;
    };
    Patches out;
    out.vertex.assign(layout.vertex_count, kNoPatch);
    out.edge.assign(layout.edge_count, kNoPatch);
    out.triangle.assign(layout.triangle_count, kNoPatch);
    for (std::uint32_t v = 0; v < layout.cloth_vertices; ++v) out.vertex[v] = patch(h.vertex_triangle[v]);
    for (std::uint32_t e = 0; e < layout.cloth_edges; ++e) out.edge[e] = patch(h.edge_triangle[e]);
    for (std::uint32_t t = 0; t < layout.cloth_triangles; ++t) out.triangle[t] = patch(t);
    return out;
}

using test::Stream;

/// x0 and x1 on the device as the CUDA backend lays them out: structure of arrays, component stride
/// `stride` (≥ the vertex count; the padding is NaN, which must never be read).
struct DevicePositions {
    cuda::MemoryLedger ledger;
    cuda::DeviceArray<float> x0, x1;
    std::uint32_t stride = 0;
    DevicePositions(const Scene& s, std::uint32_t pad) {
        stride = static_cast<std::uint32_t>(s.x0.size()) + pad;
        x0.upload(test::soa_floats(s.x0, stride), ledger, "x0");
        x1.upload(test::soa_floats(s.x1, stride), ledger, "x1");
    }
};

struct DeviceRun {
    Patches patches;
    gpu::GpuNormalConeCounters counters;
    std::vector<gpu::GpuCone> cones;
};

/// One enqueue on the device, everything downloaded.
DeviceRun device_patches(const PatchHierarchy& h, const Scene& s, std::uint32_t pad = 0) {
    Stream stream;
    DevicePositions x(s, pad);
    gpu::GpuNormalConeCulling culling;
    culling.build(h, s.layout());
    culling.enqueue(x.x0.get(), x.x1.get(), x.stride, stream.s);
    DeviceRun r;
    r.counters = culling.read_back(stream.s);
    culling.download(r.patches.vertex, r.patches.edge, r.patches.triangle, stream.s);
    culling.download_cones(r.cones, stream.s);
    return r;
}

// ---- Checks -------------------------------------------------------------------------------------------

/// The patches must be a cut of the hierarchy made of cloth nodes: each cloth triangle's patch is a
/// node on its leaf's ancestor chain, all triangles of a patch node carry it, a vertex or edge takes
/// its reference triangle's patch, and nothing else has one. Returns the number of patches.
std::size_t expect_cut(const PatchHierarchy& h, const Scene& s, const Patches& p, const char* what) {
    const gpu::GpuNormalConeLayout layout = s.layout();
    EXPECT_EQ(p.vertex.size(), layout.vertex_count) << what;
    EXPECT_EQ(p.edge.size(), layout.edge_count) << what;
    EXPECT_EQ(p.triangle.size(), layout.triangle_count) << what;
    std::set<std::uint32_t> patches;
    for (std::uint32_t t = 0; t < p.triangle.size(); ++t) {
        if (t >= layout.cloth_triangles) {
            EXPECT_EQ(p.triangle[t], kNoPatch) << what << ": collider triangle " << t;
            continue;
        }
        const std::uint32_t f = p.triangle[t];
        bool above = false;
        for (std::uint32_t n = h.triangle_leaf[t]; n != kNone && !above; n = h.node_parent[n]) above = n == f;
        EXPECT_TRUE(above) << what << ": triangle " << t << " has patch " << f << ", not above its leaf";
        if (above) patches.insert(f);
    }
    for (std::uint32_t f : patches)
        for (std::uint32_t k = h.node_first[f]; k < h.node_first[f] + h.node_count[f]; ++k)
            EXPECT_EQ(p.triangle[h.triangle_order[k]], f) << what << ": patch " << f << " is not a cut";
    for (std::uint32_t v = 0; v < p.vertex.size(); ++v) {
        const std::uint32_t t = v < h.vertex_triangle.size() ? h.vertex_triangle[v] : kNone;
        const std::uint32_t want = v < layout.cloth_vertices && t != kNone ? p.triangle[t] : kNoPatch;
        EXPECT_EQ(p.vertex[v], want) << what << ": vertex " << v;
    }
    for (std::uint32_t e = 0; e < p.edge.size(); ++e) {
        const std::uint32_t t = e < h.edge_triangle.size() ? h.edge_triangle[e] : kNone;
        const std::uint32_t want = e < layout.cloth_edges && t != kNone ? p.triangle[t] : kNoPatch;
        EXPECT_EQ(p.edge[e], want) << what << ": edge " << e;
    }
    return patches.size();
}

/// Every non-adjacent vertex–face and edge–edge pair that CCD (double, separation 0) finds
/// colliding during the step (normal_cone_scenes.h).
using Colliding = test::CollidingPairs;
Colliding brute_force_ccd(const Scene& s) { return test::brute_force_ccd(s, 0.0); }

/// Colliding pairs whose two primitives share a patch: what culling would wrongly skip.
std::size_t culled_colliding(const Colliding& c, const Patches& p, const char* what) {
    std::size_t lost = 0;
    for (const VertexFacePair& q : c.vf) {
        if (p.vertex[q.vertex] == kNoPatch || p.vertex[q.vertex] != p.triangle[q.triangle]) continue;
        ++lost;
        ADD_FAILURE() << what << ": colliding vertex " << q.vertex << " / triangle " << q.triangle << " culled (patch "
                      << p.triangle[q.triangle] << ")";
    }
    for (const EdgeEdgePair& q : c.ee) {
        if (p.edge[q.a] == kNoPatch || p.edge[q.a] != p.edge[q.b]) continue;
        ++lost;
        ADD_FAILURE() << what << ": colliding edges " << q.a << " / " << q.b << " culled (patch " << p.edge[q.a] << ")";
    }
    return lost;
}

/// The CPU broad phase with these patches at `thickness`: pairs culled and pairs kept.
struct Culled {
    std::size_t culled = 0, kept = 0;
    [[nodiscard]] double share() const { return culled + kept > 0 ? double(culled) / double(culled + kept) : 0.0; }
};
Culled broad_phase_culling(const Scene& s, const Patches& p, double thickness) {
    BroadPhaseInput in{.x0 = s.x0,
                       .x1 = s.x1,
                       .triangles = s.triangles,
                       .edges = s.edges,
                       .triangle_cloth = s.triangle_cloth,
                       .thickness = thickness};
    in.vertex_patch = p.vertex;
    in.edge_patch = p.edge;
    in.triangle_patch = p.triangle;
    in.count_culled = true;
    BroadPhase bp;
    BroadPhaseResult out;
    bp.find(in, out);
    return {out.counters.culled_pairs, out.counters.candidate_pairs};
}

/// The adversarial motions of tests/solver/test_normal_cone.cpp (folding through, spirals whose
/// turns pass through each other, twists and crumples that cross themselves, folds that happen only
/// mid-step) and random soups (random_geometry.h), float-snapped.
std::vector<std::pair<std::string, Scene>> adversarial_scenes() {
    std::vector<std::pair<std::string, Scene>> out;
    const auto add = [&](std::string name, Scene s) {
        s.snap();
        out.emplace_back(std::move(name), std::move(s));
    };
    test::MotionRandom random(3);
    test::adversarial_motions<Scene>(random, {.folds = 4, .spirals = 3, .twists = 3, .crumples = 4},
                                     [&](Scene&& s, std::string name) { add(std::move(name), std::move(s)); });
    for (unsigned seed = 1; seed <= 2; ++seed) {
        // Soups: mostly non-manifold, hence few disks, but every triangle is its own leaf patch and
        // any disk found among the lattice's sheets is tested like any other.
        std::mt19937 soup_rng(seed);
        const test::RandomSoup soup = test::random_soup(soup_rng, 6, 300, 0.15, 0.0);
        Scene s;
        s.rest = soup.x0;
        s.x0 = soup.x0;
        s.x1 = soup.x1;
        s.triangles = soup.triangles;
        s.triangle_cloth.assign(s.triangles.size(), 0);
        s.edges = build_edges(s.triangles);
        s.cloth_vertices = static_cast<std::uint32_t>(s.x0.size());
        s.cloth_triangles = static_cast<std::uint32_t>(s.triangles.size());
        add("soup " + std::to_string(seed), std::move(s));
    }
    return out;
}

/// Requirement (1), conservative: on every adversarial scene no colliding pair shares a patch; and
/// the patches are a cut. Returns the pairs culled at the contact thickness over all scenes (so the
/// check is not vacuous).
template <typename Compute>
std::size_t check_conservative(Compute compute, const char* who) {
    std::size_t colliding = 0, culled = 0, kept = 0;
    for (const auto& [name, s] : adversarial_scenes()) {
        const std::string what = std::string(who) + " " + name;
        const PatchHierarchy h = s.hierarchy();
        const Patches p = compute(h, s);
        (void)expect_cut(h, s, p, what.c_str());
        const Colliding c = brute_force_ccd(s);
        colliding += c.vf.size() + c.ee.size();
        EXPECT_EQ(culled_colliding(c, p, what.c_str()), 0U);
        const Culled k = broad_phase_culling(s, p, kThickness);
        culled += k.culled;
        kept += k.kept;
    }
    std::printf("%s: %zu colliding pairs, none culled; culling removed %zu of %zu candidates at %.0f mm\n", who,
                colliding, culled, culled + kept, kThickness * 1e3);
    EXPECT_GT(colliding, 5000U);
    return culled;
}

/// Requirement (2), agreement with NormalConeFront::rebuild on the same state (cloth, a loose vertex
/// and a mesh collider): every primitive the CPU leaves without a patch has none, mesh-collider
/// primitives have none, and the pairs culled (the CPU's patches restricted to the cloth, since the
/// device never culls collider pairs) are at least 90 % of the CPU's.
template <typename Compute>
void check_agreement(Compute compute, const char* who) {
    struct Case {
        double t, crumple;
        Vec3d offset;
    };
    // The last case lies 100 m from the origin, where float positions are 8 µm apart.
    for (const Case c : {Case{1.5, 0.0, {}}, Case{3.0, 0.0, {}}, Case{4.5, 0.0, {}}, Case{2.0, 0.002, {}},
                         Case{5.0, 0.004, {}}, Case{3.5, 0.001, {60.0, -70.0, 40.0}}}) {
        Scene s = twist_scene(60, c.t, 0.01, c.crumple, 7);
        for (auto* xs : {&s.x0, &s.x1})
            for (Vec3d& p : *xs) p += c.offset;
        s.add_loose_vertex({0.0, 0.0, 0.5});
        s.add_collider(8, 8, {0.0, -0.5, 0.0});
        s.snap();
        char what[96];
        std::snprintf(what, sizeof what, "%s twist t = %.1f s%s%s", who, c.t, c.crumple > 0.0 ? ", crumpled" : "",
                      c.offset.x != 0.0 ? ", 100 m away" : "");
        const PatchHierarchy h = s.hierarchy();
        const Patches p = compute(h, s);
        Patches ref = cpu_patches(h, s);
        const std::size_t patches = expect_cut(h, s, p, what);
        // kNoPatch wherever the CPU has it (the loose vertex), and on the collider.
        std::size_t cpu_none = 0;
        for (std::uint32_t v = 0; v < ref.vertex.size(); ++v)
            if (ref.vertex[v] == kNoPatch) {
                ++cpu_none;
                EXPECT_EQ(p.vertex[v], kNoPatch) << what << ": vertex " << v;
            }
        for (std::uint32_t e = 0; e < ref.edge.size(); ++e) {
            if (ref.edge[e] == kNoPatch) {
                EXPECT_EQ(p.edge[e], kNoPatch) << what << ": edge " << e;
            }
        }
        for (std::uint32_t t = 0; t < ref.triangle.size(); ++t) {
            if (ref.triangle[t] == kNoPatch) {
                EXPECT_EQ(p.triangle[t], kNoPatch) << what << ": triangle " << t;
            }
        }
        EXPECT_GE(cpu_none, 1U) << "the loose vertex";
        // The CPU's patches on the cloth only.
        const gpu::GpuNormalConeLayout l = s.layout();
        std::fill(ref.vertex.begin() + l.cloth_vertices, ref.vertex.end(), kNoPatch);
        std::fill(ref.edge.begin() + l.cloth_edges, ref.edge.end(), kNoPatch);
        std::fill(ref.triangle.begin() + l.cloth_triangles, ref.triangle.end(), kNoPatch);
        const Culled mine = broad_phase_culling(s, p, kThickness), cpu = broad_phase_culling(s, ref, kThickness);
        std::size_t same = 0;
        for (std::uint32_t t = 0; t < l.cloth_triangles; ++t) same += p.triangle[t] == ref.triangle[t] ? 1 : 0;
        std::printf(
            "%s: %zu patches, %.1f %% of triangles with the CPU's patch; culled %zu pairs (%.1f %%), the CPU "
            "%zu (%.1f %%)\n",
            what, patches, 100.0 * double(same) / double(l.cloth_triangles), mine.culled, 100.0 * mine.share(),
            cpu.culled, 100.0 * cpu.share());
        EXPECT_GT(cpu.culled, 1000U) << what << ": the comparison is not vacuous";
        EXPECT_GE(double(mine.culled), 0.9 * double(cpu.culled)) << what;
    }
}

/// Requirement (3): on PSCC's twisting sheet (100 × 100 cells, steps of 10 ms, 5 mm thickness), at
/// least 40 % of the candidates are culled at every whole second from 1 to 6 s.
template <typename Compute>
void check_twist_share(Compute compute, const char* who) {
    for (int second = 1; second <= 6; ++second) {
        const Scene s = twist_scene(100, second, 0.01);
        const PatchHierarchy h = s.hierarchy();
        const Patches p = compute(h, s);
        const Culled k = broad_phase_culling(s, p, kThickness);
        std::printf("%s twist t = %d s: culled %.1f %% of %zu candidates\n", who, second, 100.0 * k.share(),
                    k.culled + k.kept);
        EXPECT_GE(k.share(), 0.4) << who << " t = " << second;
    }
}

/// Do the closed segments ab and cd of the plane z = 0 (x, y used) intersect? Orientation tests in
/// double; collinear overlaps count.
bool segments_intersect(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
    const auto orient = [](const Vec3d& o, const Vec3d& p, const Vec3d& q) {
        const double v = (p.x - o.x) * (q.y - o.y) - (p.y - o.y) * (q.x - o.x);
        return v > 0.0 ? 1 : (v < 0.0 ? -1 : 0);
    };
    const auto within = [](const Vec3d& p, const Vec3d& q, const Vec3d& r) {  // r on segment pq, collinear
        return std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y &&
               r.y <= std::max(p.y, q.y);
    };
    const int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
    if (o1 != o2 && o3 != o4) return true;
    return (o1 == 0 && within(a, b, c)) || (o2 == 0 && within(a, b, d)) || (o3 == 0 && within(c, d, a)) ||
           (o4 == 0 && within(c, d, b));
}

// ---- The float arithmetic, on the host ---------------------------------------------------------------

TEST(NormalConeFloat, TriangleConesContainTheNormalAtSampledTimes) {
    std::mt19937 rng(1);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    int bounded = 0, unbounded = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        // Motions from tiny to flipping, and positions far from the origin for some.
        const double scale = std::pow(10.0, -4.0 + 4.5 * unit(rng));
        const Vec3d offset = trial % 4 == 0 ? Vec3d{100.0 * g(rng), 100.0 * g(rng), 0.0} : Vec3d{};
        Vec3f p0[3], p1[3];
        for (int k = 0; k < 3; ++k) {
            const Vec3d a = offset + Vec3d{g(rng), g(rng), g(rng)};
            p0[k] = to_float(a);
            p1[k] = to_float(a + scale * Vec3d{g(rng), g(rng), g(rng)});
        }
        const FloatCone c = gpu::float_triangle_cone(p0[0], p0[1], p0[2], p1[0], p1[1], p1[2]);
        if (!gpu::float_cone_is_narrow(c)) {
            ++unbounded;
            continue;
        }
        ++bounded;
        const Vec3d axis = c.axis.cast<double>();
        for (int i = 0; i <= 200; ++i) {
            const double t = i / 200.0;
            Vec3d q[3];
            for (int k = 0; k < 3; ++k) q[k] = p0[k].cast<double>() + t * (p1[k].cast<double>() - p0[k].cast<double>());
            const Vec3d n = physics::cross(q[1] - q[0], q[2] - q[0]);
            if (physics::length(n) < 1e-9) continue;
            ASSERT_LE(angle_between(axis, n), double(c.half_angle) + 1e-12) << "trial " << trial << " t " << t;
        }
    }
    std::printf("float triangle cones: %d bounded, %d unbounded\n", bounded, unbounded);
    EXPECT_GT(bounded, 2000);
    EXPECT_GT(unbounded, 100);
    // Turned by π in its plane: collapses mid-step although both ends face +z.
    const Vec3f a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    EXPECT_FALSE(gpu::float_cone_is_narrow(gpu::float_triangle_cone(a, b, c, -1.0F * a, -1.0F * b, -1.0F * c)));
    EXPECT_FALSE(gpu::float_cone_is_narrow(gpu::float_triangle_cone(a, b, c, a, b, Vec3f{0, -1, 0})));
    const float nan = std::numeric_limits<float>::quiet_NaN(), big = 1e30F;
    EXPECT_FALSE(gpu::float_cone_is_narrow(gpu::float_triangle_cone(a, b, c, a, b, Vec3f{nan, 0, 0})));
    EXPECT_FALSE(gpu::float_cone_is_narrow(gpu::float_triangle_cone(a, b, c, a, Vec3f{big, 0, 0}, Vec3f{0, big, 0})));
    const FloatCone still = gpu::float_triangle_cone(a, b, c, a, b, c);
    EXPECT_LT(still.half_angle, 1e-4F);
    EXPECT_NEAR(still.axis.z, 1.0F, 1e-6F);
}

TEST(NormalConeFloat, MergedConesContainBothInputs) {
    std::mt19937 rng(2);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const auto random_axis = [&] { return physics::normalized(Vec3d{g(rng), g(rng), g(rng)}); };
    int merged = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        // Axes from identical to far apart (including the nearly parallel range of the fallback).
        const Vec3d a1 = random_axis();
        const double spread = std::pow(10.0, -8.0 + 8.3 * unit(rng));
        const Vec3d a2 = physics::normalized(a1 + spread * random_axis());
        FloatCone c1, c2;
        c1.axis = to_float(a1);
        c2.axis = to_float(a2);
        c1.half_angle = static_cast<float>(1.2 * unit(rng) * unit(rng));
        c2.half_angle = static_cast<float>(1.2 * unit(rng) * unit(rng));
        const FloatCone m = gpu::float_merge_cones(c1, c2);
        if (!gpu::float_cone_is_narrow(m)) continue;
        ++merged;
        // The boundary of each input cone, in 64 directions, must lie in the merged cone.
        for (const FloatCone& in : {c1, c2}) {
            const Vec3d axis = physics::normalized(in.axis.cast<double>());
            const Vec3d u =
                physics::normalized(physics::cross(axis, std::abs(axis.x) < 0.6 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0}));
            const Vec3d v = physics::cross(axis, u);
            for (int k = 0; k < 64; ++k) {
                const double phi = 2.0 * kPi * k / 64.0, th = double(in.half_angle);
                const Vec3d d = std::cos(th) * axis + std::sin(th) * (std::cos(phi) * u + std::sin(phi) * v);
                ASSERT_LE(angle_between(m.axis.cast<double>(), d), double(m.half_angle) + 1e-12)
                    << "trial " << trial << " spread " << spread;
            }
        }
    }
    EXPECT_GT(merged, 5000);
    EXPECT_FALSE(
        gpu::float_cone_is_narrow(gpu::float_merge_cones(FloatCone{{1, 0, 0}, 0.8F}, FloatCone{{-1, 0, 0}, 0.1F})));
    EXPECT_FALSE(gpu::float_cone_is_narrow(gpu::float_merge_cones(FloatCone{{1, 0, 0}, 0.1F}, FloatCone{})));
}

TEST(NormalConeFloat, ContourTestFollowsTheMotion) {
    const auto simple = [](const std::vector<ContourEdge>& c, const Vec3d& axis, const std::vector<Vec3d>& x0,
                           const std::vector<Vec3d>& x1) {
        std::vector<Vec3f> f0, f1;
        for (const Vec3d& p : x0) f0.push_back(to_float(p));
        for (const Vec3d& p : x1) f1.push_back(to_float(p));
        return float_contour_simple(c, to_float(axis), f0, f1);
    };
    const std::vector<ContourEdge> square = {{0, 1}, {1, 2}, {2, 3}, {3, 0}};
    const std::vector<Vec3d> x0 = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const Vec3d z{0, 0, 1};
    std::vector<Vec3d> x1;
    for (const Vec3d& p : x0) x1.push_back(0.5 * p + Vec3d{3.0, 0.2, 5.0 * p.x});
    EXPECT_TRUE(simple(square, z, x0, x1));
    x1 = x0;
    x1[2] = {0.5, -1.0, 0.0};
    x1[3] = {0.5, 2.0, 0.0};
    EXPECT_FALSE(simple(square, z, x0, x1));
    x1 = {{0, 1, 0}, {1, 1, 0}, {1, 0, 0}, {0, 0, 0}};  // mirrored mid-step, simple at both ends
    EXPECT_FALSE(simple(square, z, x0, x1));
    EXPECT_FALSE(simple(square, Vec3d{1, 0, 0}, x0, x0));
    // A U whose arms stay 1e-3 apart is simple, touching arms are not; far from the origin alike
    // (the reference point keeps float's precision local).
    const std::vector<ContourEdge> u = {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 5}, {5, 0}};
    for (const Vec3d shift : {Vec3d{}, Vec3d{1000.0, -2000.0, 500.0}}) {
        std::vector<Vec3d> ux = {{0, 0, 0}, {1, 0, 0}, {1, 1e-3, 0}, {0.01, 1e-3, 0}, {0.01, 2e-3, 0}, {0, 2e-3, 0}};
        for (Vec3d& p : ux) p += shift;
        EXPECT_TRUE(simple(u, z, ux, ux));
        std::vector<Vec3d> ux1 = ux;
        ux1[2].y = ux1[3].y = shift.y;  // the middle arm pressed onto the bottom one at t = 1
        EXPECT_FALSE(simple(u, z, ux, ux1));
        ux1 = ux;
        ux1[4].x = std::numeric_limits<double>::quiet_NaN();
        EXPECT_FALSE(simple(u, z, ux, ux1));
    }
    // The turning, flying 400-gon of the CPU test stays simple.
    std::vector<ContourEdge> ring;
    std::vector<Vec3d> r0, r1;
    for (std::uint32_t i = 0; i < 400; ++i) {
        const double a = 2.0 * kPi * i / 400.0;
        ring.push_back({i, (i + 1) % 400});
        r0.push_back({std::cos(a), std::sin(a), 0.0});
        r1.push_back(Vec3d{std::cos(a + 0.3), std::sin(a + 0.3), 0.1 * std::sin(3.0 * a)} + Vec3d{10.0, 3.0, 0.0});
    }
    EXPECT_TRUE(simple(ring, z, r0, r1));
    // Random small contours: whatever the float test accepts must be simple at every sampled time
    // (no two non-adjacent edges of the projected polygon intersect).
    std::mt19937 rng(4);
    std::normal_distribution<double> g(0.0, 1.0);
    ContourTestScratch scratch;
    ContourTestCounters counters;
    int accepted = 0, refused = 0, cpu_accepted = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const double amp = std::pow(10.0, -2.0 + 2.3 * double(trial % 100) / 100.0);
        std::vector<Vec3d> p0, p1;
        std::vector<ContourEdge> c;
        const auto m = static_cast<std::uint32_t>(5 + trial % 7);
        for (std::uint32_t i = 0; i < m; ++i) {
            const double a = 2.0 * kPi * i / m;
            const Vec3d p{std::cos(a), std::sin(a), 0.0};
            p0.push_back(to_float(p + 0.3 * amp * Vec3d{g(rng), g(rng), g(rng)}).cast<double>());
            p1.push_back(to_float(p + amp * Vec3d{g(rng), g(rng), g(rng)}).cast<double>());
            c.push_back({i, (i + 1) % m});
        }
        cpu_accepted += contour_stays_simple(c, z, p0, p1, scratch, counters) ? 1 : 0;
        if (!simple(c, z, p0, p1)) {
            ++refused;
            continue;
        }
        ++accepted;
        for (int k = 0; k <= 100; ++k) {
            const double t = k / 100.0;
            const auto at = [&](std::uint32_t v) { return p0[v] + t * (p1[v] - p0[v]); };
            for (std::uint32_t i = 0; i < m; ++i)
                for (std::uint32_t j = i + 2; j < m; ++j) {
                    if (i == 0 && j + 1 == m) continue;  // adjacent through the closing edge
                    ASSERT_FALSE(segments_intersect(at(c[i].a), at(c[i].b), at(c[j].a), at(c[j].b)))
                        << "trial " << trial << " t " << t << " edges " << i << ", " << j;
                }
        }
    }
    std::printf("random contours: %d accepted, %d refused by the float test (the CPU's accepts %d)\n", accepted,
                refused, cpu_accepted);
    EXPECT_GT(accepted, 200);
    EXPECT_GT(refused, 200);
}

// ---- The float semantics emulated on the host ----------------------------------------------------------

TEST(NormalConeFloat, EmulationIsConservative) {
    EXPECT_GT(check_conservative(emulated_patches, "host float emulation"), 20000U);
}

TEST(NormalConeFloat, EmulationAgreesWithTheCpuFront) { check_agreement(emulated_patches, "host float emulation"); }

TEST(NormalConeFloat, EmulationCullsTheTwistingSheet) { check_twist_share(emulated_patches, "host float emulation"); }

// ---- The device -------------------------------------------------------------------------------------------

Patches on_device(const PatchHierarchy& h, const Scene& s) { return device_patches(h, s).patches; }

TEST(NormalConeGpu, ConservativeOnAdversarialMotions) {
    WEFT_REQUIRE_GPU();
    EXPECT_GT(check_conservative(on_device, "GPU"), 20000U);
}

TEST(NormalConeGpu, AgreesWithTheCpuFront) {
    WEFT_REQUIRE_GPU();
    check_agreement(on_device, "GPU");
}

TEST(NormalConeGpu, CullsTheTwistingSheet) {
    WEFT_REQUIRE_GPU();
    check_twist_share(on_device, "GPU");
}

TEST(NormalConeGpu, DeviceConesContainTheSampledNormals) {
    WEFT_REQUIRE_GPU();
    const Scene s = twist_scene(30, 2.5, 0.05, 0.003, 11);
    const PatchHierarchy h = s.hierarchy();
    const DeviceRun r = device_patches(h, s);
    ASSERT_EQ(r.cones.size(), h.node_size());
    std::size_t narrow = 0;
    for (std::uint32_t n = 0; n < h.node_size(); ++n) {
        const gpu::GpuCone& c = r.cones[n];
        if (!(c.half_angle < gpu::kNarrowLimit)) continue;
        ++narrow;
        const Vec3d axis{c.axis[0], c.axis[1], c.axis[2]};
        for (std::uint32_t k = h.node_first[n]; k < h.node_first[n] + h.node_count[n]; ++k) {
            const Triangle& t = s.triangles[h.triangle_order[k]];
            for (int i = 0; i <= 20; ++i) {
                const double u = i / 20.0;
                const auto at = [&](std::uint32_t v) { return s.x0[v] + u * (s.x1[v] - s.x0[v]); };
                const Vec3d nrm = physics::cross(at(t.v[1]) - at(t.v[0]), at(t.v[2]) - at(t.v[0]));
                ASSERT_LE(angle_between(axis, nrm), double(c.half_angle) + 1e-12) << "node " << n;
            }
        }
    }
    EXPECT_GT(narrow, h.node_size() / 4);
}

TEST(NormalConeGpu, SameBitsOnEveryCallAndAnyStride) {
    WEFT_REQUIRE_GPU();
    Scene s = twist_scene(50, 4.0, 0.01, 0.002, 5);
    s.add_collider(5, 5, {0.0, 0.4, 0.0});
    s.snap();
    const PatchHierarchy h = s.hierarchy();
    const DeviceRun a = device_patches(h, s), b = device_patches(h, s, 37);
    EXPECT_TRUE(a.patches.vertex == b.patches.vertex);
    EXPECT_TRUE(a.patches.edge == b.patches.edge);
    EXPECT_TRUE(a.patches.triangle == b.patches.triangle);
    // Repeated calls on one object: the same ids and counters.
    Stream stream;
    DevicePositions x(s, 0);
    gpu::GpuNormalConeCulling culling;
    culling.build(h, s.layout());
    Patches first, again;
    culling.enqueue(x.x0.get(), x.x1.get(), 0, stream.s);
    const gpu::GpuNormalConeCounters c1 = culling.read_back(stream.s);
    culling.download(first.vertex, first.edge, first.triangle, stream.s);
    const std::size_t bytes = culling.memory_bytes();
    culling.enqueue(x.x0.get(), x.x1.get(), 0, stream.s);
    const gpu::GpuNormalConeCounters c2 = culling.read_back(stream.s);
    culling.download(again.vertex, again.edge, again.triangle, stream.s);
    EXPECT_TRUE(first.triangle == a.patches.triangle);
    EXPECT_TRUE(again.vertex == first.vertex && again.edge == first.edge && again.triangle == first.triangle);
    EXPECT_EQ(c1.front_size, c2.front_size);
    EXPECT_EQ(c1.contour_tests, c2.contour_tests);
    EXPECT_EQ(c1.contour_failed, c2.contour_failed);
    EXPECT_EQ(c1.contour_items, c2.contour_items);
    EXPECT_EQ(culling.memory_bytes(), bytes);
    // The front counts every patch: the cloth's distinct ids (the collider's root is closed).
    const std::set<std::uint32_t> ids(first.triangle.begin(), first.triangle.begin() + s.cloth_triangles);
    EXPECT_EQ(c1.front_size, ids.size());
    EXPECT_GT(c1.contour_tests, c1.contour_failed);
    std::printf("twist 50x50 + collider: %u patches, %u contour tests (%u refused, %u tile pairs), %zu bytes\n",
                c1.front_size, c1.contour_tests, c1.contour_failed, c1.contour_items, bytes);
}

TEST(NormalConeGpu, InputErrorsAreReported) {
    WEFT_REQUIRE_GPU();
    const Scene s = twist_scene(8, 1.0, 0.01);
    const PatchHierarchy h = s.hierarchy();
    Stream stream;
    DevicePositions x(s, 0);
    gpu::GpuNormalConeCulling culling;
    EXPECT_THROW(culling.enqueue(x.x0.get(), x.x1.get(), 0, stream.s), Error);  // before build
    gpu::GpuNormalConeLayout small = s.layout();
    small.triangle_count -= 1;
    small.cloth_triangles -= 1;
    EXPECT_THROW(culling.build(h, small), Error);
    gpu::GpuNormalConeLayout wrong = s.layout();
    wrong.cloth_vertices = wrong.vertex_count + 1;
    EXPECT_THROW(culling.build(h, wrong), Error);
    culling.build(h, s.layout());
    EXPECT_THROW(culling.enqueue(x.x0.get(), x.x1.get(), x.stride - 1, stream.s), Error);
    EXPECT_THROW(culling.enqueue(nullptr, x.x1.get(), 0, stream.s), Error);
}

}  // namespace
}  // namespace weft::collision
