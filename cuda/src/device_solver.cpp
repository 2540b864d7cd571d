// The CUDA solver on one device: upload, the per-substep parameter block, and the substep recorded
// once into a CUDA graph whose CG loop is a conditional while node (no host round trip per
// iteration). The math is in the kernels; this file orders them.
#include "device_solver.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstring>

#include "kernels.h"
#include "weft/backend/collider_shape.h"
#include "weft/error.h"
#include "weft/physics/hessian.h"
#include "weft/physics/swept_collider.h"

namespace weft::cuda {
namespace {

static_assert(kSliceRows == 32, "device code assumes 32-row ELL slices (kSliceRowsDevice)");

/// Host-driven CG (before the graph exists, or when graphs are off): iterations launched in batches of
/// this many, then one small copy of the `running` flag. Kernels after convergence do nothing.
constexpr int kHostCheckInterval = 8;
/// CG iterations in the body of the graph's while node.
constexpr int kIterationsPerGraphLoop = 2;

std::uint32_t align16(std::size_t bytes) { return static_cast<std::uint32_t>((bytes + 15) / 16 * 16); }

V3 to_float(const Vec3d& a) { return {static_cast<float>(a.x), static_cast<float>(a.y), static_cast<float>(a.z)}; }

// Vertex arrays in the SoA layout: component c of vertex i at [c·n + i].
void scatter_soa(std::vector<float>& out, std::size_t offset, std::size_t n, const std::vector<Vec3d>& in) {
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) out[offset + c * n + i] = static_cast<float>(in[i][c]);
}

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
    cudaSetDevice(device_);
    destroy_graph();
    for (cudaEvent_t e : events_) cudaEventDestroy(e);
    if (body_stream_ != nullptr) cudaStreamDestroy(body_stream_);
    if (stream_ != nullptr) cudaStreamDestroy(stream_);
}

void DeviceSolver::destroy_graph() {
    if (graph_exec_ != nullptr) cudaGraphExecDestroy(graph_exec_);
    graph_exec_ = nullptr;
    graph_active_ = false;
}

void DeviceSolver::build(const FlatModel& flat, const Model& model) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
    destroy_graph();
    warm_ = false;
    sweep_launches_ = 0;
    flat_ = &flat;
    ledger_.clear();
    contacts_.release();  // vertex ids of the old model mean nothing in the new one
    collisions_.release();
    layout_ = make_device_layout(flat);
    const std::size_t n = flat.vertex_count, nt = flat.triangle_count(), nh = flat.hinge_count();
    if (n > 0x7fffffffu / 9 || layout_.ell.positions() > 0x7fffffffu / 9)
        throw Error("CUDA backend: " + std::to_string(n) + " vertices is more than one device solver indexes");

    // Vertex state: x, v, x0, v0, vk, wk, b, dv, pin velocity, previous dv.
    constexpr int kStateVectors = 10;
    std::vector<float> host(kStateVectors * 3 * n, 0.0f);
    scatter_soa(host, 0, n, flat.initial_positions);
    scatter_soa(host, 3 * n, n, flat.initial_velocities);
    state_.upload(host, ledger_, "vertex state");
    cg_vectors_.allocate((4 * 3 + 9) * n, ledger_, "CG vectors and preconditioner");
    std::vector<float> mass(n);
    for (std::size_t i = 0; i < n; ++i) mass[i] = static_cast<float>(flat.mass[i]);
    mass_.upload(mass, ledger_, "vertex attributes");
    std::vector<std::uint8_t> fixed(n, 0);
    for (std::uint32_t v : flat.pin_vertex) fixed[v] = 1;
    fixed_.upload(fixed, ledger_, "vertex attributes");
    vertex_cloth_.upload(flat.vertex_cloth, ledger_, "vertex attributes");

    blocks_.allocate(9 * layout_.ell.positions(), ledger_, "matrix blocks");
    column_.upload(layout_.ell.column, ledger_, "matrix structure");
    slice_start_.upload(layout_.ell.slice_start, ledger_, "matrix structure");
    diagonal_.upload(layout_.ell.diagonal, ledger_, "matrix structure");

    // Elements in colour order (device_layout.h); the incidence lists already use colour-order ids.
    std::vector<std::uint32_t> ids(3 * nt), cloth(nt);
    std::vector<float> rest(5 * nt);
    for (std::size_t j = 0; j < nt; ++j) {
        const std::uint32_t t = layout_.triangle_colors.order[j];
        for (int a = 0; a < 3; ++a) ids[3 * j + a] = flat.triangles[t].v[a];
        const TriangleRest& r = flat.triangle_rest[t];
        rest[5 * j + 0] = static_cast<float>(r.dm_inv[0][0]);
        rest[5 * j + 1] = static_cast<float>(r.dm_inv[0][1]);
        rest[5 * j + 2] = static_cast<float>(r.dm_inv[1][0]);
        rest[5 * j + 3] = static_cast<float>(r.dm_inv[1][1]);
        rest[5 * j + 4] = static_cast<float>(r.area);
        cloth[j] = flat.triangle_cloth[t];
    }
    triangle_vertices_.upload(ids, ledger_, "triangles");
    triangle_rest_.upload(rest, ledger_, "triangles");
    triangle_cloth_.upload(cloth, ledger_, "triangles");
    triangle_positions_.upload(layout_.triangle_positions, ledger_, "element slot maps");

    ids.assign(4 * nh, 0);
    cloth.assign(nh, 0);
    rest.assign(2 * nh, 0.0f);
    for (std::size_t j = 0; j < nh; ++j) {
        const std::uint32_t k = layout_.hinge_colors.order[j];
        for (int a = 0; a < 4; ++a) ids[4 * j + a] = flat.hinges[k].v[a];
        rest[2 * j] = static_cast<float>(flat.hinges[k].weight);
        rest[2 * j + 1] = static_cast<float>(flat.hinges[k].rest_angle);
        cloth[j] = flat.hinge_cloth[k];
    }
    hinge_vertices_.upload(ids, ledger_, "hinges");
    hinge_rest_.upload(rest, ledger_, "hinges");
    hinge_cloth_.upload(cloth, ledger_, "hinges");
    hinge_positions_.upload(layout_.hinge_positions, ledger_, "element slot maps");
    // The triangle incidence also serves the normals; the hinge incidence only the row gather.
    vertex_triangle_start_.upload(layout_.vertex_triangle_start, ledger_, "vertex incidence");
    vertex_triangle_.upload(layout_.vertex_triangle, ledger_, "vertex incidence");
    vertex_hinge_start_.upload(layout_.vertex_hinge_start, ledger_, "vertex incidence");
    vertex_hinge_.upload(layout_.vertex_hinge, ledger_, "vertex incidence");
    pin_vertex_.upload(flat.pin_vertex, ledger_, "pins");

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
    offset += align16(std::max<std::size_t>(1, flat.pin_vertex.size()) * sizeof(V3));
    lp.shape_start_offset = static_cast<std::uint32_t>(offset);
    offset += align16(std::max<std::size_t>(1, model.colliders.size()) * sizeof(physics::Shape<float>));
    staging_.allocate(offset, ledger_, "parameters");
    host_staging_.allocate(offset);
    std::memset(host_staging_.get(), 0, offset);

    control_.allocate(1, ledger_, "CG control and stats");
    stats_.allocate(1, ledger_, "CG control and stats");
    // Two sets of block partials: the one-launch CG loop alternates between them.
    partials_.allocate(2 * std::max(1u, grid_for(static_cast<std::uint32_t>(n))), ledger_, "CG control and stats");
    WEFT_CUDA_CHECK(cudaMemset(control_.get(), 0, sizeof(PcgControl)));
    WEFT_CUDA_CHECK(cudaMemset(stats_.get(), 0, sizeof(DeviceStats)));

    DeviceView& d = view_;
    d = DeviceView{};
    d.n = static_cast<std::uint32_t>(n);
    d.triangles = static_cast<std::uint32_t>(nt);
    d.hinges = static_cast<std::uint32_t>(nh);
    d.pins = static_cast<std::uint32_t>(flat.pin_vertex.size());
    d.slices = static_cast<std::uint32_t>(layout_.ell.slices());
    float* sv = state_.get();
    float** vectors[] = {&d.x, &d.v, &d.x0, &d.v0, &d.vk, &d.wk, &d.b, &d.dv, &d.pin_velocity, &d.dv_previous};
    for (int k = 0; k < kStateVectors; ++k) *vectors[k] = sv + static_cast<std::size_t>(k) * 3 * n;
    float* cv = cg_vectors_.get();
    d.r = cv;
    d.c = cv + 3 * n;
    d.q = cv + 6 * n;
    d.s = cv + 9 * n;
    d.precond = cv + 12 * n;
    d.mass = mass_.get();
    d.fixed = fixed_.get();
    d.vertex_cloth = vertex_cloth_.get();
    d.blocks = blocks_.get();
    d.column = column_.get();
    d.slice_start = slice_start_.get();
    d.diagonal = diagonal_.get();
    d.triangle_vertices = triangle_vertices_.get();
    d.triangle_rest = triangle_rest_.get();
    d.triangle_cloth = triangle_cloth_.get();
    d.triangle_positions = triangle_positions_.get();
    d.hinge_vertices = hinge_vertices_.get();
    d.hinge_rest = hinge_rest_.get();
    d.hinge_cloth = hinge_cloth_.get();
    d.hinge_positions = hinge_positions_.get();
    d.vertex_triangle_start = vertex_triangle_start_.get();
    d.vertex_triangle = vertex_triangle_.get();
    d.vertex_hinge_start = vertex_hinge_start_.get();
    d.vertex_hinge = vertex_hinge_.get();
    d.pin_vertex = pin_vertex_.get();
    d.staging = staging_.get();
    d.control = control_.get();
    d.stats = stats_.get();
    d.partials = partials_.get();
    choose_assembly();
    choose_pcg_loop();
    build_collisions(model);
    WEFT_CUDA_CHECK(cudaDeviceSynchronize());
}

void DeviceSolver::build_collisions(const Model& model) {
    const bool was_active = collisions_.active();
    collisions_.build(*flat_, model);
    if (collisions_.active() && view_.n > 0) {
        // The contact path on for good (the graph is captured with it), room for the kinematic arrays.
        reserve_contacts(1, collisions_.kinematic_count());
    } else if (was_active && contacts_.capacity() > 0) {
        // Switched off live: the last substep's contacts must not stay in the solve.
        WEFT_CUDA_CHECK(cudaMemsetAsync(contacts_.inputs().count, 0, sizeof(std::uint32_t), active_stream()));
    }
    ledger_.set("cloth collisions", collisions_.memory_bytes());
}

void DeviceSolver::choose_pcg_loop() {
    // Measured on an H200 (docs/results.md, solve ms per frame): one cooperative launch per solve is
    // 1.6× faster than a kernel per step up to 40K vertices and 1.2× at 100K; from 216K vertices on
    // the two are within 5% either way (bandwidth, not launches, bounds the iteration there).
    constexpr std::uint32_t kOneLaunchMaxVertices = 200000;
    int grid = 0;
    if (pcg_loop_ == PcgLoop::OneLaunch || (pcg_loop_ == PcgLoop::Auto && view_.n <= kOneLaunchMaxVertices))
        grid = view_.n > 0 ? pcg_persistent_grid(view_, device_) : 0;
    if (grid != persistent_grid_) destroy_graph();
    persistent_grid_ = grid;
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

void DeviceSolver::reserve_contacts(std::size_t pairs, std::size_t kinematic) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    if (view_.n == 0) throw Error("CUDA backend: reserve_contacts before build");
    if (contacts_.reserve(pairs, kinematic, view_.n, active_stream())) contacts_resized();
}

void DeviceSolver::set_contacts(std::span<const weft::collision::ProximityContact> contacts,
                                std::span<const Vec3d> kinematic_x1, std::span<const Vec3d> kinematic_v) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    if (view_.n == 0) throw Error("CUDA backend: set_contacts before build");
    if (contacts_.upload(contacts, kinematic_x1, kinematic_v, view_.n, active_stream())) contacts_resized();
}

void DeviceSolver::contacts_resized() {
    // New arrays: the view every kernel (and the captured graph) holds changed, and the one-launch
    // loop switches to its contact variant, whose grid may differ.
    view_.contacts = contacts_.view();
    ledger_.set("proximity contacts", contacts_.bytes());
    destroy_graph();
    choose_pcg_loop();
}

void DeviceSolver::fill_staging(const Model& model, double t, double h) {
    const WorldDesc& w = model.settings;
    unsigned char* base = host_staging_.get();
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
    p.pin_count = static_cast<int>(flat_->pin_vertex.size());
    p.cg_max_iterations = w.solver.cg_max_iterations;
    p.cg_warm_start = w.solver.cg_warm_start ? 1 : 0;
    p.cg_eps2 = w.solver.cg_tolerance * w.solver.cg_tolerance;
    p.grab_vertex = 0xFFFFFFFFu;
    if (model.grab && model.grab->cloth < model.cloths.size()) {
        p.grab_vertex = flat_->cloth_vertex_offset[model.grab->cloth] + model.grab->vertex;
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
    for (std::size_t q = 0; q < f.pin_vertex.size(); ++q) {
        Vec3d target = f.pin_local[q];
        if (f.pin_motion[q] >= 0) target = model.motions[static_cast<std::size_t>(f.pin_motion[q])].at(t1).apply(target);
        targets[q] = to_float(target);
    }
}

void DeviceSolver::record_pcg_loop(cudaStream_t stream, bool capturing, int newton) {
    (void)newton;
    if (persistent_grid_ > 0) {
        // The whole loop is one cooperative kernel, in a graph or not.
        launch_pcg_residual(view_, 0, stream);
        launch_pcg_persistent(view_, persistent_grid_, stream);
        return;
    }
    if (!capturing) {
        launch_pcg_residual(view_, 0, stream);
        // Host-driven loop: batches of iterations, then the `running` flag back.
        for (;;) {
            for (int k = 0; k < kHostCheckInterval; ++k) launch_pcg_iteration(view_, 0, stream);
            WEFT_CUDA_CHECK(cudaMemcpyAsync(host_running_.get(), &view_.control->running, sizeof(int),
                                            cudaMemcpyDeviceToHost, stream));
            WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
            if (host_running_[0] == 0) break;
        }
        return;
    }
    // Graph: the residual kernel sets the condition; a while node runs the iteration body until the
    // update kernel clears it (converged, capped or broken down).
    cudaStreamCaptureStatus status{};
    cudaGraph_t graph = nullptr;
    WEFT_CUDA_CHECK(cudaStreamGetCaptureInfo(stream, &status, nullptr, &graph, nullptr, nullptr, nullptr));
    cudaGraphConditionalHandle handle{};
    WEFT_CUDA_CHECK(cudaGraphConditionalHandleCreate(&handle, graph, 0, 0));
    launch_pcg_residual(view_, handle, stream);
    const cudaGraphNode_t* deps = nullptr;
    std::size_t dep_count = 0;
    WEFT_CUDA_CHECK(cudaStreamGetCaptureInfo(stream, &status, nullptr, &graph, &deps, nullptr, &dep_count));
    cudaGraphNodeParams params{};
    params.type = cudaGraphNodeTypeConditional;
    params.conditional.handle = handle;
    params.conditional.type = cudaGraphCondTypeWhile;
    params.conditional.size = 1;
    cudaGraphNode_t node = nullptr;
    WEFT_CUDA_CHECK(cudaGraphAddNode(&node, graph, deps, nullptr, dep_count, &params));
    WEFT_CUDA_CHECK(cudaStreamUpdateCaptureDependencies(stream, &node, nullptr, 1, cudaStreamSetCaptureDependencies));
    cudaGraph_t body = params.conditional.phGraph_out[0];
    WEFT_CUDA_CHECK(cudaStreamBeginCaptureToGraph(body_stream_, body, nullptr, nullptr, 0, cudaStreamCaptureModeThreadLocal));
    try {
        // Two iterations per trip round the while node halve its per-iteration overhead; the second
        // does nothing if the first finished the solve.
        for (int k = 0; k < kIterationsPerGraphLoop; ++k) launch_pcg_iteration(view_, handle, body_stream_);
    } catch (...) {
        cudaGraph_t discarded = nullptr;
        cudaStreamEndCapture(body_stream_, &discarded);
        throw;
    }
    cudaGraph_t captured = nullptr;
    WEFT_CUDA_CHECK(cudaStreamEndCapture(body_stream_, &captured));
}

void DeviceSolver::record(cudaStream_t stream, bool capturing) {
    const int newton = recorded_newton_;
    int e = 0;
    // Under capture a plain record only orders streams; an external record makes an event node that
    // the graph records at run time, so the stage times below work in both modes.
    const unsigned flags = capturing ? cudaEventRecordExternal : cudaEventRecordDefault;
    auto mark = [&] { WEFT_CUDA_CHECK(cudaEventRecordWithFlags(events_[static_cast<std::size_t>(e++)], stream, flags)); };
    mark();
    launch_begin_substep(view_, stream);
    launch_pin_velocities(view_, stream);
    const bool contacts = view_.contacts.capacity > 0;
    // The incidence of this substep's contacts (timed with the substep's start, as "kinematics").
    if (contacts) launch_contact_incidence(view_, contacts_.scan_storage(), contacts_.scan_storage_bytes(), stream);
    mark();
    for (int it = 0; it < newton; ++it) {
        launch_begin_newton(view_, stream);
        if (row_gather_)
            launch_assemble_rows(view_, stream);
        else
            launch_assemble_colors(view_, layout_.triangle_colors, layout_.hinge_colors, stream);
        if (contacts) launch_contact_evaluate(view_, stream);  // gathered by the PCG setup
        mark();
        launch_pcg_setup(view_, it == 0, stream);
        record_pcg_loop(stream, capturing, it);
        launch_pcg_finish(view_, stream);
        mark();
        launch_newton_update(view_, stream);
        mark();
    }
    launch_commit(view_, stream);
    mark();
}

void DeviceSolver::capture_graph() {
    destroy_graph();
    cudaStream_t stream = active_stream();
    cudaGraph_t graph = nullptr;
    WEFT_CUDA_CHECK(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal));
    try {
        record(stream, true);
    } catch (...) {
        cudaStreamEndCapture(stream, &graph);
        if (graph != nullptr) cudaGraphDestroy(graph);
        throw;
    }
    WEFT_CUDA_CHECK(cudaStreamEndCapture(stream, &graph));
    const cudaError_t err = cudaGraphInstantiate(&graph_exec_, graph, 0);
    cudaGraphDestroy(graph);
    if (err != cudaSuccess) {
        graph_exec_ = nullptr;
        throw_cuda_error(err, "cudaGraphInstantiate", __FILE__, __LINE__);
    }
    ++graph_captures_;
    graph_newton_ = recorded_newton_;
}

void DeviceSolver::substep(const Model& model, double t, double h, StepStats& stats) {
    if (view_.n == 0) return;
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    const auto host_start = Clock::now();
    cudaStream_t stream = active_stream();
    fill_staging(model, t, h);
    WEFT_CUDA_CHECK(cudaMemcpyAsync(staging_.get(), host_staging_.get(), host_staging_.size(), cudaMemcpyHostToDevice, stream));
    const double host_ms = std::chrono::duration<double, std::milli>(Clock::now() - host_start).count();

    // Collision detection before the solve, outside the graph on the same stream (it reads overflow
    // counters back): the contacts go straight into the solve's device list.
    if (collisions_.stale(model)) build_collisions(model);  // self-collision toggled live
    if (collisions_.active()) {
        const std::size_t found = collisions_.detect(model, t, h, view_.x, view_.v, stream, stats);
        reserve_contacts(found, collisions_.kinematic_count());  // grows (and re-captures) only when needed
        collisions_.publish(contacts_.inputs(), stream, stats);
    }

    recorded_newton_ = model.settings.solver.newton_iterations;
    const std::size_t event_count = 3 + 3 * static_cast<std::size_t>(recorded_newton_);
    if (events_.size() < event_count) {
        // Grows only when the Newton iteration count rises past what was seen (reported in memory).
        for (std::size_t k = events_.size(); k < event_count; ++k) {
            cudaEvent_t ev = nullptr;
            WEFT_CUDA_CHECK(cudaEventCreate(&ev));
            events_.push_back(ev);
        }
    }

    const bool want_graph = use_graph_ && !graph_unsupported_ && warm_;
    if (want_graph && (graph_exec_ == nullptr || graph_newton_ != recorded_newton_)) {
        try {
            capture_graph();
        } catch (const Error&) {
            // Conditional nodes need CUDA 12.4 and a recent driver; without them the host-driven loop
            // (same kernels, same results) is used and graph_active() says so.
            graph_unsupported_ = true;
            destroy_graph();
            cudaGetLastError();
        }
    }
    if (want_graph && graph_exec_ != nullptr) {
        WEFT_CUDA_CHECK(cudaGraphLaunch(graph_exec_, stream));
        graph_active_ = true;
    } else {
        record(stream, false);
        graph_active_ = false;
    }
    WEFT_CUDA_CHECK(cudaMemcpyAsync(host_stats_.get(), stats_.get(), sizeof(DeviceStats), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    warm_ = true;

    const DeviceStats& ds = host_stats_[0];
    stats.cg_iterations += ds.cg_iterations;
    stats.cg_iterations_max = std::max(stats.cg_iterations_max, ds.cg_iterations_max);
    stats.cg_residual = std::max(stats.cg_residual, ds.cg_residual);
    stats.cg_not_converged += ds.cg_not_converged;
    stats.newton_iterations += ds.newton_iterations;
    stats.collider_contacts = ds.contacts;
    // With the collision stages on, `detect` reported the list's size, as the CPU does.
    if (view_.contacts.capacity > 0 && !collisions_.active()) stats.collision.contacts = ds.proximity_contacts;
    if (ds.non_finite > 0) stats.non_finite = true;

    auto elapsed = [&](std::size_t a, std::size_t b) {
        float ms = 0.0f;
        WEFT_CUDA_CHECK(cudaEventElapsedTime(&ms, events_[a], events_[b]));
        return static_cast<double>(ms);
    };
    // Events: 0 start, 1 after kinematics, per Newton iteration (forces+assembly, solve, update), last.
    stats.ms(Stage::Kinematics) += host_ms + elapsed(0, 1);
    std::size_t e = 1;
    for (int it = 0; it < recorded_newton_; ++it, e += 3) {
        stats.ms(Stage::Forces) += elapsed(e, e + 1);
        stats.ms(Stage::Solve) += elapsed(e + 1, e + 2);
        stats.ms(Stage::Update) += elapsed(e + 2, e + 3);
    }
    stats.ms(Stage::Update) += elapsed(e, e + 1);

    // After the solve and before CCD, as on the CPU: vertices that an analytic collider ran into
    // during the substep ride along with it (outside the graph, which stays as captured).
    if (ds.non_finite == 0) sweep_colliders(std::bit_cast<float>(ds.largest_move_bits), stream, stats);

    // After the solve: CCD and the impact zones on the device (device_collisions.h).
    if (collisions_.active() && ds.non_finite == 0) {
        (void)collisions_.resolve(model, h, view_.x, view_.v, view_.v0, view_.dv_previous, stream, stats);
        ledger_.set("cloth collisions", collisions_.memory_bytes());  // the detection buffers grow on use
    }

    // The output buffer gets the substep's final state (after the sweep and the impact zones), outside
    // the graph so that switching buffers (the two shared slots of a frame pipeline) re-captures
    // nothing. A shared slot is ordered by its timeline (SharedOutput::end_frame); a buffer bound with
    // set_output() is complete when the step returns, as that API promises.
    if (output_ != nullptr) {
        launch_write_output(view_, output_, output_stride_, stream);
        if (output_synchronous_) WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    }
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
    WEFT_CUDA_CHECK(cudaMemcpyAsync(&host_stats_[0].swept_hits, &stats_.get()->swept_hits, sizeof(int),
                                    cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    ++sweep_launches_;
    stats.collision.swept_collider_hits += host_stats_[0].swept_hits;
    stats.ms(Stage::Update) += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

void DeviceSolver::read_state(std::size_t first, std::size_t count, Vec3d* x, Vec3d* v) const {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
    const std::size_t n = view_.n;
    std::vector<float> buf(3 * count);
    const float* arrays[2] = {view_.x, view_.v};
    Vec3d* outs[2] = {x, v};
    for (int a = 0; a < 2; ++a) {
        for (int c = 0; c < 3; ++c)
            WEFT_CUDA_CHECK(cudaMemcpy(buf.data() + c * count, arrays[a] + c * n + first, count * sizeof(float),
                                       cudaMemcpyDeviceToHost));
        for (std::size_t i = 0; i < count; ++i)
            outs[a][i] = Vec3d{buf[i], buf[count + i], buf[2 * count + i]};
    }
}

void DeviceSolver::write_state(std::size_t first, std::size_t count, const Vec3d* x, const Vec3d* v) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
    const std::size_t n = view_.n;
    std::vector<float> buf(3 * count);
    float* arrays[2] = {view_.x, view_.v};
    const Vec3d* ins[2] = {x, v};
    // The motion was replaced: nothing to extrapolate the next solve's start from.
    for (int c = 0; c < 3; ++c) WEFT_CUDA_CHECK(cudaMemset(view_.dv_previous + c * n + first, 0, count * sizeof(float)));
    for (int a = 0; a < 2; ++a) {
        for (std::size_t i = 0; i < count; ++i)
            for (int c = 0; c < 3; ++c) buf[c * count + i] = static_cast<float>(ins[a][i][c]);
        for (int c = 0; c < 3; ++c)
            WEFT_CUDA_CHECK(cudaMemcpy(arrays[a] + c * n + first, buf.data() + c * count, count * sizeof(float),
                                       cudaMemcpyHostToDevice));
    }
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
    if (output_ != nullptr && view_.n > 0) {
        // Make the buffer valid at once, before the next substep.
        WEFT_CUDA_CHECK(cudaSetDevice(device_));
        launch_write_output(view_, output_, output_stride_, active_stream());
        if (synchronous) WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
    }
}

void DeviceSolver::set_use_graph(bool enabled) {
    use_graph_ = enabled;
    if (!enabled) destroy_graph();
}

}  // namespace weft::cuda
