#pragma once
// The energy of the bending models per triangle (SolverSettings::bending = Shell and MidEdge;
// weft/physics/shell_bending.h, midedge_bending.h) over a fabric, for the host's energy accounts (the
// energy guard's audit, cpu/energy.cpp): one triangle at a time, in double.

#include <cstddef>
#include <span>

#include "midedge_normals.h"
#include "weft/fabric.h"
#include "weft/physics/shell_bending.h"

namespace weft {

/// Triangle `t` of `fabric` at positions `x` (the fabric's vertices, m) with plate stiffness
/// `stiffness` (N·m): returns its bending energy (J) and calls `gradient(vertex, ∂E/∂x_vertex)` for
/// every vertex of its hinges (a vertex in several hinges gets several calls; they add up).
/// `midedge`: the mid-edge model, its normals relaxed at `x` (relax_midedge_normals); null for the
/// shell model.
template <typename Gradient>
double shell_bending_triangle(const Fabric& fabric, std::size_t t, double stiffness, std::span<const Vec3d> x, Gradient&& gradient,
                              const MidEdgeState* midedge = nullptr) {
    const auto& v = fabric.triangles()[t].v;
    const auto rest_x = fabric.rest_positions();
    physics::ShellBendingRest<double> rest;
    if (!physics::shell_bending_rest(rest_x[v[0]], rest_x[v[1]], rest_x[v[2]], rest)) return 0.0;
    physics::ShellReading<double> reading;
    if (midedge != nullptr) {
        rest = midedge->rest[t];
        reading = midedge->reading(t);
    }
    const TriangleHinges& th = fabric.triangle_hinges()[t];
    bool present[3];
    Vec3d p[3][4];
    double rest_angle[3];
    for (int k = 0; k < 3; ++k) {
        present[k] = th.edge[k] >= 0;
        const Hinge* h = present[k] ? &fabric.hinges()[static_cast<std::size_t>(th.edge[k])] : nullptr;
        rest_angle[k] = h != nullptr ? h->rest_angle : 0.0;
        for (int a = 0; a < 4; ++a) p[k][a] = h != nullptr ? x[h->v[a]] : Vec3d{};
    }
    const physics::ShellBendingTerms<double> terms = physics::shell_bending_evaluate(stiffness, rest, present, p, rest_angle,
                                                                                         midedge != nullptr ? &reading : nullptr);
    for (int k = 0; k < 3; ++k)
        if (terms.active[k] && terms.force_angle[k] != 0.0)
            for (int a = 0; a < 4; ++a)
                gradient(fabric.hinges()[static_cast<std::size_t>(th.edge[k])].v[a], terms.force_angle[k] * terms.dtheta[k][a]);
    return terms.energy;
}

}  // namespace weft
