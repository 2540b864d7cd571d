// Per-vertex conservative displacement bounds and the truncation (displacement_bounds.h).
#include "collision/displacement_bounds.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <string>
#include <unordered_map>

#include "weft/error.h"
#include "weft/physics/proximity.h"

namespace weft::collision {

void compute_displacement_bounds(const DisplacementBoundsInput& in, BroadPhase& hash, DisplacementBounds& out) {
    const std::size_t n = in.x.size();
    const bool per_vertex = !in.radius.empty();
    if (per_vertex && in.radius.size() != n)
        throw Error("displacement bounds: " + std::to_string(in.radius.size()) + " query radii for " +
                    std::to_string(n) + " vertices");
    const double r = in.query_radius;
    if (!per_vertex && (!(r > 0.0) || !std::isfinite(r)))
        throw Error("displacement bounds: query radius " + std::to_string(r) + " m (must be > 0)");
    for (std::size_t v = 0; per_vertex && v < n; ++v)
        if (!(in.radius[v] > 0.0) || !std::isfinite(in.radius[v]))
            throw Error("displacement bounds: vertex " + std::to_string(v) + " has query radius " +
                        std::to_string(in.radius[v]) + " m (must be > 0)");
    if (!(in.relaxation > 0.0 && in.relaxation < 0.5))
        throw Error("displacement bounds: relaxation " + std::to_string(in.relaxation) + " (must lie in (0, 0.5))");
    const auto radius_of = [&](std::uint32_t v) { return per_vertex ? in.radius[v] : r; };
    // One radius: boxes grown by r/2 on each side overlap along every axis when the primitives are
    // within r. Per vertex: each primitive grows by the largest radius of its vertices, so a pair
    // within the larger of its two radii always overlaps (BroadPhaseInput::vertex_padding).
    BroadPhaseInput query;
    query.x0 = in.x;
    query.x1 = in.x;
    query.triangles = in.triangles;
    query.edges = in.edges;
    query.self_pairs = in.self_pairs;
    query.triangle_cloth = in.triangle_group;
    query.vertex_patch = in.vertex_patch;
    query.edge_patch = in.edge_patch;
    query.triangle_patch = in.triangle_patch;
    query.count_culled = false;
    if (per_vertex)
        query.vertex_padding = in.radius;
    else
        query.thickness = 0.5 * r;
    hash.find(query, out.pairs);
    const BroadPhaseResult& pairs = out.pairs;

    // d_v: the nearest partner of any primitive v belongs to, capped at r_v; and, for the planar
    // variant, each (vertex, partner) measured with the direction towards the partner.
    std::vector<double>& nearest = out.bound;
    nearest.resize(n);
    for (std::size_t v = 0; v < n; ++v) nearest[v] = radius_of(static_cast<std::uint32_t>(v));
    struct Entry {
        std::uint32_t vertex;
        PartnerLimit limit;
    };
    std::vector<Entry> entries;
    const auto add = [&](std::uint32_t v, double d, Vec3d towards) {
        nearest[v] = std::min(nearest[v], d);
        entries.push_back({v, {towards, in.relaxation * d}});
    };
    // A pair counts when it is within the largest radius of its vertices (the broad phase's boxes
    // are a superset).
    const auto measured = [&](double d, std::initializer_list<std::uint32_t> vertices) {
        double largest = 0.0;
        for (const std::uint32_t v : vertices) largest = std::max(largest, radius_of(v));
        return d < largest;
    };
    out.vf_distance.resize(pairs.vf.size());
    out.ee_distance.resize(pairs.ee.size());
    out.vf_pairs = out.ee_pairs = 0;
    for (std::size_t k = 0; k < pairs.vf.size(); ++k) {
        const VertexFacePair& p = pairs.vf[k];
        const Triangle& t = in.triangles[p.triangle];
        // The normal points from the face's closest point to the vertex.
        const auto prox = physics::point_triangle_proximity(in.x[p.vertex], in.x[t.v[0]], in.x[t.v[1]], in.x[t.v[2]]);
        out.vf_distance[k] = prox.distance;
        if (!measured(prox.distance, {p.vertex, t.v[0], t.v[1], t.v[2]})) continue;
        ++out.vf_pairs;
        add(p.vertex, prox.distance, -1.0 * prox.normal);
        for (const std::uint32_t c : t.v) add(c, prox.distance, prox.normal);
    }
    for (std::size_t k = 0; k < pairs.ee.size(); ++k) {
        const EdgeEdgePair& p = pairs.ee[k];
        const Edge &e = in.edges[p.a], &f = in.edges[p.b];
        // The normal points from f's closest point to e's.
        const auto prox = physics::edge_edge_proximity(in.x[e.v[0]], in.x[e.v[1]], in.x[f.v[0]], in.x[f.v[1]]);
        out.ee_distance[k] = prox.distance;
        if (!measured(prox.distance, {e.v[0], e.v[1], f.v[0], f.v[1]})) continue;
        ++out.ee_pairs;
        for (const std::uint32_t c : e.v) add(c, prox.distance, -1.0 * prox.normal);
        for (const std::uint32_t c : f.v) add(c, prox.distance, prox.normal);
    }
    out.limited_vertices = 0;
    out.reach.resize(n);
    for (std::size_t v = 0; v < n; ++v) {
        const double rv = radius_of(static_cast<std::uint32_t>(v));
        if (nearest[v] < rv) ++out.limited_vertices;
        nearest[v] *= in.relaxation;
        out.reach[v] = in.relaxation * rv;
    }
    // Group the partners by vertex, each vertex's in pair order (a stable counting sort).
    out.partner_start.assign(n + 1, 0);
    for (const Entry& e : entries) ++out.partner_start[e.vertex + 1];
    for (std::size_t v = 0; v < n; ++v) out.partner_start[v + 1] += out.partner_start[v];
    out.partners.resize(entries.size());
    std::vector<std::uint32_t> fill(out.partner_start.begin(), out.partner_start.end() - 1);
    for (const Entry& e : entries) out.partners[fill[e.vertex]++] = e.limit;
}

bool patches_hold(std::span<const std::uint32_t> before, std::span<const std::uint32_t> after) {
    if (before.size() != after.size())
        throw Error("patches_hold: " + std::to_string(before.size()) + " ids before, " + std::to_string(after.size()) +
                    " after");
    // Each culled patch must map to exactly one certified patch.
    std::unordered_map<std::uint32_t, std::uint32_t> image;
    for (std::size_t p = 0; p < before.size(); ++p) {
        if (before[p] == kNoPatch) continue;
        if (after[p] == kNoPatch) return false;
        const auto [it, inserted] = image.emplace(before[p], after[p]);
        if (!inserted && it->second != after[p]) return false;
    }
    return true;
}

double kept_share(const DisplacementBounds& b, std::size_t v, Vec3d move, bool planar) {
    const double length = math::length(move);
    if (!planar) return length > b.bound[v] ? b.bound[v] / length : 1.0;
    // The largest share t of the move that keeps every limit.
    double t = length > b.reach[v] ? b.reach[v] / length : 1.0;
    for (std::uint32_t k = b.partner_start[v]; k < b.partner_start[v + 1]; ++k) {
        const double advance = math::dot(move, b.partners[k].towards);
        if (advance > 0.0 && t * advance > b.partners[k].limit) t = b.partners[k].limit / advance;
    }
    return t;
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
    if (x0.size() != x1.size() || b.partner_start.size() != x0.size() + 1 || b.reach.size() != x0.size())
        throw Error("truncate_displacements_planar: " + std::to_string(x0.size()) + " start positions, " +
                    std::to_string(x1.size()) + " end positions, bounds for " +
                    std::to_string(b.partner_start.empty() ? 0 : b.partner_start.size() - 1) + " vertices");
    std::size_t truncated = 0;
    for (std::size_t v = 0; v < x0.size(); ++v) {
        const Vec3d move = x1[v] - x0[v];
        const double t = kept_share(b, v, move, true);
        if (t < 1.0) {
            x1[v] = x0[v] + t * move;
            ++truncated;
        }
    }
    return truncated;
}

}  // namespace weft::collision
