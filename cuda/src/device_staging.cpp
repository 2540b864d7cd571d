// The CUDA solver's parameter staging (see device_solver.cpp): one block per substep, filled on the
// host and copied to the device in one transfer before the substep's kernels read it. build() lays
// it out (StepParams, then cloths, shapes, shape friction, pin targets, and the shapes again at the
// substep's start); fill_staging() writes the substep's values.
#include "device_solver.h"

#include <algorithm>
#include <cstring>

#include "weft/backend/collider_shape.h"
#include "weft/physics/hessian.h"
#include "weft/physics/swept_collider.h"

namespace weft::cuda {
namespace {

std::uint32_t align16(std::size_t bytes) { return static_cast<std::uint32_t>((bytes + 15) / 16 * 16); }

V3 to_float(const Vec3d& a) { return {static_cast<float>(a.x), static_cast<float>(a.y), static_cast<float>(a.z)}; }

}  // namespace

void DeviceSolver::layout_staging(const Model& model) {
    // The per-substep parameter block: header, then cloths, shapes, shape friction, pin targets, and
    // the shapes again at the substep's start (for the swept test).
    StepParams& lp = layout_params_;
    lp = StepParams{};
    std::size_t offset = align16(sizeof(StepParams));
    lp.cloth_offset = static_cast<std::uint32_t>(offset);
    offset += align16(std::max<std::size_t>(1, model.cloths.size()) * sizeof(ClothParams));
    lp.shape_offset = static_cast<std::uint32_t>(offset);
    offset += align16(std::max<std::size_t>(1, model.colliders.size()) * sizeof(physics::Shape<float>));
    lp.friction_offset = static_cast<std::uint32_t>(offset);
    offset += align16(std::max<std::size_t>(1, model.colliders.size()) * sizeof(float));
    lp.pin_target_offset = static_cast<std::uint32_t>(offset);
    offset += align16(std::max<std::size_t>(1, flat_->pin_vertex.size()) * sizeof(V3));
    lp.shape_start_offset = static_cast<std::uint32_t>(offset);
    offset += align16(std::max<std::size_t>(1, model.colliders.size()) * sizeof(physics::Shape<float>));
    staging_.allocate(offset, ledger_, "parameters");
    host_staging_.allocate(offset);
    std::memset(host_staging_.get(), 0, offset);
}

void DeviceSolver::fill_staging(const Model& model, double t, double h, unsigned char* base) const {
    const WorldDesc& w = model.settings;
    StepParams p = layout_params_;
    p.h = static_cast<float>(h);
    p.h2 = static_cast<float>(h * h);
    p.time = static_cast<float>(t);
    p.hessian = static_cast<int>(w.solver.hessian == HessianMode::Projected ? physics::HessianKind::Projected
                                                                            : physics::HessianKind::Fast);
    p.gravity = to_float(w.gravity);
    p.wind_active = w.wind.active() ? 1 : 0;
    p.wind = to_float(w.wind.velocity);
    p.air_density = static_cast<float>(w.wind.air_density);
    p.turbulence = static_cast<float>(w.wind.turbulence);
    p.turbulence_frequency = static_cast<float>(w.wind.turbulence_frequency);
    p.turbulence_scale = static_cast<float>(w.wind.turbulence_scale);
    p.contact_stiffness = static_cast<float>(w.solver.contact_stiffness);
    p.shape_count = static_cast<int>(
        std::count_if(model.colliders.begin(), model.colliders.end(), [](const ColliderDesc& c) { return c.is_analytic(); }));
    p.bounded_shape_count = static_cast<int>(std::count_if(model.colliders.begin(), model.colliders.end(), [](const ColliderDesc& c) {
        return c.is_analytic() && c.shape != ColliderShape::Plane;
    }));
    p.correct_overshoots = moves_bounded_ ? 0 : 1;
    p.face_contacts = w.solver.face_contacts && p.shape_count > 0 ? 1 : 0;
    p.pin_count = static_cast<int>(flat_->pin_vertex.size());
    p.cg_max_iterations = w.solver.cg_max_iterations;
    p.cg_warm_start = w.solver.cg_warm_start ? 1 : 0;
    p.cg_eps2 = w.solver.cg_tolerance * w.solver.cg_tolerance;
    p.cg_energy_floor = cg_energy_floor(total_mass_, w.solver.cg_velocity_tolerance);
    p.grab_vertex = 0xFFFFFFFFu;
    if (model.grab && model.grab->cloth < model.cloths.size()) {
        if (part_ == nullptr) {
            p.grab_vertex = flat_->cloth_vertex_offset[model.grab->cloth] + model.grab->vertex;
        } else {  // part mode: the grabbed vertex's local id, where it is local at all
            const std::size_t global = whole_->cloth_vertex_offset[model.grab->cloth] + model.grab->vertex;
            if (global < local_of_global_.size()) p.grab_vertex = local_of_global_[global];
        }
        p.grab_target = to_float(model.grab->target);
        p.grab_stiffness = static_cast<float>(model.grab->stiffness);
        p.grab_damping = static_cast<float>(model.grab->damping);
    }
    std::memcpy(base, &p, sizeof(p));

    auto* cloths = reinterpret_cast<ClothParams*>(base + p.cloth_offset);
    for (std::size_t c = 0; c < model.cloths.size(); ++c) {
        cloths[c] = material_terms<float>(model.cloths[c].material);
    }
    // Colliders take their pose at the end of the substep, as on the CPU (cpu_solver.cpp); the swept
    // test also needs the pose at its start.
    const double t1 = t + h;
    auto* shapes = reinterpret_cast<physics::Shape<float>*>(base + p.shape_offset);
    auto* shapes_start = reinterpret_cast<physics::Shape<float>*>(base + p.shape_start_offset);
    auto* friction = reinterpret_cast<float*>(base + p.friction_offset);
    int analytic = 0;
    for (const ColliderDesc& c : model.colliders) {
        if (!c.is_analytic()) continue;  // mesh colliders: the collision stages (device_collisions.h)
        shapes[analytic] = shape_at<float>(c, t1);
        shapes_start[analytic] = shape_at<float>(c, t);
        friction[analytic] = static_cast<float>(c.friction);
        ++analytic;
    }
    // Pin targets at t + h, evaluated in double on the host (a handful of vertices).
    auto* targets = reinterpret_cast<V3*>(base + p.pin_target_offset);
    const FlatModel& f = *flat_;
    std::vector<Vec3d> host(f.pin_vertex.size());
    pin_targets(model, f, t1, host);
    for (std::size_t q = 0; q < host.size(); ++q) targets[q] = to_float(host[q]);
}

}  // namespace weft::cuda
