// Per-vertex conservative displacement bounds and the truncation (displacement_bounds.h).
#include "collision/displacement_bounds.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "weft/error.h"
#include "weft/physics/proximity.h"

namespace weft::collision {

void compute_displacement_bounds(const DisplacementBoundsInput& in, BroadPhase& hash, DisplacementBounds& out) {
    const double r = in.query_radius;
    if (!(r > 0.0) || !std::isfinite(r))
        throw Error("displacement bounds: query radius " + std::to_string(r) + " m (must be > 0)");
    if (!(in.relaxation > 0.0 && in.relaxation < 0.5))
        throw Error("displacement bounds: relaxation " + std::to_string(in.relaxation) + " (must lie in (0, 0.5))");
    // Boxes grown by r/2 on each side overlap along every axis when the primitives are within r.
    BroadPhaseInput query;
    query.x0 = in.x;
    query.x1 = in.x;
    query.triangles = in.triangles;
    query.edges = in.edges;
    query.thickness = 0.5 * r;
    BroadPhaseResult pairs;
    hash.find(query, pairs);

    // d_v: the nearest partner of any primitive v belongs to, capped at r; and, for the planar
    // variant, each (vertex, partner) within r with the direction towards the partner.
    std::vector<double>& nearest = out.bound;
    nearest.assign(in.x.size(), r);
    struct Entry {
        std::uint32_t vertex;
        PartnerLimit limit;
    };
    std::vector<Entry> entries;
    const auto add = [&](std::uint32_t v, double d, Vec3d towards) {
        nearest[v] = std::min(nearest[v], d);
        if (d < r) entries.push_back({v, {towards, in.relaxation * d}});
    };
    for (const VertexFacePair& p : pairs.vf) {
        const Triangle& t = in.triangles[p.triangle];
        // The normal points from the face's closest point to the vertex.
        const auto prox = physics::point_triangle_proximity(in.x[p.vertex], in.x[t.v[0]], in.x[t.v[1]], in.x[t.v[2]]);
        add(p.vertex, prox.distance, -1.0 * prox.normal);
        for (const std::uint32_t c : t.v) add(c, prox.distance, prox.normal);
    }
    for (const EdgeEdgePair& p : pairs.ee) {
        const Edge &e = in.edges[p.a], &f = in.edges[p.b];
        // The normal points from f's closest point to e's.
        const auto prox = physics::edge_edge_proximity(in.x[e.v[0]], in.x[e.v[1]], in.x[f.v[0]], in.x[f.v[1]]);
        for (const std::uint32_t c : e.v) add(c, prox.distance, -1.0 * prox.normal);
        for (const std::uint32_t c : f.v) add(c, prox.distance, prox.normal);
    }
    out.vf_pairs = pairs.vf.size();
    out.ee_pairs = pairs.ee.size();
    out.limited_vertices = 0;
    for (double& b : nearest) {
        if (b < r) ++out.limited_vertices;
        b *= in.relaxation;
    }
    out.cap = in.relaxation * r;
    // Group the partners by vertex, each vertex's in pair order (a stable counting sort).
    out.partner_start.assign(in.x.size() + 1, 0);
    for (const Entry& e : entries) ++out.partner_start[e.vertex + 1];
    for (std::size_t v = 0; v < in.x.size(); ++v) out.partner_start[v + 1] += out.partner_start[v];
    out.partners.resize(entries.size());
    std::vector<std::uint32_t> fill(out.partner_start.begin(), out.partner_start.end() - 1);
    for (const Entry& e : entries) out.partners[fill[e.vertex]++] = e.limit;
}

std::size_t truncate_displacements(std::span<const Vec3d> x0, std::span<Vec3d> x1, std::span<const double> bound) {
    if (x0.size() != x1.size() || x0.size() != bound.size())
        throw Error("truncate_displacements: " + std::to_string(x0.size()) + " start positions, " +
                    std::to_string(x1.size()) + " end positions and " + std::to_string(bound.size()) + " bounds");
    std::size_t truncated = 0;
    for (std::size_t v = 0; v < x0.size(); ++v) {
        const Vec3d move = x1[v] - x0[v];
        const double length = math::length(move);
        if (length > bound[v]) {
            x1[v] = x0[v] + (bound[v] / length) * move;
            ++truncated;
        }
    }
    return truncated;
}

std::size_t truncate_displacements_planar(std::span<const Vec3d> x0, std::span<Vec3d> x1, const DisplacementBounds& b) {
    if (x0.size() != x1.size() || b.partner_start.size() != x0.size() + 1)
        throw Error("truncate_displacements_planar: " + std::to_string(x0.size()) + " start positions, " +
                    std::to_string(x1.size()) + " end positions, bounds for " +
                    std::to_string(b.partner_start.empty() ? 0 : b.partner_start.size() - 1) + " vertices");
    std::size_t truncated = 0;
    for (std::size_t v = 0; v < x0.size(); ++v) {
        const Vec3d move = x1[v] - x0[v];
        const double length = math::length(move);
        // The largest share t of the move that keeps every limit.
        double t = length > b.cap ? b.cap / length : 1.0;
        for (std::uint32_t k = b.partner_start[v]; k < b.partner_start[v + 1]; ++k) {
            const double advance = math::dot(move, b.partners[k].towards);
            if (advance > 0.0 && t * advance > b.partners[k].limit) t = b.partners[k].limit / advance;
        }
        if (t < 1.0) {
            x1[v] = x0[v] + t * move;
            ++truncated;
        }
    }
    return truncated;
}

}  // namespace weft::collision
