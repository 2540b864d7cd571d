#pragma once
/// @file
/// The start of `run` and `bench`: check the backend name, find and load the scene with its
/// overrides, build the world.

#include <memory>
#include <string>
#include <string_view>

#include "weft/scene.h"
#include "weft/world.h"

#include "cli_args.h"

namespace weft::cli {

struct LoadedScene {
    SceneDesc desc;
    std::unique_ptr<World> world;
};

/// Throws `UsageError` (for `command`) when `backend` is not one of the compiled backends.
/// "auto" → "cuda" when that backend is compiled in and a device is present, else "cpu"; any other
/// name is returned unchanged.
[[nodiscard]] std::string resolve_backend(std::string_view backend);
void require_backend(std::string_view command, std::string_view backend);

/// Finds `scene` (path or bare name), loads it with `sim.overrides` and builds its world on
/// `sim.backend` with `sim.threads`. Throws `weft::Error` for a missing or bad scene.
[[nodiscard]] LoadedScene load_world(std::string_view scene, const SimulationOptions& sim);

}  // namespace weft::cli
