#pragma once
// Shared helpers of the GPU tests. They build and are registered on every machine with nvcc, but
// most CI machines have no GPU: there each test must show as SKIPPED with the reason, not pass
// silently and not fail.

#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cuda_check.h"
#include "weft/cuda/cuda_backend.h"
#include "weft/scene.h"
#include "weft/world.h"
#include "weft/backend/backend.h"
#include "weft/backend/energy_audit.h"

/// Registers the "cuda" backend, then skips the current test (with the CUDA runtime's reason) when
/// no device is present. Use it first thing in every test that touches the GPU.
#define WEFT_REQUIRE_GPU()                                                                                             \
    do {                                                                                                               \
        ::weft::cuda::register_cuda_backend();                                                                         \
        if (::weft::cuda::devices().empty()) GTEST_SKIP() << "no CUDA device: " << ::weft::cuda::unavailable_reason(); \
    } while (false)

namespace weft::test {

/// A non-blocking CUDA stream, destroyed with the holder.
struct Stream {
    cudaStream_t s = nullptr;
    Stream() { WEFT_CUDA_CHECK(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking)); }
    ~Stream() { cudaStreamDestroy(s); }
    Stream(const Stream&) = delete;
    Stream& operator=(const Stream&) = delete;
};

/// assets/scenes/NAME.toml of the source tree.
inline std::filesystem::path scene_file(const std::string& name) {
    return std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / (name + ".toml");
}

/// The world of shipped scene `scene` with `overrides` (KEY=VALUE), on `backend`.
inline std::unique_ptr<World> make_world(const std::string& scene, const std::string& backend,
                                         const std::vector<std::string>& overrides = {}) {
    return build_world(load_scene(scene_file(scene), overrides), backend);
}

/// Grabs cloth 0's last vertex (away from the flag's pole, whose vertex 0 is pinned) and pulls it
/// 10 cm along +x, then takes one step: a world with the grab spring working on it.
inline void grab_last_vertex_and_step(World& world) {
    const auto x = world.positions(0);
    const auto v = static_cast<std::uint32_t>(x.size() - 1);
    world.set_grab(VertexGrab{.cloth = 0, .vertex = v, .target = x[v] + Vec3d{0.1, 0.0, 0.0}, .stiffness = 50.0, .damping = 0.1});
    (void)world.step();
}

/// The energy guard's audit of `world`'s backend at its current time, summed where the backend sums
/// it (on the device) and by the host's reference over the state read back, with the wind's power.
struct AuditPair {
    EnergyAudit device, host;
    double scale = 0.0;  ///< |K| + |G| + |U| + C of the host's: what a difference is measured against
};
inline AuditPair audit_device_and_host(World& world) {
    const Model& model = world.model();
    const double t = world.time(), h = model.settings.solver.dt / model.settings.solver.substeps;
    Backend& backend = world.backend();
    AuditPair a;
    a.device = backend.energy_audit(model, t, h, true);
    a.host = backend.Backend::energy_audit(model, t, h, true);
    a.scale = std::abs(a.host.kinetic) + std::abs(a.host.gravity) + std::abs(a.host.elastic) + a.host.contact;
    return a;
}

}  // namespace weft::test
