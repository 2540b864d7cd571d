// One implicit substep on the CPU. The math of every element lives in weft/physics/ and is shared
// with the CUDA backend; this file only orders the work and makes it deterministic.
#include "cpu/cpu_solver.h"

#include <atomic>
#include <chrono>
#include <cstring>
#include <cmath>
#include <utility>

#include "weft/backend/collider_shape.h"
#include "weft/backend/cg_energy_stop.h"
#include "weft/backend/energy_audit.h"
#include "weft/error.h"
#include "weft/backend/timing.h"
#include "weft/physics/aerodynamics.h"
#include "weft/physics/swept_collider.h"

namespace weft::cpu {
namespace {

using Clock = std::chrono::steady_clock;

template <typename T>
physics::Vec3<T> to(Vec3d a) {
    return a.template cast<T>();
}

template <typename T>
physics::Mat3<T> to(const Mat3d& a) {
    return a.template cast<T>();
}

}  // namespace

template <typename T>
void CpuSolver<T>::build(const FlatModel& flat, const Model& model) {
    flat_ = &flat;
    n_ = flat.vertex_count;
    x_.resize(n_);
    v_.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) {
        x_[i] = to<T>(flat.initial_positions[i]);
        v_[i] = to<T>(flat.initial_velocities[i]);
    }
    x0_ = x_;
    v0_ = v_;
    vk_.assign(n_, V3{});
    wk_.assign(n_, V3{});
    mass_.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) mass_[i] = static_cast<T>(flat.mass[i]);
    total_mass_ = flat.total_mass();
    triangle_rest_.resize(flat.triangle_count());
    for (std::size_t t = 0; t < flat.triangle_count(); ++t) {
        const TriangleRest& r = flat.triangle_rest[t];
        for (int a = 0; a < 2; ++a)
            for (int b = 0; b < 2; ++b) triangle_rest_[t].dm_inv[a][b] = static_cast<T>(r.dm_inv[a][b]);
        triangle_rest_[t].area = static_cast<T>(r.area);
    }
    hinge_rest_.resize(flat.hinge_count());
    for (std::size_t k = 0; k < flat.hinge_count(); ++k)
        hinge_rest_[k] = {static_cast<T>(flat.hinges[k].weight), static_cast<T>(flat.hinges[k].rest_angle)};
    shell_rest_.resize(flat.triangle_count());
    hinge_faces_.assign(flat.hinge_count(), {-1, -1});
    for (std::size_t t = 0; t < flat.triangle_count(); ++t) {
        const physics::ShellBendingRest<double>& r = flat.shell_rest[t];
        shell_rest_[t].area = static_cast<T>(r.area);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) shell_rest_[t].m[a][b] = static_cast<T>(r.m[a][b]);
        for (const std::int32_t k : flat.triangle_hinges[t].edge)
            if (k >= 0) {
                auto& faces = hinge_faces_[static_cast<std::size_t>(k)];
                (faces[0] < 0 ? faces[0] : faces[1]) = static_cast<std::int32_t>(t);
            }
    }
    shell_faces_.clear();  // allocated on the first substep that asks for the model
    midedge_.rest.clear();  // the mid-edge model's too (and its rest data rebuilt for this model)
    element_rhs_.assign(3 * flat.triangle_count() + 4 * flat.hinge_count(), V3{});
    element_blocks_.assign(9 * flat.triangle_count() + 16 * flat.hinge_count(), M3{});
    vertex_rhs_.assign(n_, V3{});
    vertex_blocks_.assign(n_, M3{});
    b_.assign(n_, V3{});
    dv_.assign(n_, V3{});
    dv_previous_.assign(n_, V3{});
    pin_velocity_.assign(n_, V3{});
    fixed_.assign(n_, 0);
    for (std::uint32_t v : flat.pin_vertex) fixed_[v] = 1;
    contacts_.assign(n_, 0);
    face_contact_.assign(flat_->triangle_count(), 0);
    A_.resize(flat.pattern);
    pcg_.resize(n_);
    schwarz_ = SchwarzPreconditioner<T>{};  // levels rebuilt on first use, for this topology
    schwarz_factored_ = false;
    substep_count_ = 0;
    collisions_.build(flat, model);
}

template <typename T>
void CpuSolver<T>::prepare_parameters(const Model& model, double t, double h) {
    const WorldDesc& w = model.settings;
    hessian_ = w.solver.hessian == HessianMode::Projected ? physics::HessianKind::Projected : physics::HessianKind::Fast;
    bending_ = w.solver.bending;
    face_contacts_ = w.solver.face_contacts;
    gravity_ = to<T>(w.gravity);
    wind_.active = w.wind.active();
    wind_.velocity = to<T>(w.wind.velocity);
    wind_.air_density = static_cast<T>(w.wind.air_density);
    wind_.turbulence = static_cast<T>(w.wind.turbulence);
    wind_.turbulence_frequency = static_cast<T>(w.wind.turbulence_frequency);
    wind_.turbulence_scale = static_cast<T>(w.wind.turbulence_scale);
    wind_.time = static_cast<T>(t);
    contact_stiffness_ = static_cast<T>(w.solver.contact_stiffness);
    grab_vertex_ = n_;
    if (model.grab && model.grab->cloth < model.cloths.size()) {
        const VertexGrab& g = *model.grab;
        grab_vertex_ = flat_->cloth_vertex_offset[g.cloth] + g.vertex;
        grab_.target = to<T>(g.target);
        grab_.stiffness = static_cast<T>(g.stiffness);
        grab_.damping = static_cast<T>(g.damping);
    }

    cloth_params_.resize(model.cloths.size());
    for (std::size_t c = 0; c < model.cloths.size(); ++c) {
        cloth_params_[c] = material_terms<T>(model.cloths[c].material);
    }

    // Colliders take their pose at the end of the substep: the cloth must be clear of them then.
    const double t1 = t + h;
    shapes_.clear();
    shapes_start_.clear();
    shape_friction_.clear();
    for (const ColliderDesc& c : model.colliders) {
        if (!c.is_analytic()) continue;  // mesh colliders go through the collision pipeline
        shapes_.push_back(shape_at<T>(c, t1));
        shapes_start_.push_back(shape_at<T>(c, t));
        shape_friction_.push_back(static_cast<T>(c.friction));
    }

    // Pins: the velocity that lands each pinned vertex on its target at t + h.
    const FlatModel& f = *flat_;
    pin_targets_.resize(f.pin_vertex.size());
    pin_targets(model, f, t1, pin_targets_);
    for (std::size_t p = 0; p < f.pin_vertex.size(); ++p) {
        const std::uint32_t v = f.pin_vertex[p];
        const Vec3d x = x_[v].template cast<double>();
        pin_velocity_[v] = to<T>((pin_targets_[p] - x) / h);
    }
}

template <typename T>
void CpuSolver<T>::evaluate_elements(const Model& model, double /*t*/, T h) {
    (void)model;
    const FlatModel& f = *flat_;
    const std::size_t nt = f.triangle_count();
    const physics::ImplicitStep<T> step{h, h * h};
    const physics::HessianKind kind = hessian_;
    const physics::ColliderSet<T> colliders{shapes_.data(), shape_friction_.data(), static_cast<int>(shapes_.size()),
                                            contact_stiffness_};
    const bool faces = face_contacts_ && !shapes_.empty();
    std::atomic<int> face_contacts{0};  // an integer count: the same on any number of threads
    if (!faces && face_contacts_active_ > 0) std::fill(face_contact_.begin(), face_contact_.end(), std::uint8_t{0});
    // Each element's terms (weft/physics/implicit_terms.h) are written straight into its own slots
    // of the element buffers; assemble() gathers them per row in a fixed order.
    parallel_chunks(nt, [&](std::size_t lo, std::size_t hi) {
        int active = 0;
        for (std::size_t t = lo; t < hi; ++t) {
            const auto& tri = f.triangles[t].v;
            V3 x[3], vk[3], d[3];
            for (int a = 0; a < 3; ++a) {
                x[a] = x0_[tri[a]] + h * wk_[tri[a]];
                vk[a] = vk_[tri[a]];
                d[a] = vk[a] - wk_[tri[a]];
            }
            const TriangleRestT& r = triangle_rest_[t];
            physics::ElementTermsView<T, 3> out{&element_rhs_[3 * t], &element_blocks_[9 * t]};
            const physics::MaterialCoefficients<T>& p = cloth_params_[f.triangle_cloth[t]];
            physics::triangle_terms(step, r.dm_inv, r.area, p, wind_, x, vk, d, kind, out);
            if (faces) {
                const T mass = (mass_[tri[0]] + mass_[tri[1]] + mass_[tri[2]]) / T(3);
                const int face = physics::face_collider_terms(step, colliders, p, mass, x, vk, d, kind, out);
                face_contact_[t] = face > 0 ? 1 : 0;
                active += face;
            }
        }
        face_contacts += active;
    });
    face_contacts_active_ = face_contacts.load();
    const std::size_t nh = f.hinge_count();
    if (bending_ == BendingModel::Shell || bending_ == BendingModel::MidEdge) {
        evaluate_shell_bending(h);
        return;
    }
    parallel_chunks(nh, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t k = lo; k < hi; ++k) {
            const auto& hv = f.hinges[k].v;
            V3 x[4], vk[4], d[4];
            for (int a = 0; a < 4; ++a) {
                x[a] = x0_[hv[a]] + h * wk_[hv[a]];
                vk[a] = vk_[hv[a]];
                d[a] = vk[a] - wk_[hv[a]];
            }
            physics::ElementTermsView<T, 4> out{&element_rhs_[3 * nt + 4 * k], &element_blocks_[9 * nt + 16 * k]};
            if (!physics::hinge_terms(step, hinge_rest_[k].weight, hinge_rest_[k].rest_angle,
                                      cloth_params_[f.hinge_cloth[k]], x, vk, d, kind, out)) {
                // No bending stiffness: the hinge adds nothing (its slots are still gathered).
                for (int a = 0; a < 4; ++a) out.rhs[a] = V3{};
                for (int a = 0; a < 16; ++a) out.block[a] = M3{};
            }
        }
    });
}

template <typename T>
void CpuSolver<T>::evaluate_shell_bending(T h) {
    // cpu/shell_bending_terms.h: pass 1 per triangle, pass 2 into each hinge's element slots.
    const FlatModel& f = *flat_;
    const std::size_t nt = f.triangle_count(), nh = f.hinge_count();
    x_lin_.resize(n_);
    d_lin_.resize(n_);
    shell_faces_.resize(nt);
    parallel_chunks(n_, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i) {
            x_lin_[i] = x0_[i] + h * wk_[i];
            d_lin_[i] = vk_[i] - wk_[i];
        }
    });
    const auto hinge_at = [&](std::int32_t k) -> const Hinge& { return f.hinges[static_cast<std::size_t>(k)]; };
    const auto rest_angle_at = [&](std::int32_t k) { return hinge_rest_[static_cast<std::size_t>(k)].rest_angle; };
    const bool midedge = bending_ == BendingModel::MidEdge;
    if (midedge) {
        // The normals relaxed at the linearisation point (midedge_normals.h), in double.
        if (midedge_.rest.size() != nt) {
            midedge_rest(f.shell_rest, f.triangle_hinges, midedge_.rest);
            midedge_.hinge_faces = hinge_faces_;
            midedge_rest_.resize(nt);
            for (std::size_t t = 0; t < nt; ++t) {
                midedge_rest_[t].area = static_cast<T>(midedge_.rest[t].area);
                for (int a = 0; a < 3; ++a)
                    for (int b = 0; b < 3; ++b) midedge_rest_[t].m[a][b] = static_cast<T>(midedge_.rest[t].m[a][b]);
            }
        }
        midedge_faces(f.triangles, f.triangle_hinges, f.hinges, [&](std::uint32_t i) {
                          const V3& p = x_lin_[i];
                          return Vec3d{static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)};
                      },
                      [&](std::uint32_t i) { return fixed_[i] != 0; }, midedge_.angle, midedge_.faces);
        midedge_.xi.resize(nh);
        midedge_.report = solve_midedge_normals(midedge_.faces, midedge_.rest, midedge_.hinge_faces, midedge_.xi, midedge_.scratch);
        if (!midedge_.report.converged) ++midedge_not_converged_;
    }
    parallel_chunks(nt, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t t = lo; t < hi; ++t) {
            const ClothParams& p = cloth_params_[f.triangle_cloth[t]];
            if (!(p.bending > T(0))) {
                shell_faces_[t] = ShellFaceTerms<T>{};
                continue;
            }
            if (midedge) {
                const physics::ShellReading<double> rd = midedge_.reading(t);
                physics::ShellReading<T> reading;
                for (int k = 0; k < 3; ++k) {
                    reading.scale[k] = static_cast<T>(rd.scale[k]);
                    reading.offset[k] = static_cast<T>(rd.offset[k]);
                }
                shell_faces_[t] = shell_face_terms<T>(h, p.bending, p.damping_stiffness, midedge_rest_[t], f.triangle_hinges[t], hinge_at,
                                                      rest_angle_at, x_lin_.data(), vk_.data(), d_lin_.data(), &reading);
            } else {
                shell_faces_[t] = shell_face_terms<T>(h, p.bending, p.damping_stiffness, shell_rest_[t], f.triangle_hinges[t], hinge_at,
                                                      rest_angle_at, x_lin_.data(), vk_.data(), d_lin_.data());
            }
        }
    });
    parallel_chunks(nh, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t k = lo; k < hi; ++k) {
            V3* rhs = &element_rhs_[3 * nt + 4 * k];
            M3* block = &element_blocks_[9 * nt + 16 * k];
            for (int a = 0; a < 4; ++a) rhs[a] = V3{};
            for (int a = 0; a < 16; ++a) block[a] = M3{};
            for (const std::int32_t face : hinge_faces_[k])
                if (face >= 0)
                    shell_hinge_slots<T>(static_cast<std::int32_t>(k), shell_faces_[static_cast<std::size_t>(face)], hinge_at, rhs,
                                         block);
        }
    });
}

template <typename T>
int CpuSolver<T>::evaluate_vertices(const Model& model, T h) {
    (void)model;
    const FlatModel& f = *flat_;
    const physics::ImplicitStep<T> step{h, h * h};
    const physics::HessianKind kind = hessian_;
    const physics::ColliderSet<T> colliders{shapes_.data(), shape_friction_.data(), static_cast<int>(shapes_.size()),
                                            contact_stiffness_};
    const double contacts = deterministic_sum(n_, partials_, [&](std::size_t lo, std::size_t hi) {
        double count = 0.0;
        for (std::size_t i = lo; i < hi; ++i) {
            const physics::VertexIterate<T> v{mass_[i], x0_[i], v0_[i], vk_[i], wk_[i], fixed_[i] != 0};
            const int active = physics::vertex_terms(step, v, cloth_params_[f.vertex_cloth[i]], gravity_, colliders,
                                                     i == grab_vertex_, grab_, kind, vertex_rhs_[i], vertex_blocks_[i]);
            contacts_[i] = active;
            count += active;
        }
        return count;
    });
    return static_cast<int>(contacts);
}

template <typename T>
void CpuSolver<T>::collider_contact_vertices(std::size_t first, std::size_t count, std::vector<std::uint32_t>& out) const {
    out.clear();
    if (first + count > contacts_.size()) return;  // not built
    std::vector<std::uint8_t> touching(count, 0);
    for (std::size_t i = 0; i < count; ++i) touching[i] = contacts_[first + i] > 0 ? 1 : 0;
    if (face_contacts_active_ > 0)
        for (std::size_t t = 0; t < face_contact_.size(); ++t) {
            if (face_contact_[t] == 0) continue;
            for (const std::uint32_t v : flat_->triangles[t].v)
                if (v >= first && v < first + count) touching[v - first] = 1;
        }
    for (std::size_t i = 0; i < count; ++i)
        if (touching[i] != 0) out.push_back(static_cast<std::uint32_t>(i));
}

template <typename T>
void CpuSolver<T>::assemble() {
    const FlatModel& f = *flat_;
    const auto& rs = f.pattern.row_start;
    const auto& diag = f.pattern.diagonal;
    parallel_chunks(n_, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i) {
            V3 rhs = vertex_rhs_[i];
            for (std::uint32_t e = f.vertex_force_start[i]; e < f.vertex_force_start[i + 1]; ++e)
                rhs += element_rhs_[f.vertex_force_index[e]];
            b_[i] = rhs;
            for (std::uint32_t s = rs[i]; s < rs[i + 1]; ++s) {
                M3 block = s == diag[i] ? vertex_blocks_[i] : M3{};
                for (std::uint32_t e = f.slot_block_start[s]; e < f.slot_block_start[s + 1]; ++e)
                    block += element_blocks_[f.slot_block_index[e]];
                A_.set_block(s, block);
            }
        }
    });
}

template <typename T>
std::pair<int, int> CpuSolver<T>::sweep_fast_colliders(T h, bool correct_overshoots) {
    // Vertices a fast collider ran into during the substep ride along with it; slow ones that ended
    // inside a collider go back onto its surface (swept_collider.h). Slow colliders cost two distance
    // queries per vertex. Each vertex writes only itself; the counts are integers (any order).
    const FlatModel& f = *flat_;
    std::atomic<int> carried{0}, overshoots{0};
    parallel_chunks(n_, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i) {
            if (fixed_[i]) continue;
            const T thickness = cloth_params_[f.vertex_cloth[i]].thickness;
            for (std::size_t s = 0; s < shapes_.size(); ++s) {
                const physics::SweptContact<T> c =
                    physics::swept_shape_contact(shapes_start_[s], shapes_[s], h, x0_[i], x_[i], thickness);
                if (!c.hit || (c.samples == 0 && !correct_overshoots)) continue;
                x_[i] = c.position;
                v_[i] = (x_[i] - x0_[i]) / h;
                (c.samples > 0 ? carried : overshoots).fetch_add(1, std::memory_order_relaxed);
            }
        }
    });
    return {carried.load(), overshoots.load()};
}

template <typename T>
void CpuSolver<T>::substep(const Model& model, double t, double h_double, StepStats& stats) {
    const T h = static_cast<T>(h_double);
    const long long substep_index = substep_count_++;
    auto clock = Clock::now();
    x0_ = x_;
    v0_ = v_;
    vk_ = v_;
    std::fill(wk_.begin(), wk_.end(), V3{});
    prepare_parameters(model, t, h_double);
    stats.ms(Stage::Kinematics) += ms_since(clock);
    if (collisions_.stale(model)) collisions_.build(*flat_, model);  // self-collision toggled live
    const bool collide = collisions_.active();
    if (collide && collisions_.begin_substep(model, t, h_double, x0_, v0_, dv_previous_, stats) > 0) {
        x_ = x0_;  // vertices inside a closed mesh collider were moved out: the substep starts there
        v_ = v0_;
        vk_ = v_;
    }
    ContactTerms<T>* contacts = collide ? &collisions_.terms() : has_test_contacts_ ? &test_contacts_ : nullptr;
    const std::span<const V3> kinematic_x1 = collide ? collisions_.kinematic_x1() : std::span<const V3>(test_kinematic_x1_);
    const std::span<const V3> kinematic_v = collide ? collisions_.kinematic_v() : std::span<const V3>(test_kinematic_v_);

    const SolverSettings& solver = model.settings.solver;
    // Offset contact: every Newton update is truncated to the displacement bounds, and a rerun of the
    // detection adds one more Newton iteration (docs/methods.md §7b).
    const bool offset = collide && collisions_.offset();
    int newton_iterations = solver.newton_iterations;
    for (int newton = 0; newton < newton_iterations; ++newton) {
        clock = Clock::now();
        evaluate_elements(model, t, h);
        stats.collider_contacts = evaluate_vertices(model, h) + face_contacts_active_;
        stats.cg_not_converged += std::exchange(midedge_not_converged_, 0);  // the mid-edge normals' solve
        if (contacts != nullptr) contacts->evaluate(h, x0_, wk_, vk_, kinematic_x1, kinematic_v);
        stats.ms(Stage::Forces) += ms_since(clock);

        clock = Clock::now();
        assemble();
        if (contacts != nullptr) contacts->add_rhs(b_);
        // Filtered vertices get their prescribed change z = v_target − v_k. The rest start at 0, or in
        // the first Newton iteration from the last substep's velocity change (warm start).
        const bool warm = solver.cg_warm_start && newton == 0;
        const auto start_solve = [&] {
            for (std::size_t i = 0; i < n_; ++i)
                dv_[i] = fixed_[i] ? pin_velocity_[i] - vk_[i] : (warm ? dv_previous_[i] : V3{});
        };
        start_solve();
        stats.ms(Stage::Assembly) += ms_since(clock);

        clock = Clock::now();
        SchwarzPreconditioner<T>* schwarz = nullptr;
        // `auto`: the Schwarz preconditioner from kAutoSchwarzMinVerticesCpu vertices, where its fewer
        // iterations outweigh their cost on the CPU (about 3.4 Jacobi iterations each; docs/results.md).
        const bool schwarz_on = solver.preconditioner == Preconditioner::Schwarz ||
                                (solver.preconditioner == Preconditioner::Auto && n_ >= kAutoSchwarzMinVerticesCpu);
        if (schwarz_on) {
            if (!schwarz_.built()) {  // once per build: the levels depend on the topology only
                schwarz_levels_ = build_schwarz_hierarchy(flat_->initial_positions, flat_->pattern);
                schwarz_.build(schwarz_levels_, flat_->pattern);
            }
            // Refactored every Newton iteration, or (preconditioner_refresh = k > 1) in the first
            // Newton iteration of every k-th substep.
            const int k = solver.preconditioner_refresh;
            if (!schwarz_factored_ || k <= 1 || (newton == 0 && substep_index % k == 0)) {
                const bool with_contacts = contacts != nullptr && contacts->size() > 0;
                schwarz_.factor(A_, fixed_, [&](std::size_t i) { return with_contacts ? contacts->diagonal(i) : M3{}; });
                schwarz_factored_ = true;
                stats.preconditioner_pivot_failures += schwarz_.pivot_failures();
            }
            schwarz = &schwarz_;
            stats.ms(Stage::Precondition) += ms_since(clock);
            clock = Clock::now();
        }
        pcg_.set_energy_floor(cg_energy_floor(total_mass_, solver.cg_velocity_tolerance));
        PcgResult r = pcg_.solve(SystemOperator<T>{A_, contacts}, b_, fixed_, dv_, solver.cg_tolerance,
                                 solver.cg_max_iterations, schwarz);
        if (r.preconditioner_failed) {
            // The Schwarz preconditioner lost definiteness in this precision (rᵀM⁻¹r came out negative):
            // solved again from the same start with block-Jacobi, whose 3×3 diagonal blocks are SPD
            // wherever A is. Counted (StepStats::cg_preconditioner_fallbacks).
            ++stats.cg_preconditioner_fallbacks;
            stats.cg_iterations += r.iterations;
            start_solve();
            r = pcg_.solve(SystemOperator<T>{A_, contacts}, b_, fixed_, dv_, solver.cg_tolerance, solver.cg_max_iterations);
        }
        stats.cg_iterations += r.iterations;
        stats.cg_iterations_max = std::max(stats.cg_iterations_max, r.iterations);
        stats.cg_residual = std::max(stats.cg_residual, r.relative_residual);
        if (!r.converged) ++stats.cg_not_converged;
        ++stats.newton_iterations;
        stats.ms(Stage::Solve) += ms_since(clock);

        clock = Clock::now();
        if (solver.line_search) stats.line_search_halvings += line_search(model, t + h_double, h);
        parallel_chunks(n_, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t i = lo; i < hi; ++i) vk_[i] += dv_[i];
        });
        stats.ms(Stage::Update) += ms_since(clock);
        if (offset) {
            collisions_.truncate(model, h_double, x0_, vk_, stats);
            if (newton + 1 == newton_iterations && collisions_.wants_redetection(model)) {
                collisions_.redetect(model, h_double, x0_, vk_, stats);
                ++newton_iterations;
            }
        }
        wk_ = vk_;
    }

    clock = Clock::now();
    // Commit x = x0 + h·v and check every value: a NaN or Inf rolls the substep back and is reported.
    // A free vertex faster than kRunawaySpeed (a runaway solve) is reported too, and the substep
    // goes on without the solve: every vertex keeps its start velocity (pins their prescribed one),
    // and the collision stages below still sweep that motion against the colliders, which moved on.
    const double runaway2 = kRunawaySpeed * kRunawaySpeed;
    std::atomic<bool> runaway{false};
    const double bad = deterministic_sum(n_, partials_, [&](std::size_t lo, std::size_t hi) {
        double count = 0.0;
        for (std::size_t i = lo; i < hi; ++i) {
            v_[i] = vk_[i];
            x_[i] = x0_[i] + h * vk_[i];
            dv_previous_[i] = vk_[i] - v0_[i];
            if (!physics::is_finite(x_[i]) || !physics::is_finite(v_[i])) count += 1.0;
            else if (!fixed_[i] && static_cast<double>(physics::length_squared(v_[i])) > runaway2)
                runaway.store(true, std::memory_order_relaxed);
        }
        return count;
    });
    if (bad > 0.0) {
        x_ = x0_;
        v_ = v0_;
        std::fill(dv_previous_.begin(), dv_previous_.end(), V3{});
        stats.non_finite = true;
    } else if (runaway.load()) {
        ++stats.runaway_solves;
        parallel_chunks(n_, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t i = lo; i < hi; ++i) {
                if (!fixed_[i]) v_[i] = v0_[i];
                x_[i] = x0_[i] + h * v_[i];
                dv_previous_[i] = V3{};
            }
        });
    }
    int swept = 0;
    if (bad == 0.0 && !shapes_.empty()) {
        // Offset contact keeps every move within its displacement bound, which is what keeps the cloth
        // free of intersections without CCD; a correction after the truncation would send the substep
        // to the CCD fallback. A fast collider's carry must happen all the same (the ball would pass
        // through the cloth); a slow overshoot is left to the penalty at the next substep's start.
        const auto [carried, overshoots] = sweep_fast_colliders(h, !offset);
        stats.collision.swept_collider_hits += carried;
        stats.collision.collider_overshoots += overshoots;
        swept = carried + overshoots;  // both moved vertices after the solve
    }
    stats.ms(Stage::Update) += ms_since(clock);
    // CCD and impact zones from x0 to x1; vertices they move get the velocity of the new motion.
    if (collide && bad == 0.0) collisions_.end_substep(model, h_double, x0_, x_, v_, swept > 0, stats);
    if ((collide || swept > 0) && bad == 0.0) {
        parallel_chunks(n_, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t i = lo; i < hi; ++i) dv_previous_[i] = v_[i] - v0_[i];
        });
    }
}

template <typename T>
double CpuSolver<T>::incremental_potential(const Model& model, double t1, T h, const std::vector<V3>& v) {
    const std::size_t cloths = flat_->cloth_vertex_offset.size() - 1;
    merit_x_.resize(cloths);
    merit_v_.resize(cloths);
    for (std::size_t c = 0; c < cloths; ++c) {
        const std::size_t first = flat_->cloth_vertex_offset[c], count = flat_->cloth_vertex_offset[c + 1] - first;
        merit_x_[c].resize(count);
        merit_v_[c].resize(count);
        for (std::size_t i = 0; i < count; ++i) {
            merit_x_[c][i] = (x0_[first + i] + h * v[first + i]).template cast<double>();
            merit_v_[c][i] = v[first + i].template cast<double>();
        }
    }
    // The elastic, gravity and collider potentials as the energy guard measures them (energy_audit.h),
    // at the substep's end; the inertia term here.
    const EnergyAudit a = host_energy_audit(model, merit_x_, merit_v_, t1, static_cast<double>(h), false);
    const double inertia = deterministic_sum(n_, partials_, [&](std::size_t lo, std::size_t hi) {
        double sum = 0.0;
        for (std::size_t i = lo; i < hi; ++i) {
            const V3 d = v[i] - v0_[i];
            sum += 0.5 * static_cast<double>(mass_[i]) * static_cast<double>(physics::dot(d, d));
        }
        return sum;
    });
    double offset = 0.0;
    if (collisions_.active() && collisions_.offset()) {
        merit_positions_.resize(n_);
        for (std::size_t i = 0; i < n_; ++i) merit_positions_[i] = x0_[i] + h * v[i];
        offset = collisions_.terms().energy_at(merit_positions_, collisions_.kinematic_x1());
    }
    return inertia + a.gravity + a.elastic + a.contact + offset;
}

// Backtracking on the Newton update (SolverSettings::line_search): Baraff–Witkin's step minimises a
// quadratic model of the objective, which on stiff, light cloth over a long step can be far from it
// (the stability matrix's 1e7 N/m, 0.01 kg/m² sheet at 1/24 s gains kJ in one substep). The update
// is accepted at the first of 1, ½, ¼, … that does not raise the objective; pinned vertices always
// take their prescribed change (it is in both sides of the comparison). No sufficient-decrease
// condition: damping and wind are not in the objective, so a good step may lower it only a little.
template <typename T>
int CpuSolver<T>::line_search(const Model& model, double t1, T h) {
    constexpr int kLineSearchHalvings = 8;  // the update is then 1/256 of Newton's
    trial_v_.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) trial_v_[i] = fixed_[i] ? vk_[i] + dv_[i] : vk_[i];
    const double start = incremental_potential(model, t1, h, trial_v_);
    T alpha = T(1);
    int halvings = 0;
    for (; halvings < kLineSearchHalvings; ++halvings) {
        for (std::size_t i = 0; i < n_; ++i)
            if (!fixed_[i]) trial_v_[i] = vk_[i] + alpha * dv_[i];
        const double end = incremental_potential(model, t1, h, trial_v_);
        if (!(end > start)) break;  // not higher (a NaN is left to the commit's check)
        alpha *= T(0.5);
    }
    if (halvings > 0)
        for (std::size_t i = 0; i < n_; ++i)
            if (!fixed_[i]) dv_[i] *= alpha;
    return halvings;
}

template <typename T>
void CpuSolver<T>::read_state(std::size_t first, std::size_t count, Vec3d* x, Vec3d* v) const {
    for (std::size_t i = 0; i < count; ++i) {
        x[i] = x_[first + i].template cast<double>();
        v[i] = v_[first + i].template cast<double>();
    }
}

template <typename T>
void CpuSolver<T>::write_state(std::size_t first, std::size_t count, const Vec3d* x, const Vec3d* v) {
    for (std::size_t i = 0; i < count; ++i) {
        x_[first + i] = to<T>(x[i]);
        v_[first + i] = to<T>(v[i]);
        dv_previous_[first + i] = V3{};  // the motion was replaced: nothing to extrapolate from
    }
}

template <typename T>
std::vector<std::uint8_t> CpuSolver<T>::solver_state() const {
    // 'C', the scalar's size, the vertex count, the substep count, then the warm start's scalars.
    const std::uint64_t n = n_;
    const std::int64_t substeps = substep_count_;
    std::vector<std::uint8_t> out(2 + sizeof(n) + sizeof(substeps) + dv_previous_.size() * sizeof(V3));
    out[0] = 'C';
    out[1] = static_cast<std::uint8_t>(sizeof(T));
    std::memcpy(out.data() + 2, &n, sizeof(n));
    std::memcpy(out.data() + 2 + sizeof(n), &substeps, sizeof(substeps));
    if (!dv_previous_.empty())
        std::memcpy(out.data() + 2 + sizeof(n) + sizeof(substeps), dv_previous_.data(), dv_previous_.size() * sizeof(V3));
    return out;
}

template <typename T>
void CpuSolver<T>::restore_solver_state(std::span<const std::uint8_t> bytes) {
    std::uint64_t n = 0;
    std::int64_t substeps = 0;
    const std::size_t head = 2 + sizeof(n) + sizeof(substeps);
    if (bytes.size() < head || bytes[0] != 'C')
        throw Error("cpu backend: the checkpoint's solver state is not the CPU backend's");
    if (bytes[1] != sizeof(T))
        throw Error(std::string("cpu backend: the checkpoint was made in ") + (bytes[1] == 4 ? "float" : "double") +
                    ", this world runs in " + (sizeof(T) == 4 ? "float" : "double") + " (solver.precision)");
    std::memcpy(&n, bytes.data() + 2, sizeof(n));
    std::memcpy(&substeps, bytes.data() + 2 + sizeof(n), sizeof(substeps));
    if (n != n_ || bytes.size() != head + n * sizeof(V3))
        throw Error("cpu backend: the checkpoint's solver state is for " + std::to_string(n) + " vertices, this world has " +
                    std::to_string(n_));
    std::memcpy(dv_previous_.data(), bytes.data() + head, n * sizeof(V3));
    substep_count_ = substeps;
    // The Schwarz factors are not in the checkpoint: the next substep refactors (with
    // preconditioner_refresh = 1, the default, it would anyway).
    schwarz_factored_ = false;
}

template <typename T>
double CpuSolver<T>::offset_contact_energy() const {
    if (!collisions_.active() || !collisions_.offset()) return 0.0;
    return collisions_.terms().energy_at(x_, collisions_.kinematic_x1());
}

template <typename T>
std::size_t CpuSolver<T>::memory_bytes() const {
    const std::size_t vec3 = x_.capacity() + v_.capacity() + x0_.capacity() + v0_.capacity() + vk_.capacity() +
                             wk_.capacity() + dv_previous_.capacity() + element_rhs_.capacity() + vertex_rhs_.capacity() + b_.capacity() +
                             dv_.capacity() + pin_velocity_.capacity();
    return vec3 * sizeof(V3) + (element_blocks_.capacity() + vertex_blocks_.capacity() + A_.columns.capacity()) * sizeof(M3) +
           mass_.capacity() * sizeof(T) + triangle_rest_.capacity() * sizeof(TriangleRestT) +
           hinge_rest_.capacity() * sizeof(HingeRestT) + shell_rest_.capacity() * sizeof(physics::ShellBendingRest<T>) +
           hinge_faces_.capacity() * sizeof(hinge_faces_[0]) + shell_faces_.capacity() * sizeof(ShellFaceTerms<T>) +
           (x_lin_.capacity() + d_lin_.capacity()) * sizeof(V3) + fixed_.capacity() + contacts_.capacity() * sizeof(int) +
           face_contact_.capacity() + pcg_.memory_bytes() + schwarz_.memory_bytes() + collisions_.memory_bytes();
}

template class CpuSolver<float>;
template class CpuSolver<double>;

}  // namespace weft::cpu
