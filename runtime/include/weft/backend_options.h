#pragma once
/// @file
/// Choosing and configuring the backend that steps a `World`: its name ("cpu", "cuda", …) and
/// `BackendOptions`. The backends themselves are behind a factory (weft/backend/backend.h).

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace weft {

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
    int gpus = 0;      ///< GPUs one world is split across; 0 = the scene's `solver.gpus` (1 unless set)
    HostWait host_wait = HostWait::automatic;  ///< how the host waits for a GPU backend
    /// Bytes of device memory the backend may hold on each GPU; 0 = as much as the device has. A
    /// scene that needs more fails at build, a buffer that would grow past it fails the substep,
    /// each with the bytes asked for, held and free (docs/design.md, "Device faults").
    std::size_t device_memory_limit = 0;
};

/// Names of the registered backends, "cpu" first.
[[nodiscard]] std::vector<std::string> backend_names();
/// Description registered with a backend name.
[[nodiscard]] std::string backend_description(std::string_view name);

}  // namespace weft
