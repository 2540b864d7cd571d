// The CUDA solver's recording (see device_solver.cpp): the substep's kernels enqueued in order,
// either directly (the CG loop driven from the host) or captured once into a CUDA graph whose CG
// loop is a conditional while node, launched each substep and captured again only when what it was
// recorded with changes.
#include "device_solver.h"

#include <vector>

#include "kernels.h"
#include "weft/error.h"

namespace weft::cuda {
namespace {

/// Host-driven CG (before the graph exists, or when graphs are off): iterations launched in batches of
/// this many, then one small copy of the `running` flag. Kernels after convergence do nothing.
constexpr int kHostCheckInterval = 8;
/// CG iterations in the body of the graph's while node.
constexpr int kIterationsPerGraphLoop = 2;

}  // namespace

void DeviceSolver::destroy_graph() {
    if (graph_exec_ != nullptr) cudaGraphExecDestroy(graph_exec_);
    graph_exec_ = nullptr;
    graph_active_ = false;
}

void DeviceSolver::record_pcg_loop(cudaStream_t stream, bool capturing, int newton) {
    (void)newton;
    if (persistent_grid_ > 0) {
        // The whole loop is one cooperative kernel, in a graph or not.
        launch_pcg_residual(view_, 0, schwarz_on_, stream);
        launch_pcg_persistent(view_, persistent_grid_, schwarz_on_, stream);
        return;
    }
    if (!capturing) {
        launch_pcg_residual(view_, 0, schwarz_on_, stream);
        // Host-driven loop: batches of iterations, then the `running` flag back.
        for (;;) {
            for (int k = 0; k < kHostCheckInterval; ++k) launch_pcg_iteration(view_, 0, schwarz_on_, stream);
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
    launch_pcg_residual(view_, handle, schwarz_on_, stream);
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
        for (int k = 0; k < kIterationsPerGraphLoop; ++k) launch_pcg_iteration(view_, handle, schwarz_on_, body_stream_);
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
    if (!capturing) substep_started_ = true;  // x0 and v0 now hold the substep's start (a fault rolls back to them)
    launch_pin_velocities(view_, stream);
    const bool contacts = view_.contacts.capacity > 0;
    // Offset contacts change from active to inactive with every evaluation: their incidence is built
    // after each (record_contact_evaluation), this one only for pair springs.
    const bool offset = offset_model_ != nullptr;
    // The incidence of this substep's contacts (timed with the substep's start, as "kinematics").
    if (contacts && !offset) launch_contact_incidence(view_, contacts_.sort_scratch(), stream);
    mark();
    for (int it = 0; it < newton; ++it) {
        launch_begin_newton(view_, stream);
        launch_shell_faces(view_, stream);  // the bending model per triangle's pass 1 (nothing with hinges)
        if (row_gather_)
            launch_assemble_rows(view_, stream);
        else
            launch_assemble_colors(view_, layout_.triangle_colors, layout_.hinge_colors, stream);
        if (contacts) record_contact_evaluation(stream);  // gathered by the PCG setup
        mark();
        launch_pcg_setup(view_, it == 0, schwarz_on_, stream);
        if (schwarz_on_) launch_schwarz_factor(view_, it, stream);
        mark();
        record_pcg_loop(stream, capturing, it);
        launch_pcg_finish(view_, stream);
        mark();
        if (line_search_model_ != nullptr && !capturing) line_search_halvings_ += line_search(stream);
        launch_newton_update(view_, stream);
        record_truncation(stream);
        mark();
    }
    launch_commit(view_, stream);
    mark();
}

void DeviceSolver::record_contact_evaluation(cudaStream_t stream) {
    launch_contact_evaluate(view_, stream);
    // Offset mode: the incidence of the pairs the evaluation found in contact (kInactiveContactBit).
    if (offset_model_ != nullptr)
        launch_contact_incidence(view_, contacts_.sort_scratch(), stream);
}

void DeviceSolver::record_truncation(cudaStream_t stream) {
    if (offset_model_ == nullptr) return;
    collisions_.enqueue_truncation(*offset_model_, view_.x0, view_.vk, view_.wk, view_.fixed, step_h_device(), stream);
}

void DeviceSolver::record_extra_newton(cudaStream_t stream) {
    // One Newton iteration over the contacts of the rerun detection, as in record() (offset mode only:
    // the evaluation builds their incidence).
    launch_begin_newton(view_, stream);
    launch_shell_faces(view_, stream);
    if (row_gather_)
        launch_assemble_rows(view_, stream);
    else
        launch_assemble_colors(view_, layout_.triangle_colors, layout_.hinge_colors, stream);
    if (view_.contacts.capacity > 0) record_contact_evaluation(stream);
    launch_pcg_setup(view_, false, schwarz_on_, stream);
    if (schwarz_on_) launch_schwarz_factor(view_, 1, stream);
    record_pcg_loop(stream, false, 1);
    launch_pcg_finish(view_, stream);
    if (line_search_model_ != nullptr) line_search_halvings_ += line_search(stream);
    launch_newton_update(view_, stream);
    record_truncation(stream);
    launch_commit(view_, stream);
}

void DeviceSolver::capture_graph() {
    destroy_graph();
    cudaStream_t stream = active_stream();
    cudaGraph_t graph = nullptr;
    // The capture enqueues nothing: its launches are counted per replay instead (graph_kernels_).
    const long long launches_before = thread_kernel_launches;
    WEFT_CUDA_CHECK(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal));
    try {
        record(stream, true);
        graph_kernels_ = thread_kernel_launches - launches_before;
        thread_kernel_launches = launches_before;
    } catch (...) {
        thread_kernel_launches = launches_before;
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
    graph_truncation_key_ = offset_model_ != nullptr ? collisions_.truncation_key(*offset_model_) | 1U : 0U;
}

void DeviceSolver::launch_substep(cudaStream_t stream, int newton_iterations) {
    recorded_newton_ = newton_iterations;
    const std::size_t event_count = 3 + kEventsPerNewton * static_cast<std::size_t>(recorded_newton_);
    if (events_.size() < event_count) {
        // Grows only when the Newton iteration count rises past what was seen (reported in memory).
        for (std::size_t k = events_.size(); k < event_count; ++k) {
            cudaEvent_t ev = nullptr;
            WEFT_CUDA_CHECK(cudaEventCreate(&ev));
            events_.push_back(ev);
        }
    }

    // Offset contact's truncation is captured too; the graph is captured again when its buffers grew
    // or its settings changed (DeviceCollisions::truncation_key), or when offset contact is switched.
    const std::uint64_t truncation_key = offset_model_ != nullptr ? collisions_.truncation_key(*offset_model_) | 1U : 0U;
    // A substep that line-searches reads energies back between the kernels: host-driven, while the
    // graph (if any) stays for the substeps that do not.
    const bool want_graph = use_graph_ && !graph_unsupported_ && warm_ && line_search_model_ == nullptr;
    if (want_graph &&
        (graph_exec_ == nullptr || graph_newton_ != recorded_newton_ || graph_truncation_key_ != truncation_key)) {
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
        thread_kernel_launches += graph_kernels_;
        substep_started_ = true;  // the graph's first kernel writes x0 and v0
        graph_active_ = true;
    } else {
        record(stream, false);
        graph_active_ = false;
    }
}

void DeviceSolver::set_use_graph(bool enabled) {
    use_graph_ = enabled;
    if (!enabled) destroy_graph();
}

}  // namespace weft::cuda
