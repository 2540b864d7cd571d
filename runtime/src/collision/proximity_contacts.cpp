// Proximity contacts of one substep from the broad-phase candidates (see proximity_contacts.h).
#include "collision/proximity_contacts.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "deterministic_parallel.h"
#include "weft/error.h"
#include "weft/physics/proximity.h"

namespace weft::collision {
namespace {

/// True when the pair's vertices all belong to one cloth and lie within rest_exclusion × thickness of
/// each other in its rest shape: fabric neighbours, not surfaces in contact.
bool rest_neighbours(const ProximityInput& in, const std::uint32_t (&ids)[4], int first_side, double thickness) {
    if (!(in.rest_exclusion > 0.0) || in.rest.empty()) return false;
    for (const std::uint32_t v : ids)
        if (v >= in.rest.size()) return false;
    if (in.vertex_cloth[ids[0]] != in.vertex_cloth[ids[3]]) return false;
    const auto& r = in.rest;
    const Vec3d x[4] = {r[ids[0]], r[ids[1]], r[ids[2]], r[ids[3]]};
    const double distance = physics::pair_closest_points(first_side == 2, x).distance;
    return distance < in.rest_exclusion * thickness;
}

/// Builds the contact of one candidate from its four vertices and weights; false when it is not a
/// contact (too far at both ends, or nothing can move).
/// `first_side` vertices (1 for vertex–face, 2 for edge–edge) belong to the first primitive.
bool make_contact(const ProximityInput& in, const std::uint32_t (&ids)[4], const double (&w)[4], int first_side,
                  Vec3d normal, double gap0, ProximityContact& c) {
    double inverse_effective_mass = 0.0, movable_weight = 0.0;
    double thickness_a = 0.0, thickness_b = 0.0, friction_a = 0.0, friction_b = 0.0;
    Vec3d predicted{};
    for (int i = 0; i < 4; ++i) {
        const std::uint32_t v = ids[i];
        inverse_effective_mass += w[i] * w[i] * in.inverse_mass[v];
        if (in.inverse_mass[v] > 0.0) movable_weight += std::abs(w[i]);
        predicted += w[i] * in.x1[v];
        double& thickness_side = i < first_side ? thickness_a : thickness_b;
        double& friction_side = i < first_side ? friction_a : friction_b;
        thickness_side = std::max(thickness_side, in.thickness[v]);
        friction_side = std::max(friction_side, in.friction[v]);
    }
    if (!(inverse_effective_mass > 0.0) || !(movable_weight >= kMinMovableContactWeight)) return false;
    const double thickness = in.thickness_override > 0.0 ? in.thickness_override : std::max(thickness_a, thickness_b);
    if (in.offset_bound.empty()) {
        const double gap1 = dot(normal, predicted);
        if (!(std::min(gap0, gap1) < thickness)) return false;
    } else {
        // The most the gap can shrink: each primitive moves at most as far as its farthest vertex.
        double reach_a = 0.0, reach_b = 0.0;
        for (int i = 0; i < 4; ++i) {
            double& reach = i < first_side ? reach_a : reach_b;
            reach = std::max(reach, in.offset_bound[ids[i]]);
        }
        if (!(gap0 - (reach_a + reach_b) < thickness)) return false;
    }
    if (rest_neighbours(in, ids, first_side, thickness)) return false;
    for (int i = 0; i < 4; ++i) {
        c.vertex[i] = ids[i];
        c.weight[i] = w[i];
    }
    c.normal = normal;
    c.gap = gap0;
    c.thickness = thickness;
    c.stiffness = in.stiffness_override > 0.0 ? in.stiffness_override : 100.0 / (inverse_effective_mass * in.h * in.h);
    c.friction = 0.5 * (friction_a + friction_b);
    c.edge_edge = first_side == 2;
    return true;
}

}  // namespace

void find_proximity_contacts(const ProximityInput& in, std::vector<ProximityContact>& out) {
    const std::size_t n = in.x0.size();
    if (in.x1.size() != n || in.inverse_mass.size() != n || in.thickness.size() != n || in.friction.size() != n)
        throw Error("find_proximity_contacts: per-vertex arrays differ in size (" + std::to_string(n) + " positions)");
    if (!in.rest.empty() && in.vertex_cloth.size() != in.rest.size())
        throw Error("find_proximity_contacts: " + std::to_string(in.rest.size()) + " rest positions but " +
                    std::to_string(in.vertex_cloth.size()) + " cloth ids");
    if (!in.offset_bound.empty() && in.offset_bound.size() != n)
        throw Error("find_proximity_contacts: " + std::to_string(in.offset_bound.size()) + " displacement bounds for " +
                    std::to_string(n) + " vertices");
    if (!(in.h > 0.0)) throw Error("find_proximity_contacts: substep must be positive, got " + std::to_string(in.h));
    const std::size_t nvf = in.vf.size();
    const std::size_t total = nvf + in.ee.size();
    out.resize(total);
    std::vector<std::uint8_t> keep(total, 0);
    parallel_chunks(total, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t k = lo; k < hi; ++k) {
            std::uint32_t ids[4];
            const bool edge_edge = k >= nvf;
            if (!edge_edge) {
                const VertexFacePair& p = in.vf[k];
                const Triangle& t = in.triangles[p.triangle];
                ids[0] = p.vertex;
                ids[1] = t.v[0];
                ids[2] = t.v[1];
                ids[3] = t.v[2];
            } else {
                const EdgeEdgePair& p = in.ee[k - nvf];
                const Edge& e = in.edges[p.a];
                const Edge& f = in.edges[p.b];
                ids[0] = e.v[0];
                ids[1] = e.v[1];
                ids[2] = f.v[0];
                ids[3] = f.v[1];
            }
            const Vec3d x[4] = {in.x0[ids[0]], in.x0[ids[1]], in.x0[ids[2]], in.x0[ids[3]]};
            const physics::PairClosestPoints<double> c = physics::pair_closest_points(edge_edge, x);
            keep[k] = make_contact(in, ids, c.weight, edge_edge ? 2 : 1, c.normal, c.distance, out[k]) ? 1 : 0;
        }
    });
    // Stable compaction: the contacts keep the candidates' order.
    std::size_t m = 0;
    for (std::size_t k = 0; k < total; ++k)
        if (keep[k]) out[m++] = out[k];
    out.resize(m);
}

}  // namespace weft::collision
