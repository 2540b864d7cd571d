// The energy guard's measurement and criterion (weft/backend/energy_audit.h; docs/methods.md §1b),
// on the host in double.
#include "weft/backend/energy_audit.h"

#include <algorithm>
#include <cmath>

#include "deterministic_parallel.h"
#include "weft/backend/backend.h"
#include "weft/backend/collider_shape.h"
#include "weft/backend/material_terms.h"
#include "weft/physics/aerodynamics.h"
#include "weft/physics/bending.h"
#include "shell_bending_energy.h"
#include "weft/physics/collider_contact.h"
#include "weft/physics/implicit_terms.h"
#include "weft/physics/membrane.h"

namespace weft {
namespace {

/// One chunk's share of the audit's sums.
struct Parts {
    double kinetic = 0.0, gravity = 0.0, contact = 0.0, power = 0.0, elastic = 0.0, pin_power = 0.0;
    double max_stretch_squared = 0.0;  // the square root is taken once, of the largest
};

std::size_t chunk_count(std::size_t n) { return (n + kParallelChunk - 1) / kParallelChunk; }

void add(EnergyAudit& a, double& pin_power, const Parts& p) {
    a.kinetic += p.kinetic;
    a.gravity += p.gravity;
    a.contact += p.contact;
    a.external_power += p.power;
    a.elastic += p.elastic;
    a.max_stretch = std::max(a.max_stretch, std::sqrt(p.max_stretch_squared));
    pin_power += p.pin_power;
}

struct ColliderNow {
    physics::Shape<double> shape;
    double friction;  // negative: the cloth's
    bool moving;
};

}  // namespace

EnergyAudit host_energy_audit(const Model& model, std::span<const std::vector<Vec3d>> x,
                              std::span<const std::vector<Vec3d>> v, double t, double h, bool with_wind) {
    EnergyAudit a;
    a.with_wind = with_wind;
    const WorldDesc& w = model.settings;
    std::vector<ColliderNow> colliders;
    for (const ColliderDesc& c : model.colliders) {
        // A mesh collider's contacts are the collision pipeline's springs and impact zones, which
        // hold no energy the audit can see; one that stands still does no work, one that moves does.
        if (!c.is_analytic()) {
            if (c.moves()) a.bounded = false;
            continue;
        }
        colliders.push_back({shape_at<double>(c, t), c.friction, !c.motion.is_static()});
    }
    const bool wind = with_wind && w.wind.active();
    double pin_power = 0.0;
    std::vector<char> moving_pin;  // per vertex of the current cloth: pinned to a motion that moves
    std::vector<Parts> parts;      // per chunk of the current loop
    for (std::size_t ci = 0; ci < model.cloths.size(); ++ci) {
        const ClothDesc& cloth = model.cloths[ci];
        const Fabric& f = *cloth.fabric;
        const std::span<const Vec3d> xc = x[ci], vc = v[ci];
        const MaterialTerms<double> p = material_terms<double>(cloth.material);

        moving_pin.assign(f.vertex_count(), 0);
        bool any_moving_pin = false;
        for (const PinDesc& pin : cloth.pins)
            if (pin.motion >= 0 && !model.motions[static_cast<std::size_t>(pin.motion)].is_static()) {
                moving_pin[pin.vertex] = 1;
                any_moving_pin = true;
            }
        std::vector<char> pinned;
        if (!colliders.empty()) {
            pinned.assign(f.vertex_count(), 0);
            for (const PinDesc& pin : cloth.pins) pinned[pin.vertex] = 1;
        }

        // Per chunk of vertices, then the chunks in order (deterministic_parallel.h): the same sums on
        // any number of threads.
        const std::size_t vertex_chunks = chunk_count(f.vertex_count());
        parts.assign(vertex_chunks, Parts{});
        parallel_chunks(f.vertex_count(), [&](std::size_t lo, std::size_t hi) {
            Parts& out = parts[lo / kParallelChunk];
            for (std::size_t i = lo; i < hi; ++i) {
                const double m = f.masses()[i];
                out.kinetic += 0.5 * m * physics::dot(vc[i], vc[i]);
                out.gravity -= m * physics::dot(w.gravity, xc[i]);
                // Pinned vertices get no collider terms in the solve (implicit_terms.h: vertex_terms).
                if (colliders.empty() || pinned[i]) continue;
                const double k = physics::collider_penalty_stiffness(w.solver.contact_stiffness, m, h * h);
                for (const ColliderNow& c : colliders) {
                    const double mu = c.friction >= 0.0 ? c.friction : p.friction;
                    const physics::ContactResult<double> r = physics::collider_contact(
                        c.shape, physics::ContactParams<double>{k, p.thickness, mu, 1e-3}, xc[i], vc[i],
                        physics::HessianKind::None);
                    if (!r.active) continue;
                    out.contact += r.energy;
                    if (c.moving) {
                        // Steady contact: |f|·|v_col|. Impact: a vertex struck by a collider moving at u
                        // leaves it at most at 2u − v (an elastic bounce off a heavy wall), a gain of at
                        // most 2m|u|(|u| + |v|); spread over the substep as a power, since the substep in
                        // which the penalty spring releases it is not known.
                        const double u = physics::length(physics::shape_point_velocity(c.shape, xc[i]));
                        out.power += physics::length(r.force) * u + 2.0 * m * u * (u + physics::length(vc[i])) / h;
                    }
                }
            }
        });
        for (const Parts& part : parts) add(a, pin_power, part);

        parts.assign(chunk_count(f.triangle_count()), Parts{});
        parallel_chunks(f.triangle_count(), [&](std::size_t lo, std::size_t hi) {
            Parts& out = parts[lo / kParallelChunk];
            for (std::size_t tri = lo; tri < hi; ++tri) {
                const auto& idx = f.triangles()[tri].v;
                const Vec3d xs[3] = {xc[idx[0]], xc[idx[1]], xc[idx[2]]};
                const TriangleRest& r = f.triangle_rest()[tri];
                const bool pin = any_moving_pin && (moving_pin[idx[0]] || moving_pin[idx[1]] || moving_pin[idx[2]]);
                Vec3d grad[3];
                out.elastic += physics::membrane_evaluate<double>(r.dm_inv, r.area, p.membrane, xs, pin ? grad : nullptr,
                                                                  nullptr, physics::HessianKind::None);
                out.max_stretch_squared = std::max(out.max_stretch_squared, physics::largest_stretch_squared<double>(r.dm_inv, xs));
                if (pin)
                    for (int k = 0; k < 3; ++k)
                        if (moving_pin[idx[k]]) out.pin_power += physics::dot(grad[k], vc[idx[k]]);
                if (wind && (p.drag > 0.0 || p.lift > 0.0)) {
                    // The solver's wind (implicit_terms.h: triangle_terms): mean plus the gust at the centroid.
                    Vec3d air = w.wind.velocity;
                    if (w.wind.turbulence > 0.0)
                        air += physics::wind_gust((xs[0] + xs[1] + xs[2]) / 3.0, t, w.wind.turbulence,
                                                  w.wind.turbulence_frequency, w.wind.turbulence_scale);
                    const Vec3d vs[3] = {vc[idx[0]], vc[idx[1]], vc[idx[2]]};
                    Vec3d per_vertex{};
                    physics::aerodynamic_force(xs, vs, air,
                                               physics::AeroCoefficients<double>{w.wind.air_density, p.drag, p.lift},
                                               per_vertex, static_cast<Mat3d*>(nullptr));
                    out.power += std::max(0.0, 3.0 * physics::dot(per_vertex, air));
                }
            }
        });
        for (const Parts& part : parts) add(a, pin_power, part);

        if (w.solver.face_contacts && !colliders.empty()) {
            // The triangles' centroid contacts (implicit_terms.h: face_collider_terms), as the
            // vertices' above: the penalty energy and a moving collider's power bound.
            parts.assign(chunk_count(f.triangle_count()), Parts{});
            parallel_chunks(f.triangle_count(), [&](std::size_t lo, std::size_t hi) {
                Parts& out = parts[lo / kParallelChunk];
                for (std::size_t tri = lo; tri < hi; ++tri) {
                    const auto& idx = f.triangles()[tri].v;
                    const Vec3d xm = (xc[idx[0]] + xc[idx[1]] + xc[idx[2]]) / 3.0;
                    const Vec3d vm = (vc[idx[0]] + vc[idx[1]] + vc[idx[2]]) / 3.0;
                    const double m = (f.masses()[idx[0]] + f.masses()[idx[1]] + f.masses()[idx[2]]) / 3.0;
                    const double k = physics::collider_penalty_stiffness(w.solver.contact_stiffness, m, h * h);
                    for (const ColliderNow& c : colliders) {
                        const double mu = c.friction >= 0.0 ? c.friction : p.friction;
                        const physics::ContactResult<double> r = physics::collider_contact(
                            c.shape, physics::ContactParams<double>{k, p.thickness, mu, 1e-3}, xm, vm,
                            physics::HessianKind::None);
                        if (!r.active) continue;
                        out.contact += r.energy;
                        if (c.moving) {
                            const double u = physics::length(physics::shape_point_velocity(c.shape, xm));
                            out.power += physics::length(r.force) * u + 2.0 * m * u * (u + physics::length(vm)) / h;
                        }
                    }
                }
            });
            for (const Parts& part : parts) add(a, pin_power, part);
        }

        if (p.bending > 0.0 && (w.solver.bending == BendingModel::Shell || w.solver.bending == BendingModel::MidEdge)) {
            // The models per triangle (shell_bending_energy.h); the mid-edge model's normals relaxed
            // at these positions, so that the audit sees min over ξ, the energy the solver descends.
            MidEdgeState midedge;
            const bool relaxed = w.solver.bending == BendingModel::MidEdge;
            if (relaxed) relax_midedge_normals(f, cloth.pins, xc, midedge);
            parts.assign(chunk_count(f.triangle_count()), Parts{});
            parallel_chunks(f.triangle_count(), [&](std::size_t lo, std::size_t hi) {
                Parts& out = parts[lo / kParallelChunk];
                for (std::size_t tri = lo; tri < hi; ++tri)
                    out.elastic += shell_bending_triangle(
                        f, tri, p.bending, xc,
                        [&](std::uint32_t vertex, const Vec3d& grad) {
                            if (any_moving_pin && moving_pin[vertex]) out.pin_power += physics::dot(grad, vc[vertex]);
                        },
                        relaxed ? &midedge : nullptr);
            });
            for (const Parts& part : parts) add(a, pin_power, part);
        } else if (p.bending > 0.0) {
            parts.assign(chunk_count(f.hinges().size()), Parts{});
            parallel_chunks(f.hinges().size(), [&](std::size_t lo, std::size_t hi) {
                Parts& out = parts[lo / kParallelChunk];
                for (std::size_t k = lo; k < hi; ++k) {
                    const Hinge& hg = f.hinges()[k];
                    const Vec3d xs[4] = {xc[hg.v[0]], xc[hg.v[1]], xc[hg.v[2]], xc[hg.v[3]]};
                    const bool pin = any_moving_pin && (moving_pin[hg.v[0]] || moving_pin[hg.v[1]] ||
                                                        moving_pin[hg.v[2]] || moving_pin[hg.v[3]]);
                    Vec3d grad[4];
                    out.elastic += physics::bending_evaluate<double>(p.bending, hg.weight, hg.rest_angle, xs,
                                                                     pin ? grad : nullptr, nullptr,
                                                                     physics::HessianKind::None);
                    if (pin)
                        for (int c = 0; c < 4; ++c)
                            if (moving_pin[hg.v[c]]) out.pin_power += physics::dot(grad[c], vc[hg.v[c]]);
                }
            });
            for (const Parts& part : parts) add(a, pin_power, part);
        }
    }
    a.external_power += std::max(0.0, pin_power);

    if (model.grab && model.grab->cloth < model.cloths.size()) {
        const VertexGrab& g = *model.grab;
        const ClothDesc& cloth = model.cloths[g.cloth];
        const bool pinned = std::any_of(cloth.pins.begin(), cloth.pins.end(),
                                        [&](const PinDesc& pin) { return pin.vertex == g.vertex; });
        if (!pinned && g.vertex < x[g.cloth].size()) {
            const Vec3d xg = x[g.cloth][g.vertex], vg = v[g.cloth][g.vertex];
            const Vec3d force = g.stiffness * (g.target - xg) - g.damping * vg;
            a.external_power += std::max(0.0, physics::dot(force, vg));
        }
    }
    return a;
}

double energy_excess(const EnergyAudit& start, const EnergyAudit& end, double h) {
    const double gained = end.total() - start.total();
    const double external = kEnergyGuardWorkFactor * h * std::max(start.external_power, end.external_power);
    const double scale = start.kinetic + start.elastic + start.contact + std::abs(end.gravity - start.gravity);
    const double excess = gained - external - kEnergyGuardSlack * scale - kEnergyGuardFloor;
    return excess > 0.0 ? excess : 0.0;
}

// The default for every backend: the state read back to the host (one copy of every cloth), then
// the host sums. A backend whose state lives on a device overrides it to sum there.
EnergyAudit Backend::energy_audit(const Model& model, double t, double h, bool with_wind) const {
    std::vector<std::vector<Vec3d>> x(model.cloths.size()), v(model.cloths.size());
    for (std::size_t c = 0; c < model.cloths.size(); ++c) {
        x[c].resize(model.cloths[c].fabric->vertex_count());
        v[c].resize(x[c].size());
        read_state(c, x[c], v[c]);
    }
    return host_energy_audit(model, x, v, t, h, with_wind);
}

}  // namespace weft
