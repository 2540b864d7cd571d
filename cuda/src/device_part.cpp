// The CUDA solver in part mode (device_solver.h): one part of the multi-GPU solver, its substep's
// stages enqueued one by one by the multi-GPU solver (multi/multi_solver.cpp), which runs the CG
// across the parts between them.
#include <bit>
#include <algorithm>
#include <limits>
#include <vector>

#include "device_solver.h"
#include "multi/part_contacts.h"
#include "kernels.h"
#include "weft/error.h"

namespace weft::cuda {

void DeviceSolver::build_part(const FlatModel& whole, const PartModel& part, const Model& model) {
    if (part.model.vertex_count != part.global_vertex.size() || part.owned > part.model.vertex_count)
        throw Error("CUDA backend: a part of " + std::to_string(part.model.vertex_count) + " local vertices with " +
                    std::to_string(part.global_vertex.size()) + " global ids and " + std::to_string(part.owned) + " owned");
    whole_ = &whole;
    part_ = &part;
    local_of_global_.assign(whole.vertex_count, std::numeric_limits<std::uint32_t>::max());
    for (std::size_t i = 0; i < part.global_vertex.size(); ++i) local_of_global_[part.global_vertex[i]] = static_cast<std::uint32_t>(i);
    build(part.model, model);
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    // A ghost is fixed where its owner is (the part's pins are its owned ones): filters that read a
    // neighbour's flag, such as the Schwarz couplings, then see what one GPU sees.
    std::vector<std::uint8_t> fixed(part.global_vertex.size(), 0);
    for (std::size_t i = 0; i < fixed.size(); ++i) {
        const std::uint32_t g = part.global_vertex[i];
        fixed[i] = g < whole.vertex_pin.size() && whole.vertex_pin[g] >= 0 ? 1 : 0;
    }
    if (!fixed.empty()) {
        WEFT_CUDA_CHECK(cudaMemcpy(fixed_.get(), fixed.data(), fixed.size(), cudaMemcpyHostToDevice));
        wait_for_default_stream();
    }
    const std::vector<std::uint32_t> owned(part.global_vertex.begin(), part.global_vertex.begin() + part.owned);
    output_index_.upload(owned, ledger_, "part output places");
    // The bending model per triangle: the part holds its faces' hinges (extract_part), cut for it.
    if (!part.model.triangle_hinges.empty()) choose_bending(model.settings.solver.bending);
    global_index_.upload(part.global_vertex, ledger_, "part vertex ids");
    if (needs_cloth_collisions(model)) {
        std::vector<std::uint32_t> row_of(whole.vertex_count, std::numeric_limits<std::uint32_t>::max());
        for (std::uint32_t i = 0; i < part.owned; ++i) row_of[part.global_vertex[i]] = i;
        row_of_.upload(row_of, ledger_, "part contact rows");
    }
    schwarz_on_ = false;  // block-Jacobi until part_use_schwarz
    pcg_loop_ = PcgLoop::PerKernel;
    persistent_grid_ = 0;
}

void DeviceSolver::part_begin_substep(const Model& model, double t, double h, bool moves_bounded) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    moves_bounded_ = moves_bounded;
    cudaStream_t stream = active_stream();
    stage_substep(model, t, h, stream);
    if (schwarz_on_) schwarz_factored_ = true;
    launch_begin_substep(view_, stream);
    launch_pin_velocities(view_, stream);
}

void DeviceSolver::part_assemble(bool first_newton, bool offset_contacts) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    cudaStream_t stream = active_stream();
    launch_begin_newton(view_, stream);
    launch_shell_faces(view_, stream);  // the bending model per triangle's pass 1 (nothing with hinges)
    if (row_gather_)
        launch_assemble_rows(view_, stream);
    else
        launch_assemble_colors(view_, layout_.triangle_colors, layout_.hinge_colors, stream);
    if (view_.contacts.capacity > 0) {
        // The pairs read their vertices from the whole-size copies, in the whole model's numbering.
        DeviceView whole = view_;
        whole.n = contact_whole_;
        whole.x0 = const_cast<float*>(contact_x0_);
        whole.wk = const_cast<float*>(contact_wk_);
        whole.vk = const_cast<float*>(contact_vk_);
        launch_contact_evaluate(whole, stream);
        // Offset contacts turn active and inactive with each evaluation (kInactiveContactBit).
        if (offset_contacts) launch_contact_incidence(view_, contacts_.sort_scratch(), stream);
    }
    launch_pcg_setup(view_, first_newton, schwarz_on_, stream);
}

const float* DeviceSolver::step_h_device() const { return &reinterpret_cast<const StepParams*>(view_.staging)->h; }

void DeviceSolver::part_use_schwarz(bool on, const SchwarzHierarchy& whole) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    if (on && !schwarz_.built()) {
        WEFT_CUDA_CHECK(cudaStreamSynchronize(active_stream()));
        schwarz_.build_part(extract_part_schwarz(whole, *part_), part_->model.pattern, layout_.ell.slot_position, ledger_);
        view_.mas = schwarz_.view();
    }
    if (on != schwarz_on_) schwarz_factored_ = false;
    schwarz_on_ = on;
}

void DeviceSolver::part_factor_level1(int newton) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    launch_schwarz_couplings(view_, 1, 2, newton, active_stream());
}

void DeviceSolver::part_factor_rest(int newton) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    launch_schwarz_couplings(view_, 2, view_.mas.levels, newton, active_stream());
    launch_schwarz_factor_domains(view_, newton, active_stream());
}

void DeviceSolver::part_set_contact_copies(const float* x0, const float* wk, const float* vk, std::uint32_t whole) {
    contact_x0_ = x0;
    contact_wk_ = wk;
    contact_vk_ = vk;
    contact_whole_ = whole;
}

bool DeviceSolver::part_receive_contacts(std::span<const multi::ContactShare> shares, const ContactInputs& kinematic_from,
                                         cudaEvent_t ready, std::size_t kinematic) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    cudaStream_t stream = active_stream();
    std::size_t total = 0, largest = 0;
    for (const multi::ContactShare& share : shares) {
        total += share.count;
        largest = std::max(largest, share.count);
    }
    bool grew = contacts_.reserve(std::max<std::size_t>(total, 1), kinematic, view_.n, stream);
    if (corner_source_.size() != contacts_.view().capacity) {  // with the list's capacity: the views go stale together
        WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
        corner_source_.allocate(contacts_.view().capacity, ledger_, "part contact corners");
        ledger_.set("part contact corners", corner_source_.bytes());  // grown: replaced, not added
        grew = true;
    }
    if (grew) contacts_resized();
    view_.contacts.row_of = row_of_.get();
    view_.contacts.cloth_vertices = contact_whole_;
    view_.contacts.corner_source = corner_source_.get();
    ContactInputs to = contacts_.inputs();
    // Only the contacts at this part's rows, each share's after the last's: each part evaluates
    // and multiplies its share of the contacts.
    const std::size_t scratch = multi::part_contact_selection_bytes(largest);
    if (contact_selection_.bytes() < scratch || selected_count_.size() == 0) {
        WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
        contact_selection_.allocate(scratch + scratch / 4, ledger_, "part contact selection");
        ledger_.set("part contact selection", contact_selection_.bytes());  // grown: replaced, not added
        if (selected_count_.size() == 0) {
            selected_count_.allocate(1, ledger_, "part contact selection");
            selected_host_.allocate(1);
        }
    }
    std::size_t placed = 0;
    for (const multi::ContactShare& share : shares) {
        if (share.count == 0) continue;
        multi::launch_select_part_contacts(share.list, share.count, row_of_.get(), contact_whole_, to.list + placed,
                                           selected_count_.get(), contact_selection_.get(), contact_selection_.bytes(), stream);
        WEFT_CUDA_CHECK(cudaMemcpyAsync(selected_host_.get(), selected_count_.get(), sizeof(std::uint32_t),
                                        cudaMemcpyDeviceToHost, stream));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
        placed += selected_host_[0];
    }
    part_contact_count_ = placed;
    selected_host_[0] = static_cast<std::uint32_t>(placed);
    WEFT_CUDA_CHECK(cudaMemcpyAsync(to.count, selected_host_.get(), sizeof(std::uint32_t), cudaMemcpyHostToDevice, stream));
    WEFT_CUDA_CHECK(cudaStreamWaitEvent(stream, ready, 0));
    for (int c = 0; c < 3 && kinematic > 0; ++c) {
        WEFT_CUDA_CHECK(cudaMemcpyAsync(to.kinematic_x1 + std::size_t(c) * to.kinematic_capacity,
                                        kinematic_from.kinematic_x1 + std::size_t(c) * kinematic_from.kinematic_capacity,
                                        kinematic * sizeof(float), cudaMemcpyDefault, stream));
        WEFT_CUDA_CHECK(cudaMemcpyAsync(to.kinematic_v + std::size_t(c) * to.kinematic_capacity,
                                        kinematic_from.kinematic_v + std::size_t(c) * kinematic_from.kinematic_capacity,
                                        kinematic * sizeof(float), cudaMemcpyDefault, stream));
    }
    multi::launch_part_corner_sources(view_.contacts, static_cast<std::uint32_t>(placed), corner_source_.get(), stream);
    launch_contact_incidence(view_, contacts_.sort_scratch(), stream);
    return grew;
}

void DeviceSolver::part_newton_update() {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    launch_newton_update(view_, active_stream());
}

void DeviceSolver::part_commit() {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    launch_commit(view_, active_stream());
}

const DeviceStats& DeviceSolver::part_stats() {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    cudaStream_t stream = active_stream();
    WEFT_CUDA_CHECK(cudaMemcpyAsync(host_stats_.get(), stats_.get(), sizeof(DeviceStats), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    warm_ = true;
    return host_stats_[0];
}

void DeviceSolver::part_rollback() {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    launch_rollback(view_, active_stream());
}

void DeviceSolver::part_drop_solve() {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    launch_drop_solve(view_, active_stream());
}

bool DeviceSolver::part_sweep(StepStats& stats) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    const int before = sweep_launches_;
    sweep_colliders(std::bit_cast<float>(host_stats_[0].largest_move_bits), active_stream(), stats);
    return sweep_launches_ != before;
}

void DeviceSolver::part_write_output() {
    if (output_ == nullptr) return;
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    launch_write_output(view_, output_, output_stride_, active_stream(), output_index_.get());
}

multi::PartSystem DeviceSolver::part_system() const {
    multi::PartSystem s;
    s.device = device_;
    s.stream = active_stream();
    s.owned = view_.rows;
    s.local = view_.n;
    s.slice_start = view_.slice_start;
    s.column = view_.column;
    s.diagonal = view_.diagonal;
    s.blocks = view_.blocks;
    s.fixed = view_.fixed;
    s.precond = view_.precond;
    s.contacts = view_.contacts;
    if (schwarz_on_) {
        s.schwarz = &view_;
        s.level1_begin = 3 * std::size_t{schwarz_.part().node_begin};
        s.level1_end = 3 * std::size_t{schwarz_.part().node_end};
    }
    return s;
}

}  // namespace weft::cuda
