#pragma once
// Scenes of the impact-zone tests, shared by the CPU reference's test (tests/solver/
// test_impact_zones.cpp) and the GPU's (tests/gpu/test_impact_zones_gpu.cpp): a scene is start and
// predicted end positions that collide, with masses and topology; brute_force_ccd is the judge that
// does not go through any broad phase.
#include <gtest/gtest.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <cstdio>
#include <cstring>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <random>
#include <vector>

#include "weft/mesh.h"
#include "weft/physics/ccd.h"

#include "collision/broad_phase.h"
#include "collision/impact_zones.h"
#include "collision/intersection_check.h"

namespace weft::collision::test {

struct Scene {
    std::vector<Vec3d> x0, x1;
    std::vector<double> inverse_mass;
    std::vector<Triangle> triangles;
    std::vector<Edge> edges;
    double thickness = 1e-3;
    /// Broad-phase group (cloth) of each triangle; empty: one group.
    std::vector<std::uint32_t> triangle_group;

    /// Appends a mesh with its vertices at x0 = x1 = positions; returns its first vertex.
    std::uint32_t add(const std::vector<Vec3d>& positions, const std::vector<Triangle>& tris, double inv_mass) {
        const auto first = static_cast<std::uint32_t>(x0.size());
        for (const Vec3d& p : positions) {
            x0.push_back(p);
            x1.push_back(p);
            inverse_mass.push_back(inv_mass);
        }
        for (Triangle t : tris) {
            for (std::uint32_t& v : t.v) v += first;
            triangles.push_back(t);
        }
        edges = build_edges(triangles);
        return first;
    }
    std::uint32_t add(const MeshData& mesh, double inv_mass) { return add(mesh.positions, mesh.triangles, inv_mass); }

    [[nodiscard]] double eta() const { return ImpactZoneInput{}.separation_ratio * thickness; }
};

/// A horizontal grid (XZ plane) centred on `centre`.
inline MeshData grid(double size, int cells, Vec3d centre) {
    MeshData m = make_grid(size, size, cells, cells, GridPlane::XZ);
    for (Vec3d& p : m.positions) p += centre;
    return m;
}

struct Collisions {
    std::size_t vf = 0, ee = 0;
    [[nodiscard]] std::size_t total() const { return vf + ee; }
};

/// CCD at eta on every vertex–face pair (vertex not a corner) and every edge–edge pair (no shared
/// vertex) from x0 to x1, skipping only pairs with no movable vertex. Independent of the broad phase.
inline Collisions brute_force_ccd(const Scene& s, const std::vector<Vec3d>& x1, double eta) {
    std::atomic<std::size_t> vf{0}, ee{0};
    const auto fixed = [&](std::uint32_t v) { return s.inverse_mass[v] == 0.0; };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, s.x0.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        std::size_t found = 0;
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const auto p = static_cast<std::uint32_t>(i);
            for (const Triangle& t : s.triangles) {
                if (p == t.v[0] || p == t.v[1] || p == t.v[2]) continue;
                if (fixed(p) && fixed(t.v[0]) && fixed(t.v[1]) && fixed(t.v[2])) continue;
                const auto c = physics::vertex_face_ccd(s.x0[p], s.x0[t.v[0]], s.x0[t.v[1]], s.x0[t.v[2]], x1[p],
                                                        x1[t.v[0]], x1[t.v[1]], x1[t.v[2]], eta);
                found += c.hit ? 1 : 0;
            }
        }
        vf += found;
    });
    const std::size_t ne = s.edges.size();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ne), [&](const tbb::blocked_range<std::size_t>& r) {
        std::size_t found = 0;
        for (std::size_t a = r.begin(); a != r.end(); ++a)
            for (std::size_t b = a + 1; b < ne; ++b) {
                const Edge &e = s.edges[a], &f = s.edges[b];
                if (e.v[0] == f.v[0] || e.v[0] == f.v[1] || e.v[1] == f.v[0] || e.v[1] == f.v[1]) continue;
                if (fixed(e.v[0]) && fixed(e.v[1]) && fixed(f.v[0]) && fixed(f.v[1])) continue;
                const auto c = physics::edge_edge_ccd(s.x0[e.v[0]], s.x0[e.v[1]], s.x0[f.v[0]], s.x0[f.v[1]],
                                                      x1[e.v[0]], x1[e.v[1]], x1[f.v[0]], x1[f.v[1]], eta);
                found += c.hit ? 1 : 0;
            }
        ee += found;
    });
    return {vf.load(), ee.load()};
}

/// Two sheets of `cells`² cells, the upper driven down through the lower and the lower up, offset
/// in the plane so that no vertex lands exactly on another primitive; masses vary by 4×.
inline Scene two_sheets(int cells, unsigned seed) {
    Scene s;
    const double size = 0.2, h = size / cells;
    const std::uint32_t a = s.add(grid(size, cells, {0.0, 0.01, 0.0}), 1.0);
    const std::uint32_t b = s.add(grid(size, cells, {0.3 * h, -0.01, 0.45 * h}), 1.0);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> inv(500.0, 2000.0), wobble(-0.1 * h, 0.1 * h);
    for (std::size_t v = 0; v < s.x0.size(); ++v) {
        s.inverse_mass[v] = inv(rng);
        const double dy = v < b ? -0.02 : 0.02;
        s.x1[v] = s.x0[v] + Vec3d{wobble(rng), dy + wobble(rng), wobble(rng)};
    }
    (void)a;
    return s;
}

/// A flat sheet of `cells`² cells of 1 cm, crumpled: a smooth random displacement whose lateral
/// part folds the sheet over itself (gradient beyond −1) while the vertical part stacks the folds
/// at different heights, plus a little per-vertex noise.
inline Scene crumpled_sheet(int cells, unsigned seed) {
    Scene s;
    const double h = 0.01, size = h * cells;
    s.add(grid(size, cells, {}), 1.0);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0), noise(-0.15 * h, 0.15 * h), inv(500.0, 2000.0);
    struct Mode {
        double kx, kz, phase;
        Vec3d amplitude;
    };
    std::vector<Mode> modes;
    for (int m = 0; m < 8; ++m) {
        const double angle = 2.0 * std::numbers::pi * unit(rng);
        const double k = 2.0 * std::numbers::pi / (h * (5.0 + 7.0 * unit(rng)));
        const double lateral = h * (1.0 + 1.5 * unit(rng));
        modes.push_back({k * std::cos(angle),
                         k * std::sin(angle),
                         2.0 * std::numbers::pi * unit(rng),
                         {lateral * std::cos(angle), h * (0.5 + 1.5 * unit(rng)), lateral * std::sin(angle)}});
    }
    for (std::size_t v = 0; v < s.x0.size(); ++v) {
        s.inverse_mass[v] = inv(rng);
        const Vec3d p = s.x0[v];
        Vec3d d{noise(rng), noise(rng), noise(rng)};
        for (const Mode& m : modes) d += std::sin(m.kx * p.x + m.kz * p.z + m.phase) * m.amplitude;
        s.x1[v] = p + d;
    }
    return s;
}

/// A triangle in the plane y = 0 with its centroid at the origin, and the tip of a vertical dart
/// (a second triangle above it) driven from 1 cm above the centroid to 1 cm below it; all masses
/// 1 kg. `dart` is the tip's vertex.
struct DartScene {
    Scene scene;
    std::uint32_t dart = 0;
};
inline DartScene dart_through_triangle() {
    DartScene d;
    Scene& s = d.scene;
    s.add({{-0.05, 0.0, -0.05}, {0.1, 0.0, -0.05}, {-0.05, 0.0, 0.1}}, {{{0, 1, 2}}}, 1.0);
    d.dart = s.add({{0.0, 0.01, 0.0}, {0.01, 0.06, 0.0}, {-0.01, 0.06, 0.0}}, {{{0, 1, 2}}}, 1.0);
    s.x1[d.dart] = {0.0, -0.01, 0.0};
    return d;
}

/// A cloth falling onto or through a fixed mesh (inverse mass 0): the cloth's vertices are
/// [cloth, fixed), the mesh's from `fixed` on.
struct ClothOnFixedMesh {
    Scene scene;
    std::uint32_t cloth = 0, fixed = 0;
};

/// A 24×24 cloth 30 cm wide (1 g per vertex) falls 1.4 cm into a fixed bumpy patch 10 cm wide, to the
/// middle of its bumps. The cloth's rim, far from the patch, falls freely.
inline ClothOnFixedMesh sheet_into_bumpy_patch() {
    ClothOnFixedMesh c;
    Scene& s = c.scene;
    c.cloth = s.add(grid(0.3, 24, {0.0, 0.01, 0.0}), 1000.0);
    MeshData patch = grid(0.1, 5, {0.003, 0.0, -0.002});
    for (Vec3d& p : patch.positions) p.y = 0.004 * std::sin(60.0 * p.x) * std::cos(50.0 * p.z) - 0.004;
    c.fixed = s.add(patch, 0.0);
    for (std::uint32_t v = c.cloth; v < c.fixed; ++v) s.x1[v].y -= 0.014;
    return c;
}

/// A 16×16 cloth 20 cm wide (1 g per vertex) falls 3 cm, through a fixed flat 4×4 patch 10 cm wide
/// 1 cm below it: it ends below the patch.
inline ClothOnFixedMesh sheet_through_fixed_patch() {
    ClothOnFixedMesh c;
    Scene& s = c.scene;
    c.cloth = s.add(grid(0.2, 16, {0.0, 0.01, 0.0}), 1000.0);
    c.fixed = s.add(grid(0.1, 4, {0.002, 0.0, 0.003}), 0.0);
    for (std::uint32_t v = c.cloth; v < c.fixed; ++v) s.x1[v].y -= 0.03;
    return c;
}

/// A collider plate 30 cm wide (inverse mass 0) rises by `lift` (3 cm up) through an 8×8 cloth 10 cm
/// wide at rest (1 g per vertex): the cloth's vertices are [cloth, plate), the plate's from `plate`.
struct PlateScene {
    Scene scene;
    std::uint32_t cloth = 0, plate = 0;
    Vec3d lift{0.001, 0.03, 0.0};
};
inline PlateScene plate_through_cloth() {
    PlateScene c;
    Scene& s = c.scene;
    c.cloth = s.add(grid(0.1, 8, {0.0, 0.0, 0.0}), 1000.0);
    c.plate = s.add(grid(0.3, 3, {0.004, -0.01, 0.002}), 0.0);
    for (std::uint32_t v = c.plate; v < s.x0.size(); ++v) s.x1[v] += c.lift;
    return c;
}

/// `layers` sheets 10 cm wide (6×6 cells, 1 g per vertex) stacked 5 mm apart above a fixed patch,
/// all falling 6 mm: the bottom one hits the patch; once it is held, the next one hits it, and so on
/// up the stack, one layer a fallback round (a fold frozen one layer at a time). The sheets' first
/// vertex is 0, the patch's `fixed`; then a lone sheet `lone` 1 m away falls freely. Groups: the
/// stack 0, the patch 1, the lone sheet 2.
struct StackScene {
    Scene scene;
    std::uint32_t fixed = 0, lone = 0;
};
inline StackScene falling_stack(int layers) {
    StackScene c;
    Scene& s = c.scene;
    for (int k = 0; k < layers; ++k) (void)s.add(grid(0.1, 6, {0.001 * k, 0.005 * (k + 1), -0.0007 * k}), 1000.0);
    const std::size_t stack_triangles = s.triangles.size();
    c.fixed = s.add(grid(0.14, 4, {0.002, 0.0, 0.003}), 0.0);
    const std::size_t patch_triangles = s.triangles.size() - stack_triangles;
    c.lone = s.add(grid(0.1, 6, {1.0, 0.02, 0.0}), 1000.0);
    for (std::uint32_t v = 0; v < s.x0.size(); ++v)
        if (v < c.fixed || v >= c.lone) s.x1[v].y -= 0.006;
    s.triangle_group.assign(stack_triangles, 0);
    s.triangle_group.insert(s.triangle_group.end(), patch_triangles, 1);
    s.triangle_group.resize(s.triangles.size(), 2);
    return c;
}

// ---- Checks shared by the CPU and GPU tests ------------------------------------------------------

struct Resolved {
    std::vector<Vec3d> x1;
    ImpactZoneReport report;
    std::vector<VertexOutcome> outcome;
    std::vector<std::uint32_t> zone;
    double ms = 0.0;
};

/// The CPU reference (ImpactZoneSolver) on the scene; `reuse` keeps a solver across calls.
inline Resolved resolve_cpu(const Scene& s, int max_iterations = 32, ImpactZoneSolver* reuse = nullptr,
                            int max_rigid_rounds = kImpactZoneRigidRounds,
                            std::int64_t max_work = ImpactZoneInput{}.qp_max_work,
                            const std::function<void(ImpactZoneInput&)>& adjust = {}) {
    Resolved r;
    r.x1 = s.x1;
    ImpactZoneSolver local;
    ImpactZoneSolver& solver = reuse != nullptr ? *reuse : local;
    ImpactZoneInput in;
    in.x0 = s.x0;
    in.x1 = r.x1;
    in.inverse_mass = s.inverse_mass;
    in.triangles = s.triangles;
    in.edges = s.edges;
    in.triangle_cloth = s.triangle_group;
    in.thickness = s.thickness;
    in.max_iterations = max_iterations;
    in.max_rigid_rounds = max_rigid_rounds;
    in.qp_max_work = max_work;
    if (adjust) adjust(in);
    const auto t0 = std::chrono::steady_clock::now();
    r.report = solver.resolve(in);
    r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    r.outcome.assign(solver.outcome().begin(), solver.outcome().end());
    r.zone.assign(solver.zone_of_vertex().begin(), solver.zone_of_vertex().end());
    return r;
}

inline bool same_bits(const Vec3d& a, const Vec3d& b) { return std::memcmp(&a, &b, sizeof(Vec3d)) == 0; }

/// What a resolve whose work cap `cap` was spent shows against the same scene uncapped (`full`):
/// the cap kept, fewer rounds, the fallbacks took the hits, and a cap of 1 allows no round at all.
inline void expect_work_capped(const ImpactZoneReport& capped, const ImpactZoneReport& full, std::int64_t cap) {
    EXPECT_TRUE(capped.qp_work_spent);
    EXPECT_LE(capped.qp_work, cap);
    EXPECT_LT(capped.iterations, full.iterations);
    EXPECT_GT(capped.rigid_rounds + capped.frozen_vertices, 0) << "the fallbacks took the hits";
    if (cap == 1) {
        EXPECT_EQ(capped.iterations, 0);
    }
}

/// Everything `resolve` promises about its output.
inline void expect_clean(const Scene& s, const Resolved& r) {
    const ImpactZoneReport& rep = r.report;
    EXPECT_TRUE(rep.resolved);
    EXPECT_EQ(rep.remaining_hits, 0);
    EXPECT_EQ(rep.eta, s.eta());
    const Collisions c = brute_force_ccd(s, r.x1, rep.eta);
    EXPECT_EQ(c.vf, 0U) << "vertex-face collisions left";
    EXPECT_EQ(c.ee, 0U) << "edge-edge collisions left";
    const IntersectionReport ic = check_intersections(r.x1, s.triangles);
    EXPECT_TRUE(ic.clean()) << ic.intersecting_pairs << " intersecting triangle pairs left";
    std::size_t fixed_moved = 0, untouched_moved = 0, frozen_off = 0, nonfinite = 0, zone_mismatch = 0;
    int frozen = 0, carried = 0;
    for (std::size_t v = 0; v < s.x0.size(); ++v) {
        nonfinite += physics::is_finite(r.x1[v]) ? 0 : 1;
        const VertexOutcome o = r.outcome[v];
        if (s.inverse_mass[v] == 0.0) {
            EXPECT_EQ(o, VertexOutcome::Fixed);
            fixed_moved += same_bits(r.x1[v], s.x1[v]) ? 0 : 1;
        }
        if (o == VertexOutcome::Untouched) untouched_moved += same_bits(r.x1[v], s.x1[v]) ? 0 : 1;
        if (o == VertexOutcome::Frozen) frozen_off += same_bits(r.x1[v], s.x0[v]) ? 0 : 1;
        frozen += o == VertexOutcome::Frozen ? 1 : 0;
        carried += o == VertexOutcome::Carried ? 1 : 0;
        // In a zone exactly when moved by one (a vertex the whole-cloth freeze held is in none).
        const bool zoned = o != VertexOutcome::Fixed && o != VertexOutcome::Untouched &&
                           !(rep.froze_all && o == VertexOutcome::Frozen && r.zone[v] == kNoZone);
        zone_mismatch += zoned == (r.zone[v] != kNoZone) ? 0 : 1;
    }
    EXPECT_EQ(nonfinite, 0U);
    EXPECT_EQ(fixed_moved, 0U) << "vertices of inverse mass 0 moved";
    EXPECT_EQ(untouched_moved, 0U) << "vertices in no zone changed";
    EXPECT_EQ(frozen_off, 0U) << "frozen vertices not at x0";
    EXPECT_EQ(zone_mismatch, 0U);
    EXPECT_EQ(rep.frozen_vertices, frozen);
    EXPECT_EQ(rep.carried_vertices, carried);
}

/// Σ m (x1 − x0) over `vertices`.
inline Vec3d momentum(const Scene& s, const std::vector<Vec3d>& x1, const std::vector<std::uint32_t>& vertices) {
    Vec3d p{};
    for (std::uint32_t v : vertices) p += (1.0 / s.inverse_mass[v]) * (x1[v] - s.x0[v]);
    return p;
}

/// The cloth vertices of `c` far from the fixed mesh (more than 12 cm from the axis in x or z), and
/// how many of those the resolution left untouched, their x1 the prediction's to the bit.
struct FarRim {
    std::size_t far = 0, untouched = 0;
};
inline FarRim far_rim(const ClothOnFixedMesh& c, const Resolved& r) {
    const Scene& s = c.scene;
    FarRim rim;
    for (std::uint32_t v = c.cloth; v < c.fixed; ++v) {
        if (std::max(std::fabs(s.x0[v].x), std::fabs(s.x0[v].z)) < 0.12) continue;
        ++rim.far;
        rim.untouched += r.outcome[v] == VertexOutcome::Untouched && same_bits(r.x1[v], s.x1[v]) ? 1 : 0;
    }
    return rim;
}

/// The vertices of each rigid zone of `r`, by zone label.
inline std::map<std::uint32_t, std::vector<std::uint32_t>> rigid_zones(const Scene& s, const Resolved& r) {
    std::map<std::uint32_t, std::vector<std::uint32_t>> rigid;
    for (std::uint32_t v = 0; v < s.x0.size(); ++v)
        if (r.outcome[v] == VertexOutcome::Rigid) rigid[r.zone[v]].push_back(v);
    return rigid;
}

/// The largest change of a distance between two of `vertices` from x0 to the resolved x1, m.
inline double largest_distance_change(const Scene& s, const Resolved& r, const std::vector<std::uint32_t>& vertices) {
    double worst = 0.0;
    for (std::size_t i = 0; i < vertices.size(); ++i)
        for (std::size_t j = i + 1; j < vertices.size(); ++j) {
            const std::uint32_t a = vertices[i], b = vertices[j];
            worst = std::max(worst, std::fabs(physics::length(r.x1[a] - r.x1[b]) - physics::length(s.x0[a] - s.x0[b])));
        }
    return worst;
}

inline void print(const char* what, const Resolved& r) {
    const ImpactZoneReport& p = r.report;
    std::printf(
        "%s: resolved %d, rounds %d, zones %d (max %d vertices), constraints %d, rigid zones %d (%d rounds), frozen "
        "%d, carried %d, QP sweeps %lld (%d unconverged), detections %d, candidates %lld, CCD %lld tests / %lld hits; "
        "%.1f ms (broad %.1f, CCD %.1f, zones %.1f)\n",
        what, p.resolved ? 1 : 0, p.iterations, p.zones, p.max_zone_vertices, p.constraints, p.rigid_zones,
        p.rigid_rounds, p.frozen_vertices, p.carried_vertices, static_cast<long long>(p.qp_sweeps), p.qp_unconverged,
        p.detections, static_cast<long long>(p.candidate_pairs), static_cast<long long>(p.ccd_tests),
        static_cast<long long>(p.ccd_hits), r.ms, p.broad_phase_ms, p.ccd_ms, p.zones_ms);
}

}  // namespace weft::collision::test
