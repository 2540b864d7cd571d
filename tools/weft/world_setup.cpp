#include "world_setup.h"

#include <algorithm>
#include <string>

#include "weft/backend/backend.h"
#include "weft/backend_options.h"
#include "weft/error.h"

#include "scene_lookup.h"

namespace weft::cli {

std::string resolve_backend(std::string_view backend) {
    if (backend != "auto") return std::string(backend);
    // The CUDA backend when it is compiled in and a device answers; the CPU otherwise.
    const std::vector<std::string> names = backend_names();
    if (std::find(names.begin(), names.end(), "cuda") != names.end()) {
        try {
            (void)create_backend("cuda");
            return "cuda";
        } catch (const std::exception&) {
        }
    }
    return "cpu";
}

void require_backend(std::string_view command, std::string_view backend) {
    if (backend == "auto") return;
    const std::vector<std::string> names = backend_names();
    if (std::find(names.begin(), names.end(), backend) != names.end()) return;
    std::string known;
    for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
    throw UsageError(std::string(command),
                     "--backend: unknown backend '" + std::string(backend) + "' (compiled backends: " + known + ")");
}

LoadedScene load_world(std::string_view scene, const SimulationOptions& sim) {
    LoadedScene loaded;
    loaded.desc = load_scene(find_scene(scene), sim.overrides);
    BackendOptions options;
    options.threads = sim.threads;
    options.host_wait = sim.host_wait;
    options.gpus = sim.gpus;
    const std::string backend = resolve_backend(sim.backend);
    if (sim.gpus > 1 && backend != "cuda")
        throw Error("--gpus " + std::to_string(sim.gpus) + " splits the world across GPUs, which only the cuda backend does (this run "
                    "uses '" + backend + "')");
    if (sim.device_memory_limit_mib > 0 && backend != "cuda")
        throw Error("--device-memory-limit caps a GPU backend's device memory; this run uses '" + backend + "'");
    options.device_memory_limit = static_cast<std::size_t>(sim.device_memory_limit_mib) << 20;
    loaded.world = build_world(loaded.desc, backend, options);
    return loaded;
}

}  // namespace weft::cli
