#pragma once
// Scenes of the impact-zone tests, shared by the CPU reference's test (tests/solver/
// test_impact_zones.cpp) and the GPU's (tests/gpu/test_impact_zones_gpu.cpp): a scene is start and
// predicted end positions that collide, with masses and topology; brute_force_ccd is the judge that
// does not go through any broad phase.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "weft/mesh.h"
#include "weft/physics/ccd.h"

#include "collision/broad_phase.h"
#include "collision/impact_zones.h"

namespace weft::collision::test {

struct Scene {
    std::vector<Vec3d> x0, x1;
    std::vector<double> inverse_mass;
    std::vector<Triangle> triangles;
    std::vector<Edge> edges;
    double thickness = 1e-3;

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

}  // namespace weft::collision::test
