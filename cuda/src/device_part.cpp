// The CUDA solver in part mode (device_solver.h): one part of the multi-GPU solver, its substep's
// stages enqueued one by one by the multi-GPU solver (multi/multi_solver.cpp), which runs the CG
// across the parts between them.
#include <bit>
#include <limits>
#include <vector>

#include "device_solver.h"
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
    if (!fixed.empty())
        WEFT_CUDA_CHECK(cudaMemcpy(fixed_.get(), fixed.data(), fixed.size(), cudaMemcpyHostToDevice));
    const std::vector<std::uint32_t> owned(part.global_vertex.begin(), part.global_vertex.begin() + part.owned);
    output_index_.upload(owned, ledger_, "part output places");
    schwarz_on_ = false;  // block-Jacobi until part_use_schwarz
    pcg_loop_ = PcgLoop::PerKernel;
    persistent_grid_ = 0;
}

void DeviceSolver::part_begin_substep(const Model& model, double t, double h) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    cudaStream_t stream = active_stream();
    stage_substep(model, t, h, stream);
    if (schwarz_on_) schwarz_factored_ = true;
    launch_begin_substep(view_, stream);
    launch_pin_velocities(view_, stream);
}

void DeviceSolver::part_assemble(bool first_newton) {
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    cudaStream_t stream = active_stream();
    launch_begin_newton(view_, stream);
    if (row_gather_)
        launch_assemble_rows(view_, stream);
    else
        launch_assemble_colors(view_, layout_.triangle_colors, layout_.hinge_colors, stream);
    launch_pcg_setup(view_, first_newton, schwarz_on_, stream);
}

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
    if (schwarz_on_) {
        s.schwarz = &view_;
        s.level1_begin = 3 * std::size_t{schwarz_.part().node_begin};
        s.level1_end = 3 * std::size_t{schwarz_.part().node_end};
    }
    return s;
}

}  // namespace weft::cuda
