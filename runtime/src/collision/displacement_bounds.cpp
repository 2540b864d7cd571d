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

    // d_v: the nearest partner of any primitive v belongs to, capped at r.
    std::vector<double>& nearest = out.bound;
    nearest.assign(in.x.size(), r);
    const auto limit = [&](std::uint32_t v, double d) { nearest[v] = std::min(nearest[v], d); };
    for (const VertexFacePair& p : pairs.vf) {
        const Triangle& t = in.triangles[p.triangle];
        const double d =
            physics::point_triangle_proximity(in.x[p.vertex], in.x[t.v[0]], in.x[t.v[1]], in.x[t.v[2]]).distance;
        limit(p.vertex, d);
        for (const std::uint32_t c : t.v) limit(c, d);
    }
    for (const EdgeEdgePair& p : pairs.ee) {
        const Edge &e = in.edges[p.a], &f = in.edges[p.b];
        const double d =
            physics::edge_edge_proximity(in.x[e.v[0]], in.x[e.v[1]], in.x[f.v[0]], in.x[f.v[1]]).distance;
        for (const std::uint32_t c : {e.v[0], e.v[1], f.v[0], f.v[1]}) limit(c, d);
    }
    out.vf_pairs = pairs.vf.size();
    out.ee_pairs = pairs.ee.size();
    out.limited_vertices = 0;
    for (double& b : nearest) {
        if (b < r) ++out.limited_vertices;
        b *= in.relaxation;
    }
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

}  // namespace weft::collision
