// Cloth inside a closed mesh collider (collision/closed_colliders.h).
#include "collision/closed_colliders.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <utility>

#include "deterministic_parallel.h"
#include "weft/physics/proximity.h"

namespace weft::collision {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// Triangles a cluster of a piece holds for the winding number's far field.
constexpr std::size_t kClusterTriangles = 16;

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
}

/// The signed solid angle of triangle (a, b, c) seen from p (Van Oosterom & Strackee 1983).
double solid_angle(Vec3d p, Vec3d a, Vec3d b, Vec3d c) {
    const Vec3d ra = a - p, rb = b - p, rc = c - p;
    const double la = math::length(ra), lb = math::length(rb), lc = math::length(rc);
    const double numerator = math::dot(ra, math::cross(rb, rc));
    const double denominator = la * lb * lc + math::dot(ra, rb) * lc + math::dot(ra, rc) * lb + math::dot(rb, rc) * la;
    return 2.0 * std::atan2(numerator, denominator);
}

struct Box {
    Vec3d lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
    Vec3d hi{-std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(), -std::numeric_limits<double>::max()};
    void add(Vec3d p) {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    [[nodiscard]] bool contains(Vec3d p) const {
        return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
    }
    [[nodiscard]] double distance(Vec3d p) const {
        const Vec3d d{std::max({lo.x - p.x, 0.0, p.x - hi.x}), std::max({lo.y - p.y, 0.0, p.y - hi.y}),
                      std::max({lo.z - p.z, 0.0, p.z - hi.z})};
        return math::length(d);
    }
    [[nodiscard]] double diagonal() const { return math::length(hi - lo); }
};

/// A run of a piece's triangles, with what the far field needs: its bounds, its area vector
/// Σ ½(b − a)×(c − a) and the area-weighted centre of its triangles.
struct Cluster {
    std::size_t first = 0, count = 0;  // into the piece's triangle list
    Box bounds;
    Vec3d area_vector{};
    Vec3d centre{};
};

/// A piece placed at the current positions: its bounds and its clusters.
struct PlacedPiece {
    Box bounds;
    std::vector<Cluster> clusters;
};

PlacedPiece place(const ClosedPiece& piece, std::span<const Triangle> triangles, std::span<const Vec3d> x) {
    PlacedPiece placed;
    for (std::size_t first = 0; first < piece.triangles.size(); first += kClusterTriangles) {
        Cluster c;
        c.first = first;
        c.count = std::min(kClusterTriangles, piece.triangles.size() - first);
        double area = 0.0;
        for (std::size_t k = first; k < first + c.count; ++k) {
            const Triangle& t = triangles[piece.triangles[k]];
            const Vec3d a = x[t.v[0]], b = x[t.v[1]], d = x[t.v[2]];
            c.bounds.add(a);
            c.bounds.add(b);
            c.bounds.add(d);
            const Vec3d n = 0.5 * math::cross(b - a, d - a);
            const double l = math::length(n);
            c.area_vector += n;
            c.centre += (l / 3.0) * (a + b + d);
            area += l;
        }
        c.centre = area > 0.0 ? c.centre / area : c.bounds.lo;
        placed.bounds.add(c.bounds.lo);
        placed.bounds.add(c.bounds.hi);
        placed.clusters.push_back(c);
    }
    return placed;
}

/// The winding number of a placed piece around p: clusters near p exactly, far ones by their dipole
/// (the far-field term of Barill et al. 2018), which errs by far less than the ±1/2 the inside test
/// needs once p is a cluster's diagonal away from its bounds.
double placed_winding_number(Vec3d p, const ClosedPiece& piece, const PlacedPiece& placed, std::span<const Triangle> triangles,
                             std::span<const Vec3d> x) {
    double omega = 0.0;
    for (const Cluster& c : placed.clusters) {
        if (c.bounds.distance(p) > c.bounds.diagonal()) {
            const Vec3d r = c.centre - p;
            const double l = math::length(r);
            omega += math::dot(c.area_vector, r) / (l * l * l);
            continue;
        }
        for (std::size_t k = c.first; k < c.first + c.count; ++k) {
            const Triangle& t = triangles[piece.triangles[k]];
            omega += solid_angle(p, x[t.v[0]], x[t.v[1]], x[t.v[2]]);
        }
    }
    return omega / (4.0 * kPi);
}

bool inside(double winding) { return std::abs(winding) > 0.5; }

}  // namespace

std::vector<ClosedPiece> find_closed_pieces(const CollisionGeometry& g) {
    const auto first_kinematic = static_cast<std::uint32_t>(g.cloth_vertices);
    const std::size_t nv = g.vertex_count();
    // Connected pieces of the kinematic triangles (shared vertices), by union-find.
    std::vector<std::uint32_t> parent(nv);
    std::iota(parent.begin(), parent.end(), 0U);
    std::vector<std::uint32_t> kinematic;
    for (std::uint32_t t = 0; t < g.triangles.size(); ++t) {
        const Triangle& tri = g.triangles[t];
        if (tri.v[0] < first_kinematic) continue;  // a cloth triangle
        kinematic.push_back(t);
        const std::uint32_t a = find_root(parent, tri.v[0]);
        for (int k = 1; k < 3; ++k) {
            const std::uint32_t b = find_root(parent, tri.v[k]);
            if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
    }
    std::map<std::uint32_t, ClosedPiece> pieces;  // by root: pieces come out in the order of their lowest vertex
    for (const std::uint32_t t : kinematic) pieces[find_root(parent, g.triangles[t].v[0])].triangles.push_back(t);
    std::vector<ClosedPiece> closed;
    for (auto& [root, piece] : pieces) {
        // Closed: every edge in exactly two of the piece's triangles.
        std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
        for (const std::uint32_t t : piece.triangles) {
            const Triangle& tri = g.triangles[t];
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t a = tri.v[k], b = tri.v[(k + 1) % 3];
                ++uses[{std::min(a, b), std::max(a, b)}];
            }
        }
        if (std::all_of(uses.begin(), uses.end(), [](const auto& e) { return e.second == 2; })) closed.push_back(std::move(piece));
    }
    return closed;
}

double winding_number(Vec3d p, std::span<const Triangle> triangles, std::span<const std::uint32_t> piece,
                      std::span<const Vec3d> x) {
    double omega = 0.0;
    for (const std::uint32_t t : piece) omega += solid_angle(p, x[triangles[t].v[0]], x[triangles[t].v[1]], x[triangles[t].v[2]]);
    return omega / (4.0 * kPi);
}

std::vector<Ejection> find_ejections(const CollisionGeometry& g, std::span<const ClosedPiece> pieces, std::span<const Vec3d> x,
                                     std::span<const Vec3d> kinematic_velocity, double gap) {
    if (pieces.empty()) return {};
    std::vector<PlacedPiece> placed;
    placed.reserve(pieces.size());
    for (const ClosedPiece& piece : pieces) placed.push_back(place(piece, g.triangles, x));
    const auto inside_any = [&](Vec3d p) {
        for (std::size_t k = 0; k < pieces.size(); ++k)
            if (placed[k].bounds.contains(p) && inside(placed_winding_number(p, pieces[k], placed[k], g.triangles, x))) return true;
        return false;
    };
    const std::size_t n = g.cloth_vertices;
    // Each chunk's finds in vertex order, then the chunks in order: only the few inside are stored.
    std::vector<std::vector<Ejection>> found((n + kParallelChunk - 1) / kParallelChunk);
    parallel_chunks(n, [&](std::size_t lo, std::size_t hi) {
        std::vector<std::size_t> holding;
        for (std::size_t i = lo; i < hi; ++i) {
            if (!(g.inverse_mass[i] > 0.0)) continue;  // pinned: its motion is prescribed
            const Vec3d p = x[i];
            holding.clear();
            for (std::size_t k = 0; k < pieces.size(); ++k)
                if (placed[k].bounds.contains(p) && inside(placed_winding_number(p, pieces[k], placed[k], g.triangles, x)))
                    holding.push_back(k);
            if (holding.empty()) continue;
            // Every face of the pieces holding p, nearest first; the first whose point outside lies in
            // no piece wins (where two pieces overlap, the nearest face may lead into the other).
            struct Candidate {
                double distance;
                std::uint32_t triangle;
                physics::PointTriangleProximity<double> q;
                double sign;
            };
            std::vector<Candidate> candidates;
            for (const std::size_t k : holding) {
                const double sign = placed_winding_number(p, pieces[k], placed[k], g.triangles, x) > 0.0 ? 1.0 : -1.0;
                for (const std::uint32_t t : pieces[k].triangles) {
                    const Triangle& tri = g.triangles[t];
                    const auto q = physics::point_triangle_proximity(p, x[tri.v[0]], x[tri.v[1]], x[tri.v[2]]);
                    candidates.push_back({q.distance, t, q, sign});
                }
            }
            std::stable_sort(candidates.begin(), candidates.end(),
                             [](const Candidate& a, const Candidate& b) { return a.distance < b.distance; });
            const auto ejection_at = [&](const Candidate& c) {
                const Triangle& tri = g.triangles[c.triangle];
                // Outward: from p to the surface (p is inside), or the face's normal where p is on it
                // (faces wound so that the inside counts +1 have (b − a)×(c − a) pointing out).
                Vec3d normal = c.q.distance > 0.0 ? -1.0 * c.q.normal : c.sign * c.q.normal;
                if (!(math::length(normal) > 0.0)) normal = Vec3d{0.0, 1.0, 0.0};
                Ejection e;
                e.vertex = static_cast<std::uint32_t>(i);
                e.position = c.q.closest + gap * normal;
                e.normal = normal;
                const double w0 = 1.0 - c.q.u - c.q.v;
                const auto velocity = [&](std::uint32_t v) { return kinematic_velocity[v - n]; };
                e.surface_velocity = w0 * velocity(tri.v[0]) + c.q.u * velocity(tri.v[1]) + c.q.v * velocity(tri.v[2]);
                return e;
            };
            Ejection chosen = ejection_at(candidates.front());
            for (const Candidate& c : candidates) {
                const Ejection e = ejection_at(c);
                if (inside_any(e.position)) continue;
                chosen = e;
                break;
            }
            found[lo / kParallelChunk].push_back(chosen);
        }
    });
    std::vector<Ejection> ejections;
    for (const std::vector<Ejection>& chunk : found) ejections.insert(ejections.end(), chunk.begin(), chunk.end());
    return ejections;
}

}  // namespace weft::collision
