#pragma once
/// @file
/// The CUDA backend on one GPU (`--backend cuda`). Link `Weft::cuda` (in the tree also `weft::cuda`)
/// and call `register_cuda_backend()` once; `weft::World(desc, "cuda")` then steps the whole substep
/// on the device: forces, assembly, PCG, pins, colliders and wind, in float, as one CUDA graph once warm.
/// The target defines `WEFT_HAVE_CUDA_BACKEND=1` for its users, so a game that builds with and without
/// CUDA includes this header and makes the call under `#if WEFT_HAVE_CUDA_BACKEND`
/// (examples/hello_cloth/main.cpp, examples/README.md).
///
/// Beyond the generic `weft::Backend` interface it offers the stream and buffer hooks a renderer
/// needs: the step runs on a stream the caller gives, and its last kernel writes positions and
/// normals into a device buffer the caller owns (e.g. Vulkan memory imported into CUDA).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "weft/backend/backend.h"

// The CUDA runtime types are only named here, so users of this header need not include CUDA.
struct CUstream_st;

namespace weft::cuda {

/// One CUDA device as the backend sees it.
struct DeviceInfo {
    int ordinal = 0;
    std::string name;
    int compute_major = 0, compute_minor = 0;
    std::size_t memory_bytes = 0;   ///< global memory
    int multiprocessors = 0;
    std::uint8_t uuid[16]{};        ///< matched against Vulkan's deviceUUID for interop
};

/// The devices the CUDA runtime sees; empty (never throws) when there is no driver or no GPU.
[[nodiscard]] std::vector<DeviceInfo> devices();

/// Why `devices()` is empty ("no CUDA driver", "no CUDA-capable device"), or "" when it is not.
[[nodiscard]] std::string unavailable_reason();

/// Registers the "cuda" backend with the runtime's factory (idempotent). Creating it throws
/// `weft::Error` when no device is present: check `devices()` first to fall back to "cpu".
/// Nothing registers the backend implicitly (a static registrar could be dropped by the linker
/// from a static library); this one call is all a program needs.
void register_cuda_backend();

/// Layout of one vertex in the output buffer: position (m) then unit normal, both float.
struct OutputVertex {
    float position[3];
    float normal[3];
};

/// How the CUDA backend assembles A·Δv = b (docs/architecture.md, "The CUDA backend"). Both give
/// the same physics and differ only in float rounding order.
enum class AssemblyStrategy : std::uint8_t {
    Auto,        ///< row gather up to 20,000 vertices, colour passes above (measured crossover)
    RowGather,   ///< one warp per matrix row; one launch; elements evaluated once per corner
    ColorPasses, ///< one launch per element colour; elements evaluated once; the matrix streamed per pass
};

/// How the CUDA backend drives the CG loop. Same algorithm and stopping rule; the dot products are
/// summed in a different order, so the two differ in float rounding only.
enum class PcgLoop : std::uint8_t {
    Auto,       ///< one launch up to 200,000 vertices or wherever contacts enter the solve, per-iteration kernels above (measured); several GPUs: one launch per GPU where each part has its own
    OneLaunch,  ///< the whole loop in one cooperative kernel with grid-wide barriers: least latency
    PerKernel,  ///< three kernels per iteration under a graph while node: most bandwidth on large cloth
};

/// The CUDA-specific part of the backend. Obtain it with `as_cuda(world.backend())`.
class CudaBackendApi {
public:
    virtual ~CudaBackendApi() = default;
    /// Runs every later substep on `stream` (nullptr: the backend's own stream). The backend
    /// still synchronises with the stream at the end of `substep()` to report stats.
    virtual void set_stream(CUstream_st* stream) = 0;
    /// The stream the substeps run on (the one given to set_stream, or the backend's own).
    [[nodiscard]] virtual CUstream_st* stream() const = 0;
    /// After every substep, writes one `OutputVertex` per vertex of the world (cloths concatenated in
    /// order) to `device_buffer`, `stride` bytes apart, and waits for the write: the buffer is
    /// complete when step() returns. nullptr stops it. The buffer must hold `vertex_count` entries
    /// and stay valid until unbound. (A renderer sharing its buffers uses `Backend::share_output`
    /// instead, ordered by timeline semaphores without host waits.)
    virtual void set_output(void* device_buffer, std::size_t stride = sizeof(OutputVertex)) = 0;
    /// Total vertices of the world as laid out in the output buffer.
    [[nodiscard]] virtual std::size_t vertex_count() const = 0;
    /// Uses a CUDA graph per substep once warm (default on); off runs the same kernels launched
    /// one by one with a convergence check every few CG iterations. Both give identical results.
    virtual void set_use_graph(bool enabled) = 0;
    /// Whether the last substep ran as a graph with the CG loop on the device.
    [[nodiscard]] virtual bool graph_active() const = 0;
    /// Chooses the assembly strategy (default Auto); takes effect at the next substep.
    virtual void set_assembly(AssemblyStrategy strategy) = 0;
    /// Chooses how the CG loop runs (default Auto); takes effect at the next substep.
    virtual void set_pcg_loop(PcgLoop loop) = 0;
    /// Device memory held by the solver, bytes, split by purpose (for benchmarks and stats).
    [[nodiscard]] virtual std::vector<std::pair<std::string, std::size_t>> memory_breakdown() const = 0;
};

/// The CUDA interface of `backend`, or nullptr if it is not the CUDA backend.
[[nodiscard]] CudaBackendApi* as_cuda(Backend& backend);

}  // namespace weft::cuda
