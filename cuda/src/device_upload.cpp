// The CUDA solver's upload (see device_solver.cpp): build() turns the flat model into device
// buffers (vertex state and attributes, the ELL matrix structure, the elements in colour order,
// the incidence lists), sizes the contact list, and copies vertex state in and out.
#include "device_solver.h"

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "kernels.h"
#include "loop_clock.h"
#include "weft/error.h"

namespace weft::cuda {
namespace {

static_assert(kSliceRows == 32, "device code assumes 32-row ELL slices (kSliceRowsDevice)");

// Vertex arrays in the SoA layout: component c of vertex i at [c·n + i].
void scatter_soa(std::vector<float>& out, std::size_t offset, std::size_t n, const std::vector<Vec3d>& in) {
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) out[offset + c * n + i] = static_cast<float>(in[i][c]);
}

}  // namespace

void DeviceSolver::build(const FlatModel& flat, const Model& model) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
    destroy_graph();
    warm_ = false;
    sweep_launches_ = 0;
    flat_ = &flat;
    // The CG energy test's scale (cg_energy_floor): the mass of every cloth, of the whole world in
    // part mode.
    total_mass_ = (whole_ != nullptr ? *whole_ : flat).total_mass();
    ledger_.clear();
    contacts_.release();  // vertex ids of the old model mean nothing in the new one
    collisions_.release();
    schwarz_.release();  // its levels follow the topology: rebuilt when first used
    triangle_hinges_ = {};  // the bending model per triangle's arrays too (choose_bending)
    hinge_faces_ = {};
    shell_rest_ = {};
    shell_faces_ = {};
    midedge_rest_ = {};
    midedge_vectors_ = {};
    midedge_flags_ = {};
    midedge_partials_ = {};
    schwarz_on_ = false;
    schwarz_factored_ = false;
    substep_count_ = 0;
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

    // The per-substep parameter block (device_staging.cpp).
    layout_staging(model);

    control_.allocate(1, ledger_, "CG control and stats");
    stats_.allocate(1, ledger_, "CG control and stats");
    // Two sets of block partials: the one-launch CG loop alternates between them.
    // At least kMaxPersistentBlocks a set: the loop's grid may be set wider than a block per 256 rows.
    partials_.allocate(2 * std::max(kMaxPersistentBlocks, grid_for(static_cast<std::uint32_t>(n))), ledger_,
                       "CG control and stats");
    if (loop_clock_requested() && loop_clock_.size() == 0) {  // kept over re-uploads: printed when the solver goes
        loop_clock_.allocate(kLoopClockEntries, ledger_, "CG loop clock");
        WEFT_CUDA_CHECK(cudaMemset(loop_clock_.get(), 0, kLoopClockEntries * sizeof(long long)));
    }
    collider_contact_.allocate(std::max<std::size_t>(n, 1), ledger_, "collider contact flags");
    WEFT_CUDA_CHECK(cudaMemset(collider_contact_.get(), 0, collider_contact_.bytes()));
    WEFT_CUDA_CHECK(cudaMemset(control_.get(), 0, sizeof(PcgControl)));
    WEFT_CUDA_CHECK(cudaMemset(stats_.get(), 0, sizeof(DeviceStats)));
    wait_for_default_stream();

    DeviceView& d = view_;
    d = DeviceView{};
    d.n = static_cast<std::uint32_t>(n);
    d.rows = part_ != nullptr ? part_->owned : d.n;
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
    d.collider_contact = collider_contact_.get();
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
    d.loop_clock = loop_clock_.size() != 0 ? loop_clock_.get() : nullptr;
    choose_assembly();
    choose_pcg_loop();
    if (part_ == nullptr) build_collisions(model);  // part mode: the MultiSolver detects (docs/multi-gpu.md)
    WEFT_CUDA_CHECK(cudaDeviceSynchronize());
    // Built: a state rescued from a fault is the caller's to write now (rebuild_after_fault).
    rebuild_pending_ = false;
    rescued_x_.clear();
    rescued_v_.clear();
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

void DeviceSolver::read_state(std::size_t first, std::size_t count, Vec3d* x, Vec3d* v) const {
    if (rebuild_pending_) {  // after a fault the state is on the host (DeviceSolver::substep)
        std::copy_n(rescued_x_.begin() + static_cast<std::ptrdiff_t>(first), count, x);
        std::copy_n(rescued_v_.begin() + static_cast<std::ptrdiff_t>(first), count, v);
        return;
    }
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

void DeviceSolver::contact_vertices(std::size_t first, std::size_t count, std::vector<std::uint32_t>& out) const {
    out.clear();
    const ContactView& c = view_.contacts;
    // No contact path (nothing reserved), or the state is on the host after a fault: no contacts.
    if (c.capacity == 0 || c.start == nullptr || rebuild_pending_ || count == 0) return;
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
    // A row is in a contact where its incidence is not empty: the solve's gathers read the same.
    std::vector<std::uint32_t> start(count + 1);
    WEFT_CUDA_CHECK(cudaMemcpy(start.data(), c.start + first, (count + 1) * sizeof(std::uint32_t), cudaMemcpyDeviceToHost));
    for (std::size_t i = 0; i < count; ++i)
        if (start[i + 1] > start[i]) out.push_back(static_cast<std::uint32_t>(i));
}

void DeviceSolver::collider_contact_vertices(std::size_t first, std::size_t count, std::vector<std::uint32_t>& out) const {
    out.clear();
    if (view_.collider_contact == nullptr || rebuild_pending_ || count == 0) return;
    if (first + count > view_.n)
        throw Error("collider_contact_vertices: rows [" + std::to_string(first) + ", " + std::to_string(first + count) +
                    ") past the " + std::to_string(view_.n) + " of the device");
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
    std::vector<std::uint8_t> flag(count);
    WEFT_CUDA_CHECK(cudaMemcpy(flag.data(), view_.collider_contact + first, count, cudaMemcpyDeviceToHost));
    for (std::size_t i = 0; i < count; ++i)
        if (flag[i] != 0) out.push_back(static_cast<std::uint32_t>(i));
}

void DeviceSolver::write_state(std::size_t first, std::size_t count, const Vec3d* x, const Vec3d* v) {
    if (rebuild_pending_) {
        std::copy_n(x, count, rescued_x_.begin() + static_cast<std::ptrdiff_t>(first));
        std::copy_n(v, count, rescued_v_.begin() + static_cast<std::ptrdiff_t>(first));
        return;
    }
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    cudaStream_t stream = active_stream();
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    const std::size_t n = view_.n;
    std::vector<float> buf(6 * count);
    float* arrays[2] = {view_.x, view_.v};
    const Vec3d* ins[2] = {x, v};
    // On the solver's stream, so the next substep's kernels follow the bytes (wait_for_default_stream).
    // The motion was replaced: nothing to extrapolate the next solve's start from.
    for (int c = 0; c < 3; ++c)
        WEFT_CUDA_CHECK(cudaMemsetAsync(view_.dv_previous + c * n + first, 0, count * sizeof(float), stream));
    for (int a = 0; a < 2; ++a) {
        float* staged = buf.data() + 3 * a * count;
        for (std::size_t i = 0; i < count; ++i)
            for (int c = 0; c < 3; ++c) staged[c * count + i] = static_cast<float>(ins[a][i][c]);
        for (int c = 0; c < 3; ++c)
            WEFT_CUDA_CHECK(cudaMemcpyAsync(arrays[a] + c * n + first, staged + c * count, count * sizeof(float),
                                            cudaMemcpyHostToDevice, stream));
    }
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));  // buf is read until the copies are done
}

}  // namespace weft::cuda

namespace weft::cuda {

// 'G', 4 (float), the vertex count, the substep count, then the previous Δv as the device holds it
// (SoA, 3n floats): the bits the next substep's warm start reads.
std::vector<std::uint8_t> DeviceSolver::solver_state() const {
    if (rebuild_pending_ && !pending_solver_state_.empty()) return pending_solver_state_;  // restored after a fault
    const std::uint64_t n = rebuild_pending_ ? rescued_x_.size() : view_.n;
    const std::int64_t substeps = substep_count_;
    constexpr std::size_t kHead = 2 + sizeof(std::uint64_t) + sizeof(std::int64_t);
    std::vector<std::uint8_t> out(kHead + 3 * n * sizeof(float));
    out[0] = 'G';
    out[1] = sizeof(float);
    std::memcpy(out.data() + 2, &n, sizeof(n));
    std::memcpy(out.data() + 2 + sizeof(n), &substeps, sizeof(substeps));
    if (n == 0) return out;
    if (rebuild_pending_) return out;  // after a fault: the rebuild starts cold (zeros)
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
    WEFT_CUDA_CHECK(cudaMemcpy(out.data() + kHead, view_.dv_previous, 3 * n * sizeof(float), cudaMemcpyDeviceToHost));
    return out;
}

void DeviceSolver::restore_solver_state(std::span<const std::uint8_t> bytes) {
    std::uint64_t n = 0;
    std::int64_t substeps = 0;
    constexpr std::size_t kHead = 2 + sizeof(n) + sizeof(substeps);
    if (bytes.empty()) return;  // saved across several GPUs, which keep no warm start yet: start cold
    if (bytes.size() < kHead || bytes[0] != 'G')
        throw Error("cuda backend: the checkpoint's solver state is not the CUDA backend's");
    if (bytes[1] != sizeof(float)) throw Error("cuda backend: the checkpoint's solver state is not in float");
    std::memcpy(&n, bytes.data() + 2, sizeof(n));
    std::memcpy(&substeps, bytes.data() + 2 + sizeof(n), sizeof(substeps));
    const std::size_t vertices = rebuild_pending_ ? rescued_x_.size() : view_.n;
    if (n != vertices || bytes.size() != kHead + 3 * n * sizeof(float))
        throw Error("cuda backend: the checkpoint's solver state is for " + std::to_string(n) + " vertices, this world has " +
                    std::to_string(vertices));
    if (substeps < 0) throw Error("cuda backend: the checkpoint's substep count is negative");
    if (rebuild_pending_) {
        // After a fault the buffers may be gone: the warm start waits for the rebuild.
        pending_solver_state_.assign(bytes.begin(), bytes.end());
        substep_count_ = substeps;
        return;
    }
    if (n > 0) {
        WEFT_CUDA_CHECK(cudaSetDevice(device_));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
        WEFT_CUDA_CHECK(cudaMemcpyAsync(view_.dv_previous, bytes.data() + kHead, 3 * n * sizeof(float), cudaMemcpyHostToDevice,
                                        active_stream()));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
    }
    substep_count_ = substeps;
    // The Schwarz factors are not in the checkpoint: the next substep refactors (with
    // preconditioner_refresh = 1, the default, it would anyway).
    schwarz_factored_ = false;
}

}  // namespace weft::cuda
