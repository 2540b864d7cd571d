#pragma once
/// @file
/// The backend interface and its factory. The CPU backend lives in `runtime/`; the CUDA backends
/// register themselves from `cuda/` through `register_backend()`.

#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "weft/interop.h"
#include "weft/model.h"
#include "weft/stats.h"

namespace weft {

/// A simulation backend. It owns the simulation state (on the host or a device) and steps it.
/// Threading: one thread drives a backend at a time.
class Backend {
public:
    virtual ~Backend() = default;
    Backend() = default;
    Backend(const Backend&) = delete;
    Backend& operator=(const Backend&) = delete;

    /// Short name used on the command line ("cpu", "cuda").
    [[nodiscard]] virtual std::string_view name() const = 0;
    /// Human-readable description of where it runs (CPU model and threads, GPU name).
    [[nodiscard]] virtual std::string device_description() const = 0;
    /// Builds all state for `model`: every allocation happens here, none in `substep()`.
    /// Initial positions come from each cloth's fabric and transform.
    virtual void build(const Model& model) = 0;
    /// Advances one implicit substep of `h` seconds starting at time `t`, reading the current
    /// parameters of `model`, and adds its counters and stage times to `stats`.
    virtual void substep(const Model& model, double t, double h, StepStats& stats) = 0;
    /// Copies a cloth's positions (m) and velocities (m/s) out, converting to double.
    virtual void read_state(std::size_t cloth, std::span<Vec3d> positions, std::span<Vec3d> velocities) const = 0;
    /// Overwrites a cloth's positions and velocities (reset, editing, tests).
    virtual void write_state(std::size_t cloth, std::span<const Vec3d> positions, std::span<const Vec3d> velocities) = 0;
    /// Bytes of simulation state held (host or device).
    [[nodiscard]] virtual std::size_t memory_bytes() const = 0;
    /// Zero-copy output (weft/interop.h): imports `slots` (each holds one 24-byte vertex per world
    /// vertex, positions then normals in float, then kSlotStampBytes) made on the GPU `device`, and
    /// returns their writer. The fds belong to the backend from the call on, imported or closed.
    /// nullptr, with the reason in `why`, where the backend cannot (host memory, another GPU).
    [[nodiscard]] virtual std::unique_ptr<SharedOutput> share_output(std::span<const SharedSlotHandle> slots,
                                                                     const DeviceUuid& device, std::string& why);
};

/// How a host thread waits for the GPU (a step's statistics, a synchronous output). The trade:
/// `spin` answers within microseconds but keeps a core busy for the whole wait, the frame's CPU time
/// then equals its GPU time; `block` sleeps on an OS primitive and frees the core for the game, at a
/// wake-up cost of tens of microseconds per wait; `yield` spins but yields the core between polls.
/// On the CUDA backend it sets the device's scheduling flags, which hold for the whole process on
/// that device (cudaDeviceScheduleSpin/Yield/BlockingSync/Auto). The CPU backend has no such wait.
enum class HostWait {
    automatic,  ///< the driver's choice (CUDA: spin while there are fewer busy contexts than cores)
    spin,
    yield,
    block,
};

/// "auto", "spin", "yield", "block".
[[nodiscard]] const char* host_wait_name(HostWait wait);
/// The inverse of host_wait_name; throws weft::Error naming `text` and the choices.
[[nodiscard]] HostWait parse_host_wait(std::string_view text);

/// Options a backend factory receives.
struct BackendOptions {
    int threads = 0;   ///< CPU threads, 0 = all
    int device = 0;    ///< first GPU
    int gpus = 1;      ///< number of GPUs
    HostWait host_wait = HostWait::automatic;  ///< how the host waits for a GPU backend
};

using BackendFactory = std::function<std::unique_ptr<Backend>(const BackendOptions&)>;

/// Registers a backend under `name` (replacing one of the same name).
void register_backend(std::string name, std::string description, BackendFactory factory);
/// Creates the backend called `name`; throws `weft::Error` listing the compiled backends if unknown.
[[nodiscard]] std::unique_ptr<Backend> create_backend(std::string_view name, const BackendOptions& options = {});
/// Names of the registered backends, "cpu" first.
[[nodiscard]] std::vector<std::string> backend_names();
/// Description registered with a backend name.
[[nodiscard]] std::string backend_description(std::string_view name);

}  // namespace weft
