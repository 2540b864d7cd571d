// The CUDA solver on one device: one substep in order (parameters staged, collision detection,
// the recorded kernels, stage times, the swept test of fast colliders, CCD and impact zones, the
// output buffer) and the solver's settings. The rest of the class lives beside it:
//   - device_upload.cpp: build() (every buffer from the flat model), the contact list, state copies;
//   - device_staging.cpp: the per-substep parameter block, laid out at build and filled each substep;
//   - device_graph.cpp: the substep's kernels recorded once into a CUDA graph whose CG loop is a
//     conditional while node (no host round trip per iteration), re-captured when needed.
// The math is in the kernels; these files order them.
#include "device_solver.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstddef>
#include <cstring>

#include "cuda_check.h"
#include "kernels.h"
#include "loop_clock.h"
#include "weft/backend/timing.h"
#include "weft/error.h"
#include "weft/physics/midedge_bending.h"
#include "weft/physics/swept_collider.h"

namespace weft::cuda {
namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

DeviceSolver::DeviceSolver(int device) : device_(device) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    WEFT_CUDA_CHECK(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking));
    WEFT_CUDA_CHECK(cudaStreamCreateWithFlags(&body_stream_, cudaStreamNonBlocking));
    host_stats_.allocate(1);
    host_running_.allocate(1);
}

DeviceSolver::~DeviceSolver() {
    if (loop_clock_.size() != 0) print_loop_clock("one GPU", loop_clock_.get(), device_);
    cudaSetDevice(device_);
    destroy_graph();
    for (cudaEvent_t e : events_) cudaEventDestroy(e);
    if (body_stream_ != nullptr) cudaStreamDestroy(body_stream_);
    if (stream_ != nullptr) cudaStreamDestroy(stream_);
}

std::vector<std::pair<std::string, std::size_t>> DeviceSolver::memory_breakdown() const {
    std::vector<std::pair<std::string, std::size_t>> parts;
    for (const auto& entry : ledger_.entries())
        if (entry.first != "cloth collisions") parts.push_back(entry);
    for (auto& part : collisions_.memory_breakdown()) parts.push_back(std::move(part));
    return parts;
}

bool face_contacts(const Model& model) {
    return model.settings.solver.face_contacts &&
           std::any_of(model.colliders.begin(), model.colliders.end(), [](const ColliderDesc& c) { return c.is_analytic(); });
}

void DeviceSolver::choose_bending(BendingModel bending) {
    const bool per_triangle = bending == BendingModel::Shell || bending == BendingModel::MidEdge;
    const bool midedge = bending == BendingModel::MidEdge;
    if (per_triangle == (view_.shell_faces != nullptr) && midedge == (view_.midedge.xi != nullptr)) return;
    // A part holds what the per-triangle pass of its rows reads only when it was cut for it
    // (extract_part), and the mid-edge normals are one solve over the whole cloth.
    if (part_ != nullptr && (midedge || (per_triangle && flat_->triangle_hinges.size() != flat_->triangle_count())))
        throw Error("CUDA backend: a part of the multi-GPU solver cannot switch to solver.bending = \"" +
                    std::string(midedge ? "midedge" : "shell") + "\" (its parts were cut for another model); build the world again");
    if (per_triangle && shell_faces_.size() == 0) upload_shell_bending();
    if (midedge && midedge_vectors_.size() == 0) upload_midedge_bending();
    destroy_graph();  // recorded with the other view
    view_.triangle_hinges = per_triangle ? triangle_hinges_.get() : nullptr;
    view_.hinge_faces = per_triangle ? hinge_faces_.get() : nullptr;
    view_.shell_rest = midedge ? midedge_rest_.get() : per_triangle ? shell_rest_.get() : nullptr;
    view_.shell_faces = per_triangle ? shell_faces_.get() : nullptr;
    view_.midedge = MidEdgeView{};
    if (midedge) {
        const std::size_t nh = std::max<std::size_t>(flat_->hinge_count(), 1);
        double* v = midedge_vectors_.get();
        view_.midedge.xi = v;
        view_.midedge.angle = v + nh;
        view_.midedge.r = v + 2 * nh;
        view_.midedge.p = v + 3 * nh;
        view_.midedge.q = v + 4 * nh;
        view_.midedge.diag = v + 5 * nh;
        view_.midedge.clamp = midedge_flags_.get();
        view_.midedge.edge = midedge_flags_.get() + nh;
        view_.midedge.partials = midedge_partials_.get();
        view_.midedge.grid = midedge_grid_;
    }
}

void DeviceSolver::upload_shell_bending() {
    // The flat model's triangles, hinges and rest data in the device's colour order; each hinge's
    // faces in ascending flat order, the order in which the CPU adds them.
    const FlatModel& flat = *flat_;
    const std::size_t nt = flat.triangle_count(), nh = flat.hinge_count();
    std::vector<std::int32_t> device_triangle(nt), device_hinge(nh);
    for (std::size_t j = 0; j < nt; ++j) device_triangle[layout_.triangle_colors.order[j]] = static_cast<std::int32_t>(j);
    for (std::size_t j = 0; j < nh; ++j) device_hinge[layout_.hinge_colors.order[j]] = static_cast<std::int32_t>(j);
    std::vector<std::int32_t> hinges(3 * nt, -1), faces(2 * nh, -1);
    std::vector<float> rest(10 * nt, 0.0f);
    for (std::size_t t = 0; t < nt; ++t) {
        const auto j = static_cast<std::size_t>(device_triangle[t]);
        for (int k = 0; k < 3; ++k) {
            const std::int32_t e = flat.triangle_hinges[t].edge[k];
            if (e < 0) continue;
            const auto dh = static_cast<std::size_t>(device_hinge[static_cast<std::size_t>(e)]);
            hinges[3 * j + static_cast<std::size_t>(k)] = static_cast<std::int32_t>(dh);
            (faces[2 * dh] < 0 ? faces[2 * dh] : faces[2 * dh + 1]) = static_cast<std::int32_t>(j);
        }
        const physics::ShellBendingRest<double>& r = flat.shell_rest[t];
        rest[10 * j] = static_cast<float>(r.area);
        for (int e = 0; e < 9; ++e) rest[10 * j + 1 + static_cast<std::size_t>(e)] = static_cast<float>(r.m[e / 3][e % 3]);
    }
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    triangle_hinges_.upload(hinges, ledger_, "shell bending");
    hinge_faces_.upload(faces, ledger_, "shell bending");
    shell_rest_.upload(rest, ledger_, "shell bending");
    shell_faces_.allocate(std::max<std::size_t>(nt, 1), ledger_, "shell bending");
}

void DeviceSolver::upload_midedge_bending() {
    // The shell model's rest data with each triangle's boundary edges condensed out (the host's
    // midedge_rest), in the device's colour order; the normals' vectors and the cooperative grid.
    const FlatModel& flat = *flat_;
    const std::size_t nt = flat.triangle_count(), nh = flat.hinge_count();
    std::vector<float> rest(10 * nt, 0.0f);
    for (std::size_t j = 0; j < nt; ++j) {
        const auto t = static_cast<std::size_t>(layout_.triangle_colors.order[j]);  // device triangle j is flat triangle t
        bool present[3];
        for (int k = 0; k < 3; ++k) present[k] = flat.triangle_hinges[t].edge[k] >= 0;
        const physics::ShellBendingRest<double> r = physics::midedge_condensed_rest(flat.shell_rest[t], present);
        rest[10 * j] = static_cast<float>(r.area);
        for (int e = 0; e < 9; ++e) rest[10 * j + 1 + static_cast<std::size_t>(e)] = static_cast<float>(r.m[e / 3][e % 3]);
    }
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    midedge_grid_ = midedge_relax_grid(view_, device_);
    if (midedge_grid_ <= 0)
        throw Error("CUDA backend: solver.bending = \"midedge\" needs cooperative launches, which GPU " + std::to_string(device_) +
                    " does not support; use solver.bending = \"shell\" or --backend cpu");
    midedge_rest_.upload(rest, ledger_, "mid-edge bending");
    const std::size_t rows = std::max<std::size_t>(nh, 1);
    midedge_vectors_.allocate(6 * rows, ledger_, "mid-edge bending");
    midedge_flags_.allocate(rows + 3 * std::max<std::size_t>(nt, 1), ledger_, "mid-edge bending");
    midedge_partials_.allocate(4 * static_cast<std::size_t>(midedge_grid_), ledger_, "mid-edge bending");
}

void DeviceSolver::choose_pcg_loop() {
    // Measured on an H200 (docs/results.md, solve ms per frame): one cooperative launch per solve is
    // 1.6× faster than a kernel per step up to 40K vertices and 1.2× at 100K; from 216K vertices on
    // the two are within 5% either way (bandwidth, not launches, bounds the iteration there) without
    // contacts. With contacts the one launch wins at any size: the 1.2M flag with self-contact
    // solves 16% faster in it (H200; docs/results.md, "The CG across GPUs in one launch").
    constexpr std::uint32_t kOneLaunchMaxVertices = 200000;
    const bool contacts = view_.contacts.capacity > 0;
    int grid = 0;
    if (pcg_loop_ == PcgLoop::OneLaunch || (pcg_loop_ == PcgLoop::Auto && (view_.n <= kOneLaunchMaxVertices || contacts)))
        grid = view_.n > 0 ? pcg_persistent_grid(view_, device_, schwarz_on_) : 0;
    if (grid != persistent_grid_) destroy_graph();
    persistent_grid_ = grid;
}

void DeviceSolver::choose_preconditioner(Preconditioner preconditioner) {
    const bool schwarz = preconditioner == Preconditioner::Schwarz ||
                         (preconditioner == Preconditioner::Auto && view_.n >= kAutoSchwarzMinVertices);
    if (schwarz == schwarz_on_) return;
    if (schwarz && !schwarz_.built()) {
        WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
        schwarz_.build(*flat_, layout_.ell.slot_position, ledger_);
        view_.mas = schwarz_.view();
    }
    schwarz_on_ = schwarz;
    schwarz_factored_ = false;  // factored afresh in its first substep
    destroy_graph();
    choose_pcg_loop();
}

void DeviceSolver::set_pcg_loop(PcgLoop loop) {
    pcg_loop_ = loop;
    choose_pcg_loop();
}

void DeviceSolver::choose_assembly() {
    // Measured on an H200 (docs/results.md, forces ms per 60 Hz frame): the row gather wins below
    // about 20K vertices (0.12 against 1.39 ms at 1K vertices, 0.66 against 1.96 at 8.8K) and the
    // colour passes above (2.13 against 2.56 at 40K, 5.1 against 18.5 at 600K).
    constexpr std::uint32_t kRowGatherMaxVertices = 20000;
    const bool gather = assembly_ == AssemblyStrategy::RowGather ||
                        (assembly_ == AssemblyStrategy::Auto && view_.n <= kRowGatherMaxVertices);
    if (gather != row_gather_) destroy_graph();
    row_gather_ = gather;
}

void DeviceSolver::set_assembly(AssemblyStrategy strategy) {
    assembly_ = strategy;
    choose_assembly();
}

void DeviceSolver::substep(const Model& model, double t, double h, StepStats& stats) {
    if (!device_lost_.empty())
        throw Error("CUDA backend: GPU " + std::to_string(device_) + " was lost in an earlier substep (" + device_lost_ +
                    "); its state cannot be read: build a new world");
    if (rebuild_pending_) rebuild_after_fault(model);
    if (view_.n == 0) return;
    substep_started_ = false;
    try {
        run_substep(model, t, h, stats);
    } catch (const Error& e) {
        recover_from_fault(e, t);
    }
}

// A failed substep (docs/design.md, "Device faults"). Out of memory (the budget's or the device's)
// and other errors that leave the context usable: the cloth goes back to the substep's start (x0,
// v0, written by the substep's first kernel) and onto the host, and the buffers are rebuilt from it
// by the next substep, since a buffer that failed to grow may have left its owner half resized. A
// sticky error (an illegal address, a kernel that faulted) loses the context and everything on it.
void DeviceSolver::recover_from_fault(const Error& error, double t) {
    const std::string stage = stage_;
    std::string where = "CUDA backend: the substep from t = " + std::to_string(t) + " s failed in " + stage + ": " + error.what();
    if (context_usable_after_fault(device_)) {
        std::string failure;
        try {
            if (substep_started_) launch_rollback(view_, active_stream());
            rescued_x_.resize(view_.n);
            rescued_v_.resize(view_.n);
            read_state(0, view_.n, rescued_x_.data(), rescued_v_.data());
            rebuild_pending_ = true;
            destroy_graph();
        } catch (const Error& again) {
            failure = again.what();
        }
        if (failure.empty())
            throw Error(where + "; the cloth is back where that substep started (t = " + std::to_string(t) + " s)");
        where += "; putting the cloth back failed too: " + failure;
    }
    device_lost_ = std::string(error.what());
    throw Error(where + "; the device is lost (a sticky CUDA error): its state cannot be read, build a new world");
}

void DeviceSolver::rebuild_after_fault(const Model& model) {
    // build() forgets the rescue once it has succeeded; until then it stays for the next try.
    const std::vector<Vec3d> x = rescued_x_, v = rescued_v_;
    const std::vector<std::uint8_t> warm = std::move(pending_solver_state_);
    pending_solver_state_.clear();
    try {
        build(*flat_, model);
    } catch (...) {
        pending_solver_state_ = warm;  // for the next try
        throw;
    }
    write_state(0, x.size(), x.data(), v.data());
    if (!warm.empty()) restore_solver_state(warm);
}

void DeviceSolver::run_substep(const Model& model, double t, double h, StepStats& stats) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    const auto host_start = Clock::now();
    cudaStream_t stream = active_stream();
    stage_ = "the parameter upload";
    // Whether this substep's contacts are offset contacts (as `offset_model_` below, known before
    // the detection): the staged parameters say so to the sweep.
    moves_bounded_ = needs_cloth_collisions(model) && model.settings.collision.mode == CollisionMode::Offset;
    stage_substep(model, t, h, stream);
    const double host_ms = ms_since(host_start);

    // Collision detection before the solve, outside the graph on the same stream (it reads overflow
    // counters back): the contacts go straight into the solve's device list.
    stage_ = "collision detection";
    if (collisions_.stale(model)) build_collisions(model);  // self-collision toggled live
    stage_ = "the preconditioner's build";
    choose_preconditioner(model.settings.solver.preconditioner);  // may change live
    stage_ = "the bending model's upload";
    choose_bending(model.settings.solver.bending);  // may change live
    stage_ = "collision detection";
    if (collisions_.active()) {
        const std::size_t found = collisions_.detect(model, t, h, view_.x, view_.v, view_.dv_previous, stream, stats);
        reserve_contacts(found, collisions_.kinematic_count());  // grows (and re-captures) only when needed
        collisions_.publish(contacts_.inputs(), stream, stats);
    }

    offset_model_ = collisions_.active() && collisions_.offset() ? &model : nullptr;
    stage_ = "the solve";
    line_search_model_ = model.settings.solver.line_search ? &model : nullptr;
    line_search_t1_ = t + h;
    line_search_h_ = h;
    line_search_halvings_ = 0;
    launch_substep(stream, model.settings.solver.newton_iterations);
    if (schwarz_on_) schwarz_factored_ = true;
    if (offset_model_ != nullptr) {
        // Offset contact: while too many moves were truncated, detect again where the truncation left
        // the cloth and take one more Newton iteration from there (CollisionSettings::redetect_share).
        stage_ = "the offset contact's truncation";
        while (collisions_.finish_truncation(model, stream, stats)) {
            stage_ = "the offset contact's detection rerun";
            const auto extra = Clock::now();
            const std::size_t found = collisions_.redetect(model, h, view_.x0, view_.vk, step_h_device(), stream, stats);
            reserve_contacts(found, collisions_.kinematic_count());
            collisions_.publish(contacts_.inputs(), stream, stats);
            record_extra_newton(stream);
            WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
            stats.ms(Stage::Solve) += ms_since(extra);
        }
        offset_model_ = nullptr;
    }
    stats.line_search_halvings += line_search_halvings_;
    line_search_model_ = nullptr;
    stage_ = "the solve";
    WEFT_CUDA_CHECK(cudaMemcpyAsync(host_stats_.get(), stats_.get(), sizeof(DeviceStats), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    warm_ = true;

    const DeviceStats& ds = host_stats_[0];
    stats.cg_iterations += ds.cg_iterations;
    stats.cg_iterations_max = std::max(stats.cg_iterations_max, ds.cg_iterations_max);
    stats.cg_residual = std::max(stats.cg_residual, ds.cg_residual);
    stats.cg_not_converged += ds.cg_not_converged;
    stats.newton_iterations += ds.newton_iterations;
    stats.preconditioner_pivot_failures += ds.pivot_failures;
    stats.collider_contacts = ds.contacts;
    // With the collision stages on, `detect` reported the list's size, as the CPU does.
    if (view_.contacts.capacity > 0 && !collisions_.active()) stats.collision.contacts = ds.proximity_contacts;
    if (ds.non_finite > 0) stats.non_finite = true;
    else if (ds.runaway > 0) ++stats.runaway_solves;  // dropped by drop_runaway_kernel

    auto elapsed = [&](std::size_t a, std::size_t b) {
        float ms = 0.0f;
        WEFT_CUDA_CHECK(cudaEventElapsedTime(&ms, events_[a], events_[b]));
        return static_cast<double>(ms);
    };
    // Events: 0 start, 1 after kinematics, per Newton iteration (forces+assembly, preconditioner
    // setup, solve, update), last.
    stats.ms(Stage::Kinematics) += host_ms + elapsed(0, 1);
    std::size_t e = 1;
    for (int it = 0; it < recorded_newton_; ++it, e += kEventsPerNewton) {
        stats.ms(Stage::Forces) += elapsed(e, e + 1);
        stats.ms(Stage::Precondition) += elapsed(e + 1, e + 2);
        stats.ms(Stage::Solve) += elapsed(e + 2, e + 3);
        stats.ms(Stage::Update) += elapsed(e + 3, e + 4);
    }
    stats.ms(Stage::Update) += elapsed(e, e + 1);

    // After the solve and before CCD, as on the CPU: vertices that an analytic collider ran into
    // during the substep ride along with it (outside the graph, which stays as captured).
    const auto moved_by_sweep = [&stats] { return stats.collision.swept_collider_hits + stats.collision.collider_overshoots; };
    const int swept_before = moved_by_sweep();
    stage_ = "the fast-collider sweep";
    if (ds.non_finite == 0) sweep_colliders(std::bit_cast<float>(ds.largest_move_bits), stream, stats);

    // After the solve: CCD and the impact zones on the device (device_collisions.h); in offset mode
    // only as the fallback.
    stage_ = "CCD and the impact zones";
    if (collisions_.active() && ds.non_finite == 0) {
        (void)collisions_.resolve(model, h, view_.x, view_.v, view_.v0, view_.dv_previous,
                                  moved_by_sweep() > swept_before, stream, stats);
        ledger_.set("cloth collisions", collisions_.memory_bytes());  // the detection buffers grow on use
    }

    // The output buffer gets the substep's final state (after the sweep and the impact zones), outside
    // the graph so that switching buffers (the two shared slots of a frame pipeline) re-captures
    // nothing. A shared slot is ordered by its timeline (SharedOutput::end_frame); a buffer bound with
    // set_output() is complete when the step returns, as that API promises.
    stage_ = "the output write";
    if (output_ != nullptr) {
        launch_write_output(view_, output_, output_stride_, stream);
        if (output_synchronous_) WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    }
}

void DeviceSolver::stage_substep(const Model& model, double t, double h, cudaStream_t stream) {
    fill_staging(model, t, h, host_staging_.get());
    // Whether this substep refactors the Schwarz preconditioner (SolverSettings::preconditioner_refresh).
    auto* sp = reinterpret_cast<StepParams*>(host_staging_.get());
    const int k = model.settings.solver.preconditioner_refresh;
    const long long index = substep_count_++;
    sp->schwarz_refactor = !schwarz_factored_ || k <= 1 ? 1 : (index % k == 0 ? 2 : 0);
    WEFT_CUDA_CHECK(cudaMemcpyAsync(staging_.get(), host_staging_.get(), host_staging_.size(), cudaMemcpyHostToDevice, stream));
}

bool DeviceSolver::sweep_needed(float largest_move) const {
    const unsigned char* base = host_staging_.get();
    StepParams p{};
    std::memcpy(&p, base, sizeof(p));
    if (p.bounded_shape_count == 0) return false;
    const auto* start = reinterpret_cast<const physics::Shape<float>*>(base + p.shape_start_offset);
    const auto* end = reinterpret_cast<const physics::Shape<float>*>(base + p.shape_offset);
    for (int s = 0; s < p.shape_count; ++s) {
        const float width = physics::shape_min_width(start[s]);
        if (!(width > 0.0f)) continue;  // a plane: never sampled
        // The relative motion swept_shape_contact compares with a quarter of the width, with the
        // vertex's own |x1 − x0| replaced by its largest value: in double, with a relative margin
        // far above float rounding, so the device test never wanted to sample where this says no.
        const double turn = static_cast<double>(p.h) * static_cast<double>(physics::shape_bounding_radius(start[s]));
        const double relative = static_cast<double>(largest_move) +
                                physics::length((end[s].origin - start[s].origin).template cast<double>()) +
                                physics::length(start[s].angular_velocity.template cast<double>()) * turn;
        if (relative * (1.0 + 1e-4) > 0.25 * static_cast<double>(width)) return true;
    }
    return false;
}

void DeviceSolver::sweep_colliders(float largest_move, cudaStream_t stream, StepStats& stats) {
    if (!sweep_needed(largest_move)) return;
    const auto start = Clock::now();
    launch_sweep_colliders(view_, stream);
    static_assert(offsetof(DeviceStats, overshoot_hits) == offsetof(DeviceStats, swept_hits) + sizeof(int));
    WEFT_CUDA_CHECK(cudaMemcpyAsync(&host_stats_[0].swept_hits, &stats_.get()->swept_hits, 2 * sizeof(int),
                                    cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    ++sweep_launches_;
    stats.collision.swept_collider_hits += host_stats_[0].swept_hits;
    stats.collision.collider_overshoots += host_stats_[0].overshoot_hits;
    stats.ms(Stage::Update) += ms_since(start);
}

EnergyAudit DeviceSolver::energy_audit(const Model& model, double t, double h, bool with_wind, const float* whole_x) {
    EnergyAudit a;
    a.with_wind = with_wind;
    // A moving mesh collider's work is not bounded (as in host_energy_audit).
    for (const ColliderDesc& c : model.colliders)
        if (!c.is_analytic() && c.moves()) a.bounded = false;
    if (!device_lost_.empty())
        throw Error("CUDA backend: GPU " + std::to_string(device_) + " was lost in an earlier substep (" + device_lost_ +
                    "); its state cannot be audited");
    // After a fault the buffers are rebuilt first (a failed rebuild throws here, reading nothing).
    if (rebuild_pending_) rebuild_after_fault(model);
    if (view_.n == 0) return a;
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    // The bending model the next substep steps (the first step's start is audited before any substep).
    choose_bending(model.settings.solver.bending);
    cudaStream_t stream = active_stream();
    ensure_audit_buffers(stream);
    // The audit's own copy of the parameters at t (the solver's block belongs to its substeps).
    fill_staging(model, t, h, audit_host_staging_.get());
    WEFT_CUDA_CHECK(cudaMemcpyAsync(audit_staging_.get(), audit_host_staging_.get(), audit_host_staging_.size(),
                                    cudaMemcpyHostToDevice, stream));
    DeviceView view = view_;
    view.staging = audit_staging_.get();
    const double* s = audit_sums(view, with_wind, face_contacts(model), whole_x, stream);
    a.kinetic = s[kEnergyKinetic];
    a.gravity = s[kEnergyGravity];
    a.contact = s[kEnergyContact] + s[kEnergyOffsetContact] + s[kEnergyFaceContact];
    a.elastic = s[kEnergyMembrane] + s[kEnergyBending];
    a.max_stretch = s[kEnergyMaxStretch];
    a.external_power = s[kEnergyColliderPower] + s[kEnergyFaceColliderPower] + s[kEnergyGrabPower] + s[kEnergyWindPower] +
                       std::max(0.0, s[kEnergyPinPower]);
    return a;
}

void DeviceSolver::ensure_audit_buffers(cudaStream_t stream) {
    if (audit_staging_.size() == staging_.size()) return;  // allocated since the build
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    audit_host_staging_.allocate(host_staging_.size());
    std::memset(audit_host_staging_.get(), 0, audit_host_staging_.size());
    audit_staging_.allocate(staging_.size(), ledger_, "energy audit");
    audit_partials_.allocate(static_cast<std::size_t>(kEnergySums) * energy_partial_stride(view_) + kEnergySums, ledger_,
                             "energy audit");
    audit_sums_.allocate(kEnergySums);
}

const double* DeviceSolver::audit_sums(const DeviceView& view, bool with_wind, bool with_faces, const float* whole_x,
                                       cudaStream_t stream) {
    double* sums = audit_partials_.get() + static_cast<std::size_t>(kEnergySums) * energy_partial_stride(view_);
    launch_energy_audit(view, with_wind, with_faces, audit_partials_.get(), sums, stream, whole_x,
                        whole_ != nullptr ? static_cast<std::uint32_t>(whole_->vertex_count) : 0);
    WEFT_CUDA_CHECK(cudaMemcpyAsync(audit_sums_.get(), sums, kEnergySums * sizeof(double), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    return audit_sums_.get();
}

// Backtracking on the Newton update (CpuSolver::line_search, with its reasons): the objective at
// v_k + α·Δv for α = 0 (the start: only the pins' prescribed change), then 1, ½, … until it is not
// higher. Damping and wind are not in the objective, so there is no sufficient-decrease condition.
int DeviceSolver::line_search(cudaStream_t stream) {
    constexpr int kLineSearchHalvings = 8;  // the update is then 1/256 of Newton's, as on the CPU
    const std::size_t n = view_.n;
    ensure_audit_buffers(stream);
    if (trial_x_.size() != 3 * n) {
        trial_x_.allocate(3 * n, ledger_, "line search");
        trial_dv_.allocate(3 * n, ledger_, "line search");
    }
    // The potentials at the substep's end, t + h (the colliders' pose there), as the CPU's.
    fill_staging(*line_search_model_, line_search_t1_, line_search_h_, audit_host_staging_.get());
    WEFT_CUDA_CHECK(cudaMemcpyAsync(audit_staging_.get(), audit_host_staging_.get(), audit_host_staging_.size(),
                                    cudaMemcpyHostToDevice, stream));
    // The audit's kinetic sum over v = v − v0 is the inertia term ½·m·|v − v0|².
    DeviceView trial = view_;
    trial.staging = audit_staging_.get();
    trial.x = trial_x_.get();
    trial.v = trial_dv_.get();
    const auto objective = [&](float alpha) {
        launch_line_search_trial(view_, alpha, trial_x_.get(), trial_dv_.get(), stream);
        const double* s = audit_sums(trial, false, face_contacts(*line_search_model_), nullptr, stream);
        return s[kEnergyKinetic] + s[kEnergyGravity] + s[kEnergyContact] + s[kEnergyMembrane] + s[kEnergyBending] +
               s[kEnergyOffsetContact] + s[kEnergyFaceContact];
    };
    const double start = objective(0.0f);
    float alpha = 1.0f;
    int halvings = 0;
    for (; halvings < kLineSearchHalvings; ++halvings) {
        if (!(objective(alpha) > start)) break;  // not higher (a NaN is left to the commit's check)
        alpha *= 0.5f;
    }
    if (halvings > 0) launch_scale_update(view_, alpha, stream);
    return halvings;
}

void DeviceSolver::set_stream(cudaStream_t stream) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
    user_stream_ = stream;
}

void DeviceSolver::set_output(void* device_buffer, std::size_t stride, bool synchronous) {
    if (device_buffer != nullptr && stride < 6 * sizeof(float))
        throw Error("CUDA backend: output stride " + std::to_string(stride) + " is smaller than one vertex (24 bytes)");
    output_ = device_buffer;
    output_stride_ = stride;
    output_synchronous_ = synchronous;
    // After a fault (rebuild pending) or with the device lost there are no buffers to write from:
    // the rebuild's first substep writes the output.
    if (output_ != nullptr && view_.n > 0 && !rebuild_pending_ && device_lost_.empty()) {
        // Make the buffer valid at once, before the next substep.
        WEFT_CUDA_CHECK(cudaSetDevice(device_));
        launch_write_output(view_, output_, output_stride_, active_stream(), output_index_.get());
        if (synchronous) WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
    }
}

}  // namespace weft::cuda
