// hello_cloth: a flag pinned along its left edge, flying in a gusty wind for 120 frames of 1/60 s.
// Prints the backend, the position of the flag's free bottom-right corner (m) and the mean step time.
// Runs on the CUDA backend when the package has one and a device answers, else on the CPU;
// `hello_cloth --cpu` forces the CPU backend (whose results are the same on every machine).
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

#include "weft/cloth.h"
#include "weft/fabric.h"
#include "weft/mesh.h"
#include "weft/world.h"
#if WEFT_HAVE_CUDA_BACKEND  // defined by the Weft::cuda target
#include "weft/cuda/cuda_backend.h"
#endif

int main(int argc, char** argv) {
    const bool force_cpu = argc > 1 && std::string_view(argv[1]) == "--cpu";
    std::string backend = "cpu", why = force_cpu ? "forced by --cpu" : "built without the CUDA backend";
#if WEFT_HAVE_CUDA_BACKEND
    weft::cuda::register_cuda_backend();  // once, before a World asks for "cuda"
    if (!force_cpu) {
        why = weft::cuda::unavailable_reason();  // "" when a device answers
        if (why.empty()) {
            backend = "cuda";
            why = weft::cuda::devices().front().name;
        }
    }
#endif
    weft::WorldDesc desc;  // gravity −9.81 m/s² along y, one implicit substep per 1/60 s frame
    desc.wind.velocity = {6.0, 0.0, 1.5};  // m/s, mostly along the flag, a little across it
    desc.wind.turbulence = 1.5;            // m/s of gusts on top
    weft::World world(desc, backend);

    constexpr int kCellsX = 30, kCellsY = 20;  // a 1.5 m × 1.0 m flag, vertex (i, j) = j·31 + i
    weft::ClothDesc flag{.name = "flag",
                         .fabric = weft::Fabric::cook(weft::make_grid(1.5, 1.0, kCellsX, kCellsY), {.density = 0.12})};
    flag.transform.translation = {0.75, 2.0, 0.0};  // left edge on the pole at x = 0
    for (int j = 0; j <= kCellsY; ++j) flag.pins.push_back({.vertex = static_cast<std::uint32_t>(j * (kCellsX + 1))});
    const std::size_t cloth = world.add_cloth(flag);

    double total_ms = 0.0;
    constexpr int kFrames = 120;
    for (int frame = 0; frame < kFrames; ++frame) {
        const weft::StepStats& stats = world.step();
        if (!stats.ok()) std::printf("frame %d: the solver reported trouble (weft::StepStats::ok)\n", frame);
        total_ms += stats.step_ms;
    }
    const weft::Vec3d tip = world.positions(cloth)[kCellsX];  // vertex (30, 0): bottom-right corner
    std::printf("backend: %s (%s)\n", backend.c_str(), why.c_str());
    std::printf("tip position after %d frames (m): %.9f %.9f %.9f\n", kFrames, tip.x, tip.y, tip.z);
    std::printf("mean step time: %.3f ms\n", total_ms / kFrames);
}
