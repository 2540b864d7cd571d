#pragma once
// The mid-edge bending model's normals (SolverSettings::bending = MidEdge; weft/physics/midedge_bending.h):
// the turns ξ (one per hinge) that minimise the bending energy at given hinge angles, for the CPU
// solver (before each assembly) and the host's energy accounts (the energy guard's audit). Jacobi-
// preconditioned CG on K_ξξ·ξ = −b in double, from ξ = 0: a function of the angles alone, so the
// same positions give the same ξ (no state to checkpoint) and the same bits on any thread count
// (deterministic_parallel.h).

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "deterministic_parallel.h"
#include "weft/cloth.h"
#include "weft/fabric.h"
#include "weft/physics/bending.h"
#include "weft/physics/midedge_bending.h"
#include "weft/types.h"

namespace weft {

/// How the last solve went (the solver reports it in its stats).
struct MidEdgeSolveReport {
    int iterations = 0;
    double relative_residual = 0.0;  ///< |K·ξ + b| / |b| at exit (0 for b = 0)
    bool converged = true;
};


/// Scratch kept between solves, so that a step allocates nothing after the first.
struct MidEdgeScratch {
    std::vector<double> b, diag, r, z, p, q, partials;
};

/// Solves for ξ (rad, one per hinge; 0 for hinges without one) given each triangle's `faces[t]`
/// (angles, scales, sides; weft/physics/midedge_bending.h), its condensed rest data `rest[t]`
/// (midedge_condensed_rest) and each hinge's two triangles `hinge_faces[h]` (−1: none).
inline MidEdgeSolveReport solve_midedge_normals(std::span<const physics::MidEdgeFace<double>> faces,
                                                std::span<const physics::ShellBendingRest<double>> rest,
                                                std::span<const std::array<std::int32_t, 2>> hinge_faces, std::span<double> xi,
                                                MidEdgeScratch& s) {
    const std::size_t nh = hinge_faces.size();
    MidEdgeSolveReport report;
    s.b.assign(nh, 0.0);
    s.diag.assign(nh, 0.0);
    s.r.resize(nh);
    s.z.resize(nh);
    s.p.resize(nh);
    s.q.resize(nh);
    for (std::size_t h = 0; h < nh; ++h) xi[h] = 0.0;
    // One hinge's row of the product K·v (or of b, with the angles and v = 0), gathered from its
    // two triangles in a fixed order.
    const auto row = [&](std::size_t h, const std::vector<double>* v, bool with_angles) {
        double sum = 0.0;
        for (const std::int32_t t : hinge_faces[h]) {
            if (t < 0) continue;
            const auto& f = faces[static_cast<std::size_t>(t)];
            int k = -1;
            double local[3]{};
            for (int l = 0; l < 3; ++l) {
                if (f.hinge[l] == static_cast<std::int32_t>(h)) k = l;
                if (v != nullptr && f.side[l] != 0.0) local[l] = (*v)[static_cast<std::size_t>(f.hinge[l])];
            }
            if (k < 0 || f.side[k] == 0.0) continue;
            const auto& r = rest[static_cast<std::size_t>(t)];
            sum += r.area * physics::midedge_xi_gradient(f, r, local, k, with_angles);
        }
        return sum;
    };
    parallel_chunks(nh, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t h = lo; h < hi; ++h) {
            s.b[h] = row(h, nullptr, true);
            double d = 0.0;
            for (const std::int32_t t : hinge_faces[h]) {
                if (t < 0) continue;
                const auto& f = faces[static_cast<std::size_t>(t)];
                for (int k = 0; k < 3; ++k)
                    if (f.hinge[k] == static_cast<std::int32_t>(h) && f.side[k] != 0.0)
                        d += 4.0 * rest[static_cast<std::size_t>(t)].area * rest[static_cast<std::size_t>(t)].m[k][k];
            }
            s.diag[h] = d;
            s.r[h] = d > 0.0 ? -s.b[h] : 0.0;
            s.z[h] = d > 0.0 ? s.r[h] / d : 0.0;
            s.p[h] = s.z[h];
        }
    });
    const auto dot = [&](const std::vector<double>& u, const std::vector<double>& v) {
        return deterministic_sum(nh, s.partials, [&](std::size_t lo, std::size_t hi) {
            double sum = 0.0;
            for (std::size_t h = lo; h < hi; ++h) sum += u[h] * v[h];
            return sum;
        });
    };
    const double bb = dot(s.r, s.r);
    if (!(bb > 0.0)) return report;
    double rz = dot(s.r, s.z);
    double rr = bb;
    const double stop = physics::kMidEdgeTolerance * physics::kMidEdgeTolerance * bb;
    while (rr > stop && report.iterations < physics::kMidEdgeMaxIterations) {
        parallel_chunks(nh, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t h = lo; h < hi; ++h) s.q[h] = s.diag[h] > 0.0 ? row(h, &s.p, false) : 0.0;
        });
        const double pq = dot(s.p, s.q);
        if (!(pq > 0.0)) break;
        const double alpha = rz / pq;
        parallel_chunks(nh, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t h = lo; h < hi; ++h) {
                xi[h] += alpha * s.p[h];
                s.r[h] -= alpha * s.q[h];
                s.z[h] = s.diag[h] > 0.0 ? s.r[h] / s.diag[h] : 0.0;
            }
        });
        rr = dot(s.r, s.r);
        const double rz_next = dot(s.r, s.z);
        const double beta = rz_next / rz;
        rz = rz_next;
        parallel_chunks(nh, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t h = lo; h < hi; ++h) s.p[h] = s.z[h] + beta * s.p[h];
        });
        ++report.iterations;
    }
    report.relative_residual = std::sqrt(rr / bb);
    report.converged = rr <= stop;
    return report;
}

/// Each hinge's (up to) two triangles, from the triangles' hinges (−1: none).
inline void midedge_hinge_faces(std::span<const TriangleHinges> triangle_hinges, std::size_t hinge_count,
                                std::vector<std::array<std::int32_t, 2>>& out) {
    out.assign(hinge_count, {-1, -1});
    for (std::size_t t = 0; t < triangle_hinges.size(); ++t)
        for (const std::int32_t k : triangle_hinges[t].edge)
            if (k >= 0) {
                auto& f = out[static_cast<std::size_t>(k)];
                (f[0] < 0 ? f[0] : f[1]) = static_cast<std::int32_t>(t);
            }
}

/// Each triangle's rest data for the mid-edge model: the shell model's `shell_rest` with its boundary
/// edges' normals condensed out (weft/physics/midedge_bending.h).
inline void midedge_rest(std::span<const physics::ShellBendingRest<double>> shell_rest, std::span<const TriangleHinges> triangle_hinges,
                         std::vector<physics::ShellBendingRest<double>>& out) {
    out.resize(shell_rest.size());
    for (std::size_t t = 0; t < shell_rest.size(); ++t) {
        bool present[3];
        for (int k = 0; k < 3; ++k) present[k] = triangle_hinges[t].edge[k] >= 0;
        out[t] = physics::midedge_condensed_rest(shell_rest[t], present);
    }
}

/// Fills `faces` (one per triangle) at positions `x_at(vertex)` (m): each hinge's angle θ − θ̄
/// (`angle`: scratch, one per hinge), the sides, and the clamp: an edge of a triangle whose three
/// corners are pinned (`pinned(vertex)`) keeps that triangle's normal, so that triangle reads it with
/// scale 0, the other with scale 2, and the edge has no ξ.
template <typename PositionAt, typename PinnedAt>
void midedge_faces(std::span<const Triangle> triangles, std::span<const TriangleHinges> triangle_hinges, std::span<const Hinge> hinges,
                   PositionAt&& x_at, PinnedAt&& pinned, std::vector<double>& angle, std::vector<physics::MidEdgeFace<double>>& faces) {
    angle.resize(hinges.size());
    faces.resize(triangles.size());
    parallel_chunks(hinges.size(), [&](std::size_t lo, std::size_t hi) {
        for (std::size_t h = lo; h < hi; ++h) {
            Vec3d p[4];
            for (int a = 0; a < 4; ++a) p[a] = x_at(hinges[h].v[a]);
            angle[h] = physics::detail::wrap_angle(physics::dihedral_angle(p) - hinges[h].rest_angle);
        }
    });
    const auto all_pinned = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) { return pinned(a) && pinned(b) && pinned(c); };
    parallel_chunks(triangles.size(), [&](std::size_t lo, std::size_t hi) {
        for (std::size_t t = lo; t < hi; ++t) {
            physics::MidEdgeFace<double> f;
            const auto& v = triangles[t].v;
            const bool self_pinned = all_pinned(v[0], v[1], v[2]);
            for (int k = 0; k < 3; ++k) {
                const std::int32_t h = triangle_hinges[t].edge[k];
                f.hinge[k] = h;
                if (h < 0) {
                    f.side[k] = 0.0;
                    continue;
                }
                const Hinge& hg = hinges[static_cast<std::size_t>(h)];
                f.angle[k] = angle[static_cast<std::size_t>(h)];
                // The hinge's triangles are (v0, v1, v2) and (v1, v0, v3).
                const bool clamped = all_pinned(hg.v[0], hg.v[1], hg.v[2]) || all_pinned(hg.v[0], hg.v[1], hg.v[3]);
                if (clamped) {
                    f.side[k] = 0.0;
                    f.scale[k] = self_pinned ? 0.0 : 2.0;
                } else {
                    f.side[k] = physics::midedge_side(v[k], hg.v[0]);
                }
            }
            faces[t] = f;
        }
    });
}

/// Everything the mid-edge model needs at one state, kept between calls (no allocation after the
/// first): the faces, the rest data, each hinge's triangles, the angles and the normals' turns ξ.
struct MidEdgeState {
    std::vector<physics::MidEdgeFace<double>> faces;
    std::vector<physics::ShellBendingRest<double>> rest;
    std::vector<std::array<std::int32_t, 2>> hinge_faces;
    std::vector<double> angle, xi;
    MidEdgeScratch scratch;
    MidEdgeSolveReport report;
    const Fabric* source = nullptr;  ///< whose rest data `rest` holds
    std::vector<char> pinned;        ///< per vertex, for the overload that takes a cloth's pins

    /// Triangle t's reading of its hinges at the solved ξ (for shell_bending_evaluate).
    [[nodiscard]] physics::ShellReading<double> reading(std::size_t t) const {
        const auto& f = faces[t];
        double local[3]{};
        for (int k = 0; k < 3; ++k)
            if (f.side[k] != 0.0) local[k] = xi[static_cast<std::size_t>(f.hinge[k])];
        return physics::midedge_reading(f, local);
    }
};

/// The mid-edge model of one fabric at positions `x` (the fabric's vertices, m), its pinned vertices
/// `pinned(vertex)`: fills `state` (rest data on the first call) and solves ξ.
template <typename PinnedAt>
void relax_midedge_normals(const Fabric& fabric, std::span<const Vec3d> x, PinnedAt&& pinned, MidEdgeState& state) {
    if (state.source != &fabric || state.rest.size() != fabric.triangle_count()) {
        state.source = &fabric;
        std::vector<physics::ShellBendingRest<double>> shell(fabric.triangle_count());
        const auto rest_x = fabric.rest_positions();
        for (std::size_t t = 0; t < fabric.triangle_count(); ++t) {
            const auto& v = fabric.triangles()[t].v;
            (void)physics::shell_bending_rest(rest_x[v[0]], rest_x[v[1]], rest_x[v[2]], shell[t]);
        }
        midedge_rest(shell, fabric.triangle_hinges(), state.rest);
        midedge_hinge_faces(fabric.triangle_hinges(), fabric.hinges().size(), state.hinge_faces);
    }
    midedge_faces(fabric.triangles(), fabric.triangle_hinges(), fabric.hinges(), [&](std::uint32_t i) { return x[i]; }, pinned,
                  state.angle, state.faces);
    state.xi.resize(fabric.hinges().size());
    state.report = solve_midedge_normals(state.faces, state.rest, state.hinge_faces, state.xi, state.scratch);
}

/// The same for a cloth's fabric and its pins (the energy accounts' form).
inline void relax_midedge_normals(const Fabric& fabric, std::span<const PinDesc> pins, std::span<const Vec3d> x, MidEdgeState& state) {
    state.pinned.assign(fabric.vertex_count(), 0);
    for (const PinDesc& pin : pins) state.pinned[pin.vertex] = 1;
    relax_midedge_normals(fabric, x, [&](std::uint32_t i) { return state.pinned[i] != 0; }, state);
}

}  // namespace weft
