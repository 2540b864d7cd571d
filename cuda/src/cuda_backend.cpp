// The "cuda" backend: a weft::Backend around one DeviceSolver, registered with the runtime's factory.
#include "weft/cuda/cuda_backend.h"

#include <cuda_runtime_api.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>

#include "backend_access.h"
#include "cuda_check.h"
#include "device_solver.h"
#include "multi/multi_gpu_backend.h"
#include "device_memory_budget.h"
#include "pcg_loop_environment.h"
#include "shared_output.h"
#include "weft/error.h"
#include "weft/backend/flat_model.h"

namespace weft::cuda {
namespace {

std::string format_gib(std::size_t bytes) {
    const double gib = static_cast<double>(bytes) / (1024.0 * 1024.0 * 1024.0);
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.0f GiB", gib);
    return buf;
}

// The device's scheduling flags (weft/backend/backend.h, HostWait). They belong to the device's primary
// context, so they hold for every backend of the process on that device; setting them on a context
// already in use replaces the flags it had (CUDA 11 and later).
void set_host_wait(int device, HostWait wait) {
    unsigned flag = cudaDeviceScheduleAuto;
    if (wait == HostWait::spin) flag = cudaDeviceScheduleSpin;
    if (wait == HostWait::yield) flag = cudaDeviceScheduleYield;
    if (wait == HostWait::block) flag = cudaDeviceScheduleBlockingSync;
    WEFT_CUDA_CHECK(cudaSetDevice(device));
    if (const cudaError_t e = cudaSetDeviceFlags(flag); e != cudaSuccess)
        throw Error(std::string("CUDA backend: host wait '") + host_wait_name(wait) + "' could not be set on device " +
                    std::to_string(device) + ": " + cudaGetErrorString(e));
}

class CudaBackend final : public Backend, public CudaBackendApi {
public:
    explicit CudaBackend(const BackendOptions& options) : budget_(options.device_memory_limit) {
        const std::vector<DeviceInfo> all = devices();
        if (all.empty()) throw Error("CUDA backend: " + unavailable_reason());
        if (options.device < 0 || options.device >= static_cast<int>(all.size()))
            throw Error("CUDA backend: device " + std::to_string(options.device) + " does not exist (" +
                        std::to_string(all.size()) + " CUDA device" + (all.size() == 1 ? "" : "s") + ")");
        info_ = all[static_cast<std::size_t>(options.device)];
        set_host_wait(info_.ordinal, options.host_wait);
        solver_ = std::make_unique<DeviceSolver>(info_.ordinal);
        // WEFT_CUDA_GRAPHS=0 runs the same kernels without graphs: for tools that cannot follow
        // conditional graph nodes (compute-sanitizer's racecheck) and for comparing the two paths.
        if (const char* env = std::getenv("WEFT_CUDA_GRAPHS"); env != nullptr && std::string_view(env) == "0")
            solver_->set_use_graph(false);
        // WEFT_CUDA_ASSEMBLY=rows|colors picks an assembly strategy for benchmarks and A/B runs.
        if (const char* env = std::getenv("WEFT_CUDA_ASSEMBLY"); env != nullptr) {
            const std::string_view v(env);
            if (v == "rows")
                solver_->set_assembly(AssemblyStrategy::RowGather);
            else if (v == "colors")
                solver_->set_assembly(AssemblyStrategy::ColorPasses);
            else if (v != "auto")
                throw Error("WEFT_CUDA_ASSEMBLY='" + std::string(v) + "': expected rows, colors or auto");
        }
        if (const auto loop = pcg_loop_from_environment()) solver_->set_pcg_loop(*loop);
    }

    std::string_view name() const override { return "cuda"; }

    std::string device_description() const override {
        return info_.name + " (sm_" + std::to_string(info_.compute_major) + std::to_string(info_.compute_minor) + ", " +
               format_gib(info_.memory_bytes) + "), float" + (solver_->graph_active() ? ", CUDA graph" : "") +
               (flat_.vertex_count == 0 ? ""  // strategies are chosen by size at build
                                        : std::string(solver_->row_gather() ? ", row-gather assembly" : ", colour-pass assembly") +
                                              (solver_->persistent_grid() > 0 ? ", one-launch CG" : ", per-kernel CG") +
                                              (solver_->schwarz_active() ? ", MAS preconditioner" : ""));
    }

    // Cloth collisions (self-collision, mesh colliders) run in the device solver's collision stages
    // (device_collisions.h; impact zones on the host for now); self-collision switched on or off live
    // rebuilds them at the next substep.
    void build(const Model& model) override {
        const BudgetScope scope(&budget_);
        flat_ = flatten(model);
        solver_->build(flat_, model);
    }

    // Fast analytic colliders are swept per vertex after the solve, in the device solver as on the CPU.
    void substep(const Model& model, double t, double h, StepStats& stats) override {
        const BudgetScope scope(&budget_);
        const long long launches_before = thread_kernel_launches;
        solver_->substep(model, t, h, stats);
        stats.kernels_launched += thread_kernel_launches - launches_before + audit_kernels_;
        audit_kernels_ = 0;
    }

    std::vector<std::uint8_t> solver_state() const override { return solver_->solver_state(); }
    void restore_solver_state(std::span<const std::uint8_t> bytes) override { solver_->restore_solver_state(bytes); }

    void read_state(std::size_t cloth, std::span<Vec3d> x, std::span<Vec3d> v) const override {
        const auto [first, count] = flat_.cloth_vertices(cloth, x.size(), v.size());
        solver_->read_state(first, count, x.data(), v.data());
    }

    bool contact_vertices(std::size_t cloth, std::vector<std::uint32_t>& out) const override {
        const std::uint32_t first = flat_.cloth_vertex_offset.at(cloth), end = flat_.cloth_vertex_offset.at(cloth + 1);
        solver_->contact_vertices(first, end - first, out);
        return true;
    }

    bool collider_contact_vertices(std::size_t cloth, std::vector<std::uint32_t>& out) const override {
        const std::uint32_t first = flat_.cloth_vertex_offset.at(cloth), end = flat_.cloth_vertex_offset.at(cloth + 1);
        solver_->collider_contact_vertices(first, end - first, out);
        return true;
    }

    void write_state(std::size_t cloth, std::span<const Vec3d> x, std::span<const Vec3d> v) override {
        const auto [first, count] = flat_.cloth_vertices(cloth, x.size(), v.size());
        solver_->write_state(first, count, x.data(), v.data());
    }

    // The energy guard sums on the device (energy_kernels.cu): no state is read back.
    EnergyAudit energy_audit(const Model& model, double t, double h, bool with_wind) const override {
        const BudgetScope scope(&budget_);
        const long long launches_before = thread_kernel_launches;
        const EnergyAudit audit = solver_->energy_audit(model, t, h, with_wind);
        audit_kernels_ += thread_kernel_launches - launches_before;  // reported with the next substep
        return audit;
    }

    std::size_t memory_bytes() const override { return solver_->memory_bytes(); }

    std::unique_ptr<SharedOutput> share_output(std::span<const SharedSlotHandle> slots, const DeviceUuid& device,
                                               std::string& why) override {
        return make_shared_output(output_source(*solver_), info_, slots, device, why);
    }

    void set_stream(CUstream_st* stream) override { solver_->set_stream(stream); }
    CUstream_st* stream() const override { return solver_->stream(); }
    void set_output(void* device_buffer, std::size_t stride) override { solver_->set_output(device_buffer, stride); }
    std::size_t vertex_count() const override { return flat_.vertex_count; }
    void set_use_graph(bool enabled) override { solver_->set_use_graph(enabled); }
    bool graph_active() const override { return solver_->graph_active(); }
    void set_assembly(AssemblyStrategy strategy) override { solver_->set_assembly(strategy); }
    void set_pcg_loop(PcgLoop loop) override { solver_->set_pcg_loop(loop); }
    std::vector<std::pair<std::string, std::size_t>> memory_breakdown() const override { return solver_->memory_breakdown(); }

    DeviceSolver& solver() { return *solver_; }
    DeviceMemoryBudget& budget() { return budget_; }

private:
    DeviceInfo info_;
    FlatModel flat_;
    mutable DeviceMemoryBudget budget_;  // before the solver: its arrays give their bytes back to it
    /// Kernels of the energy guard's audits since the last substep (StepStats::kernels_launched).
    mutable long long audit_kernels_ = 0;
    std::unique_ptr<DeviceSolver> solver_;
};

}  // namespace

std::vector<DeviceInfo> devices() {
    int count = 0;
    if (cudaGetDeviceCount(&count) != cudaSuccess) {
        cudaGetLastError();  // clear the sticky "no driver" error
        return {};
    }
    std::vector<DeviceInfo> out;
    for (int d = 0; d < count; ++d) {
        cudaDeviceProp prop{};
        if (cudaGetDeviceProperties(&prop, d) != cudaSuccess) continue;
        DeviceInfo info;
        info.ordinal = d;
        info.name = prop.name;
        info.compute_major = prop.major;
        info.compute_minor = prop.minor;
        info.memory_bytes = prop.totalGlobalMem;
        info.multiprocessors = prop.multiProcessorCount;
        std::memcpy(info.uuid, prop.uuid.bytes, sizeof info.uuid);
        out.push_back(std::move(info));
    }
    return out;
}

std::string unavailable_reason() {
    int count = 0;
    const cudaError_t err = cudaGetDeviceCount(&count);
    if (err == cudaSuccess && count > 0) return {};
    cudaGetLastError();
    if (err == cudaErrorNoDevice || (err == cudaSuccess && count == 0)) return "no CUDA-capable device is present";
    if (err == cudaErrorInsufficientDriver)
        return "no usable CUDA driver (none installed, or one older than the CUDA " + std::to_string(CUDART_VERSION / 1000) +
               " runtime Weft was built with)";
    return std::string("no CUDA driver (") + cudaGetErrorName(err) + ")";
}

void register_cuda_backend() {
    static std::once_flag once;
    std::call_once(once, [] {
        register_backend("cuda", "CUDA backend, float: the whole substep on one GPU as a CUDA graph, or one world across --gpus N",
                         [](const BackendOptions& o) -> std::unique_ptr<Backend> {
                             if (o.gpus < 0) throw Error("CUDA backend: --gpus " + std::to_string(o.gpus) + " (at least 1)");
                             if (o.gpus > 1) return multi::make_multi_gpu_backend(o);
                             return std::make_unique<CudaBackend>(o);
                         });
    });
}

CudaBackendApi* as_cuda(Backend& backend) { return dynamic_cast<CudaBackendApi*>(&backend); }

DeviceSolver* device_solver(Backend& backend) {
    auto* b = dynamic_cast<CudaBackend*>(&backend);
    return b != nullptr ? &b->solver() : nullptr;
}

DeviceMemoryBudget* device_memory_budget(Backend& backend) {
    auto* b = dynamic_cast<CudaBackend*>(&backend);
    return b != nullptr ? &b->budget() : multi::multi_gpu_budget(backend);
}

}  // namespace weft::cuda
