#pragma once
// Scenes of the normal-cone culling tests, shared by the CPU front's test (tests/solver/
// test_normal_cone.cpp) and the GPU's (tests/gpu/test_normal_cone_gpu.cpp): 1 cm grids moving
// x0 → x1 in one collision index space, the adversarial motions both run, and brute-force CCD as
// the judge that goes through no broad phase.
#include <algorithm>
#include <cstdint>
#include <initializer_list>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "weft/mesh.h"
#include "weft/physics/ccd.h"

#include "collision/broad_phase.h"
#include "random_geometry.h"
#include "sheet_deformations.h"

namespace weft::test {

inline constexpr double kGridSpacing = 0.01;  // 1 cm grids throughout

/// Cloths in one global vertex/triangle list, with a motion x0 → x1.
struct GridScene {
    std::vector<Vec3d> rest, x0, x1;
    std::vector<Triangle> triangles;
    std::vector<std::uint32_t> triangle_cloth;
    std::vector<collision::Edge> edges;
    /// The cloths' share of the index space (the GPU test appends a kinematic mesh collider after it).
    std::uint32_t cloth_vertices = 0, cloth_triangles = 0;

    /// Appends a cx × cy grid (1 cm cells) in the XY plane centred at the origin, as a new cloth;
    /// returns its first vertex.
    std::uint32_t add_grid(int cx, int cy) {
        const MeshData m = make_grid(cx * kGridSpacing, cy * kGridSpacing, cx, cy, GridPlane::XY);
        const auto base = static_cast<std::uint32_t>(rest.size());
        const auto cloth = triangle_cloth.empty() ? 0U : triangle_cloth.back() + 1;
        rest.insert(rest.end(), m.positions.begin(), m.positions.end());
        for (Triangle t : m.triangles) {
            for (std::uint32_t& v : t.v) v += base;
            triangles.push_back(t);
            triangle_cloth.push_back(cloth);
        }
        edges = collision::build_edges(triangles);
        x0 = x1 = rest;
        cloth_vertices = static_cast<std::uint32_t>(rest.size());
        cloth_triangles = static_cast<std::uint32_t>(triangles.size());
        return base;
    }
};

/// One cx × cy grid at rest (x0 = x1 = rest).
template <typename Scene = GridScene>
Scene grid_scene(int cx, int cy) {
    Scene s;
    (void)s.add_grid(cx, cy);
    return s;
}

// ---- Brute force ---------------------------------------------------------------------------------

struct SweptBox {
    Vec3d lo, hi;
};
/// The box of vertices `vs` over the step (x0 and x1), grown by `pad` (m).
inline SweptBox swept_box(const GridScene& s, std::initializer_list<std::uint32_t> vs, double pad) {
    SweptBox b{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
    for (std::uint32_t v : vs)
        for (const Vec3d& p : {s.x0[v], s.x1[v]})
            for (int k = 0; k < 3; ++k) {
                b.lo[k] = std::min(b.lo[k], p[k] - pad);
                b.hi[k] = std::max(b.hi[k], p[k] + pad);
            }
    return b;
}
inline bool boxes_touch(const SweptBox& a, const SweptBox& b) {
    for (int k = 0; k < 3; ++k)
        if (a.lo[k] > b.hi[k] || b.lo[k] > a.hi[k]) return false;
    return true;
}

struct CollidingPairs {
    std::vector<collision::VertexFacePair> vf;
    std::vector<collision::EdgeEdgePair> ee;
};

/// Every non-adjacent vertex–face and edge–edge pair that CCD (double) finds within `eta` (m)
/// during the step. A pair whose swept bounds (grown by eta) do not touch cannot come within eta,
/// so only those are given to CCD.
inline CollidingPairs brute_force_ccd(const GridScene& s, double eta) {
    std::vector<SweptBox> vb, eb, tb;
    for (std::uint32_t v = 0; v < s.x0.size(); ++v) vb.push_back(swept_box(s, {v}, eta));
    for (const collision::Edge& e : s.edges) eb.push_back(swept_box(s, {e.v[0], e.v[1]}, eta));
    for (const Triangle& t : s.triangles) tb.push_back(swept_box(s, {t.v[0], t.v[1], t.v[2]}, 0.0));
    CollidingPairs c;
    for (std::uint32_t v = 0; v < vb.size(); ++v)
        for (std::uint32_t t = 0; t < tb.size(); ++t) {
            const Triangle& tri = s.triangles[t];
            if (v == tri.v[0] || v == tri.v[1] || v == tri.v[2] || !boxes_touch(vb[v], tb[t])) continue;
            const auto r =
                physics::vertex_face_ccd<double>(s.x0[v], s.x0[tri.v[0]], s.x0[tri.v[1]], s.x0[tri.v[2]], s.x1[v],
                                                 s.x1[tri.v[0]], s.x1[tri.v[1]], s.x1[tri.v[2]], eta);
            if (r.hit) c.vf.push_back({v, t});
        }
    for (std::uint32_t a = 0; a < eb.size(); ++a)
        for (std::uint32_t b = a + 1; b < eb.size(); ++b) {
            const collision::Edge &p = s.edges[a], &q = s.edges[b];
            if (p.v[0] == q.v[0] || p.v[0] == q.v[1] || p.v[1] == q.v[0] || p.v[1] == q.v[1]) continue;
            if (!boxes_touch(eb[a], eb[b])) continue;
            const auto r = physics::edge_edge_ccd<double>(s.x0[p.v[0]], s.x0[p.v[1]], s.x0[q.v[0]], s.x0[q.v[1]],
                                                          s.x1[p.v[0]], s.x1[p.v[1]], s.x1[q.v[0]], s.x1[q.v[1]], eta);
            if (r.hit) c.ee.push_back({a, b});
        }
    return c;
}

// ---- Adversarial motions -------------------------------------------------------------------------

/// The random numbers the adversarial motions draw, kept together so that a test can go on drawing
/// from the same sequence after them.
struct MotionRandom {
    explicit MotionRandom(unsigned seed) : rng(seed) {}
    std::mt19937 rng;
    std::uniform_real_distribution<double> unit{0.0, 1.0};
    std::normal_distribution<double> g{0.0, 1.0};
};

/// How many scenes of each randomised family `adversarial_motions` makes.
struct AdversarialCounts {
    int folds = 0, spirals = 0, twists = 0, crumples = 0;
};

/// Motions that fold a sheet onto itself and through, roll a strip into a spiral whose turns pass
/// through each other, twist it far with crumpling noise that makes it cross itself, crumple it, and
/// fold it only mid-step (flat at both ends); each scene is handed to `take(Scene&&, name)` as it
/// is made. `Scene` is GridScene or a type derived from it.
template <typename Scene, typename Take>
void adversarial_motions(MotionRandom& r, const AdversarialCounts& n, Take&& take) {
    constexpr double kPi = std::numbers::pi;
    const auto noise = [&](Scene& s, double amp) {
        for (std::size_t v = 0; v < s.x0.size(); ++v) {
            s.x0[v] += amp * Vec3d{r.g(r.rng), r.g(r.rng), r.g(r.rng)};
            s.x1[v] += amp * Vec3d{r.g(r.rng), r.g(r.rng), r.g(r.rng)};
        }
    };
    // Folding onto itself and through: the flap turns from θ0 to θ1 > π about a random line.
    for (int i = 0; i < n.folds; ++i) {
        Scene s = grid_scene<Scene>(16, 14);
        const double alpha = 2.0 * kPi * r.unit(r.rng), u_fold = 0.02 * (r.unit(r.rng) - 0.5);
        const double th0 = kPi * (0.7 + 0.25 * r.unit(r.rng)), th1 = kPi * (1.02 + 0.1 * r.unit(r.rng));
        for (std::size_t v = 0; v < s.rest.size(); ++v) {
            s.x0[v] = fold(s.rest[v], alpha, u_fold, th0);
            s.x1[v] = fold(s.rest[v], alpha, u_fold, th1);
        }
        noise(s, i % 2 == 0 ? 0.0 : 2e-4);
        take(std::move(s), "fold " + std::to_string(i));
    }
    // A strip rolled into a spiral whose turns pass through each other (gap from + to −).
    for (int i = 0; i < n.spirals; ++i) {
        Scene s = grid_scene<Scene>(40, 6);
        const double x_min = -0.2, r0 = 0.025 + 0.01 * r.unit(r.rng);
        const double gap0 = 0.004 + 0.004 * r.unit(r.rng), gap1 = -0.002 - 0.004 * r.unit(r.rng);
        for (std::size_t v = 0; v < s.rest.size(); ++v) {
            s.x0[v] = roll(s.rest[v], x_min, r0, gap0);
            s.x1[v] = roll(s.rest[v], x_min, r0 * (1.0 - 0.05 * r.unit(r.rng)), gap1);
        }
        noise(s, i % 2 == 0 ? 0.0 : 1e-4);
        take(std::move(s), "spiral " + std::to_string(i));
    }
    // Twisted far (several half turns) with crumpling noise that makes it cross itself.
    for (int i = 0; i < n.twists; ++i) {
        Scene s = grid_scene<Scene>(24, 12);
        const SmoothField f0(r.rng, 0.01, 0.04, 0.15), f1(r.rng, 0.01, 0.04, 0.15);
        const double t0 = 2.0 + 3.0 * r.unit(r.rng);
        for (std::size_t v = 0; v < s.rest.size(); ++v) {
            const Vec3d p{s.rest[v].x, 0.5 * s.rest[v].y, 0.0};
            s.x0[v] = twist(p, 0.24, t0) + f0.at(s.rest[v]);
            s.x1[v] = twist(p, 0.24, t0 + 0.1) + f1.at(s.rest[v]);
        }
        take(std::move(s), "twist " + std::to_string(i));
    }
    // Crumpled: large smooth random displacements, different at both ends.
    for (int i = 0; i < n.crumples; ++i) {
        Scene s = grid_scene<Scene>(14, 14);
        const double amp = 0.01 + 0.03 * r.unit(r.rng);
        const SmoothField f0(r.rng, amp, 0.04, 0.2), f1(r.rng, amp, 0.04, 0.2);
        for (std::size_t v = 0; v < s.rest.size(); ++v) {
            s.x0[v] = s.rest[v] + f0.at(s.rest[v]);
            s.x1[v] = s.rest[v] + f1.at(s.rest[v]);
        }
        noise(s, i % 3 == 0 ? 1e-3 : 0.0);
        take(std::move(s), "crumple " + std::to_string(i));
    }
    // Folds that happen only mid-step: flat at both ends (normals +z), collapsing in between.
    Scene s = grid_scene<Scene>(6, 6);
    for (std::size_t v = 0; v < s.rest.size(); ++v) s.x1[v] = {-s.rest[v].x, -s.rest[v].y, s.rest[v].z};
    take(std::move(s), "turn by pi in-plane");
    Scene f = grid_scene<Scene>(6, 6);
    for (std::size_t v = 0; v < f.rest.size(); ++v) f.x1[v] = {f.rest[v].x, -f.rest[v].y, 0.001};
    take(std::move(f), "flip over");
    // A half of the sheet turned by π in-plane about the middle of the fold line while the other half
    // stays: it sweeps through the fixed half mid-step.
    Scene h = grid_scene<Scene>(10, 5);
    for (std::size_t v = 0; v < h.rest.size(); ++v) {
        const Vec3d p = h.rest[v];
        h.x1[v] = p.x > 0.0 ? Vec3d{-p.x, -p.y, 0.0005} : p;
    }
    take(std::move(h), "half turned mid-step");
}

}  // namespace weft::test
