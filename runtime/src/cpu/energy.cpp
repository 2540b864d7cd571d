#include "cpu/energy.h"

#include "weft/physics/bending.h"
#include "weft/physics/membrane.h"
#include "shell_bending_energy.h"

namespace weft::cpu {

EnergyBreakdown cloth_energy(const ClothDesc& cloth, const WorldDesc& world, std::span<const Vec3d> x,
                             std::span<const Vec3d> v) {
    EnergyBreakdown e;
    const Fabric& f = *cloth.fabric;
    for (std::size_t i = 0; i < f.vertex_count(); ++i) {
        e.kinetic += 0.5 * f.masses()[i] * physics::dot(v[i], v[i]);
        e.gravity -= f.masses()[i] * physics::dot(world.gravity, x[i]);
    }
    const auto mat = physics::membrane_material(cloth.material.stretch_stiffness, cloth.material.poisson_ratio);
    for (std::size_t t = 0; t < f.triangle_count(); ++t) {
        const auto& tri = f.triangles()[t].v;
        const Vec3d xs[3] = {x[tri[0]], x[tri[1]], x[tri[2]]};
        const TriangleRest& r = f.triangle_rest()[t];
        e.membrane += physics::membrane_evaluate<double>(r.dm_inv, r.area, mat, xs, nullptr, nullptr,
                                                         physics::HessianKind::None);
    }
    if (world.solver.bending == BendingModel::Shell) {
        for (std::size_t t = 0; t < f.triangle_count(); ++t)
            e.bending += shell_bending_triangle(f, t, cloth.material.bending_stiffness, x, [](std::uint32_t, const Vec3d&) {});
        return e;
    }
    if (world.solver.bending == BendingModel::MidEdge) {
        MidEdgeState midedge;
        relax_midedge_normals(f, cloth.pins, x, midedge);
        for (std::size_t t = 0; t < f.triangle_count(); ++t)
            e.bending +=
                shell_bending_triangle(f, t, cloth.material.bending_stiffness, x, [](std::uint32_t, const Vec3d&) {}, &midedge);
        return e;
    }
    for (const Hinge& h : f.hinges()) {
        const Vec3d xs[4] = {x[h.v[0]], x[h.v[1]], x[h.v[2]], x[h.v[3]]};
        e.bending += physics::bending_evaluate<double>(cloth.material.bending_stiffness, h.weight, h.rest_angle, xs,
                                                       nullptr, nullptr, physics::HessianKind::None);
    }
    return e;
}

}  // namespace weft::cpu
