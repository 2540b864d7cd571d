// The "cuda" backend on several GPUs (multi/multi_gpu_backend.h).
#include "multi/multi_gpu_backend.h"

#include <cstdint>
#include <cstdlib>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cuda_check.h"
#include "device_memory_budget.h"
#include "pcg_loop_environment.h"
#include "multi/multi_solver.h"
#include "shared_output.h"
#include "weft/backend/flat_model.h"
#include "weft/cuda/cuda_backend.h"
#include "weft/error.h"

namespace weft::cuda::multi {
namespace {

/// What one GPU runs and several do not yet: the mid-edge bending model, whose normals are one solve
/// over the whole cloth (its CG would need the parts to meet every iteration).
void require_multi_gpu_support(const SolverSettings& settings) {
    if (settings.bending == BendingModel::MidEdge)
        throw Error("cuda backend on several GPUs: solver.bending = \"midedge\" (the mid-edge bending model) runs on one GPU "
                    "or the cpu backend so far; use --gpus 1, solver.bending = \"hinge\" or --backend cpu");
}


class MultiGpuBackend final : public Backend, public CudaBackendApi {
public:
    MultiGpuBackend(std::vector<int> devices, DeviceInfo display, std::string description, std::size_t memory_limit)
        : budget_(memory_limit), solver_(std::move(devices)), display_(std::move(display)), description_(std::move(description)) {}

    std::string_view name() const override { return "cuda"; }

    std::string device_description() const override {
        std::string out = description_ + ", float, " + std::to_string(solver_.parts()) + " parts, CG across parts";
        if (flat_.vertex_count > 0) {
            const PartitionQuality& q = solver_.partition().quality;
            out += " (" + std::to_string(q.halo_vertices) + " ghost vertices, " + std::to_string(solver_.halo_bytes()) +
                   " bytes between GPUs per exchange), " + (solver_.schwarz_active() ? "MAS preconditioner" : "block-Jacobi") +
                   (solver_.one_launch_cg() ? ", one-launch CG per GPU" : ", CG in graph batches");
        }
        return out;
    }

    void build(const Model& model) override {
        require_multi_gpu_support(model.settings.solver);
        const BudgetScope scope(&budget_);
        flat_ = flatten(model);
        solver_.build(flat_, model);
    }

    void substep(const Model& model, double t, double h, StepStats& stats) override {
        require_multi_gpu_support(model.settings.solver);
        const BudgetScope scope(&budget_);
        const long long launches_before = thread_kernel_launches;  // the shares' threads add theirs
        solver_.substep(model, t, h, stats);
        stats.kernels_launched += thread_kernel_launches - launches_before + audit_kernels_;
        audit_kernels_ = 0;
    }

    // The warm start, in the one-GPU layout: a checkpoint moves between part counts and one GPU.
    std::vector<std::uint8_t> solver_state() const override { return solver_.solver_state(); }
    void restore_solver_state(std::span<const std::uint8_t> bytes) override { solver_.restore_solver_state(bytes); }

    void read_state(std::size_t cloth, std::span<Vec3d> x, std::span<Vec3d> v) const override {
        const auto [first, count] = flat_.cloth_vertices(cloth, x.size(), v.size());
        solver_.read_state(first, count, x.data(), v.data());
    }

    void write_state(std::size_t cloth, std::span<const Vec3d> x, std::span<const Vec3d> v) override {
        const auto [first, count] = flat_.cloth_vertices(cloth, x.size(), v.size());
        solver_.write_state(first, count, x.data(), v.data());
    }

    bool contact_vertices(std::size_t cloth, std::vector<std::uint32_t>& out) const override {
        const std::uint32_t first = flat_.cloth_vertex_offset.at(cloth), end = flat_.cloth_vertex_offset.at(cloth + 1);
        solver_.contact_vertices(first, end - first, out);
        return true;
    }

    bool collider_contact_vertices(std::size_t cloth, std::vector<std::uint32_t>& out) const override {
        const std::uint32_t first = flat_.cloth_vertex_offset.at(cloth), end = flat_.cloth_vertex_offset.at(cloth + 1);
        solver_.collider_contact_vertices(first, end - first, out);
        return true;
    }

    // Summed on the devices (energy_kernels.cu, each part counting what it owns): no state read back.
    EnergyAudit energy_audit(const Model& model, double t, double h, bool with_wind) const override {
        const BudgetScope scope(&budget_);
        const long long launches_before = thread_kernel_launches;
        const EnergyAudit audit = solver_.energy_audit(model, t, h, with_wind);
        audit_kernels_ += thread_kernel_launches - launches_before;  // reported with the next substep
        return audit;
    }

    std::size_t memory_bytes() const override { return solver_.memory_bytes(); }
    MultiSolver& solver() { return solver_; }
    DeviceMemoryBudget& budget() { return budget_; }

    // The renderer's slots on the first GPU: every part's vertices gathered there, then copied into
    // the slot on that GPU (MultiSolver::set_output); no byte through the host.
    std::unique_ptr<SharedOutput> share_output(std::span<const SharedSlotHandle> slots, const DeviceUuid& device,
                                               std::string& why) override {
        return make_shared_output(output_source(solver_), display_, slots, device, why);
    }
    std::vector<std::pair<std::string, std::size_t>> memory_breakdown() const override { return solver_.memory_breakdown(); }

    // ---- CudaBackendApi ---------------------------------------------------------------------------
    void set_stream(CUstream_st* stream) override { solver_.set_stream(stream); }
    CUstream_st* stream() const override { return solver_.stream(); }
    // Each part writes its owned vertices into a buffer on the first GPU (peer writes), copied there.
    void set_output(void* device_buffer, std::size_t stride) override { solver_.set_output(device_buffer, stride); }
    std::size_t vertex_count() const override { return flat_.vertex_count; }
    void set_use_graph(bool enabled) override { solver_.set_use_graph(enabled); }
    bool graph_active() const override { return solver_.graph_active(); }
    void set_assembly(AssemblyStrategy strategy) override { solver_.set_assembly(strategy); }
    void set_pcg_loop(PcgLoop loop) override { solver_.set_pcg_loop(loop); }

private:
    mutable DeviceMemoryBudget budget_;  // before the solver: its arrays give their bytes back to it
    /// Kernels of the energy guard's audits since the last substep (StepStats::kernels_launched).
    mutable long long audit_kernels_ = 0;
    mutable MultiSolver solver_;  // the audit enqueues work on the parts' streams
    FlatModel flat_;
    DeviceInfo display_;          // the first GPU: where the output lives
    std::string description_;
};

}  // namespace

MultiSolver* multi_solver(Backend& backend) {
    auto* b = dynamic_cast<MultiGpuBackend*>(&backend);
    return b != nullptr ? &b->solver() : nullptr;
}

DeviceMemoryBudget* multi_gpu_budget(Backend& backend) {
    auto* b = dynamic_cast<MultiGpuBackend*>(&backend);
    return b != nullptr ? &b->budget() : nullptr;
}

std::unique_ptr<Backend> make_multi_gpu_backend(const BackendOptions& options) {
    const std::vector<DeviceInfo> all = cuda::devices();
    if (all.empty()) throw Error("CUDA backend: " + unavailable_reason());
    const char* env = std::getenv(kPartsOnOneDeviceEnv);
    const bool one_device = env != nullptr && std::string_view(env) == "1";
    const int count = static_cast<int>(all.size());
    if (options.device < 0 || options.device >= count)
        throw Error("CUDA backend: device " + std::to_string(options.device) + " does not exist (" + std::to_string(count) +
                    " CUDA device" + (count == 1 ? "" : "s") + ")");
    if (!one_device && options.device + options.gpus > count)
        throw Error("CUDA backend: --gpus " + std::to_string(options.gpus) + " from device " + std::to_string(options.device) +
                    " needs " + std::to_string(options.device + options.gpus) + " CUDA devices; this host has " +
                    std::to_string(count) + " (" + kPartsOnOneDeviceEnv + "=1 runs the parts on one GPU, for testing)");
    std::vector<int> devices;
    std::string description;
    for (int p = 0; p < options.gpus; ++p) {
        const int d = one_device ? options.device : options.device + p;
        devices.push_back(d);
        if (p == 0 || !one_device)
            description += (p == 0 ? "" : " + ") + all[static_cast<std::size_t>(d)].name;
    }
    if (one_device) description += " (" + std::to_string(options.gpus) + " parts on one GPU: test mode)";
    const DeviceInfo display = all[static_cast<std::size_t>(options.device)];  // the first part's GPU
    auto backend = std::make_unique<MultiGpuBackend>(std::move(devices), display, std::move(description),
                                                    options.device_memory_limit);
    // WEFT_CUDA_GRAPHS=0: the same kernels without graphs, as on one GPU.
    if (const char* graphs = std::getenv("WEFT_CUDA_GRAPHS"); graphs != nullptr && std::string_view(graphs) == "0")
        backend->set_use_graph(false);
    // WEFT_CUDA_PCG=one|kernels: the one-launch loop per GPU or the graph batches, as on one GPU.
    if (const auto loop = pcg_loop_from_environment()) backend->set_pcg_loop(*loop);
    return backend;
}

}  // namespace weft::cuda::multi
