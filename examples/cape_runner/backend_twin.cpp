// cape_runner_twin: the cape_runner's level stepped on the CUDA backend and on the CPU backend side
// by side, the GPU world set to the CPU world's state before every step, so that each frame compares
// the two backends' collision handling from one state (a diagnostic, not a game; examples/README.md).
// Where the two runs of the game part (the GPU's contacts grow, zones run long, cloth goes through),
// the frames it prints say whether the GPU's step does it from a state the CPU stepped cleanly.
//
//   cape_runner_twin [--detail N] [--preset NAME] [--script FILE] [--frames N] [--character [FILE]]
//                    [--resync N] [--report N] [--strict]
//
// --resync N copies the CPU's state into the GPU world every N frames (default 1: every frame; 0:
// never, the two runs drift apart as the game's would). --report N prints at most N frames that
// differ (default 40). The preset is the same on both (default "game", the CPU game's). --strict
// exits 1 if a GPU step leaves cloth through something, or fails (a NaN rolled back or a runaway
// solve dropped), where the CPU's step does not (a test: the CPU is the reference; a frame where
// both fail is the CPU's trouble too, printed, not the GPU's). Exit 77: no CUDA device here (the test is skipped).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "input_script.h"
#include "level.h"
#include "runner.h"
#include "weft/presets.h"
#include "weft/world.h"
#if WEFT_HAVE_ASSETS
#include "weft/assets/skinned_import.h"
#endif
#include "weft/cuda/cuda_backend.h"

namespace {

using namespace cape_runner;

#ifdef CAPE_RUNNER_CHARACTER
constexpr const char* kShippedCharacter = CAPE_RUNNER_CHARACTER;
#else
constexpr const char* kShippedCharacter = "";
#endif

struct Options {
    int detail = 2;
    std::string preset = "game", script, character;
    int frames = 0, resync = 1, report = 40;
    bool strict = false;
};

constexpr int kExitNoDevice = 77;  // ctest's SKIP_RETURN_CODE

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        const auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw std::runtime_error(std::string(a) + " needs a value");
            return argv[++i];
        };
        if (a == "--detail") o.detail = std::stoi(value());
        else if (a == "--preset") o.preset = value();
        else if (a == "--script") o.script = value();
        else if (a == "--frames") o.frames = std::stoi(value());
        else if (a == "--resync") o.resync = std::stoi(value());
        else if (a == "--report") o.report = std::stoi(value());
        else if (a == "--strict") o.strict = true;
        else if (a == "--character") o.character = (i + 1 < argc && argv[i + 1][0] != '-') ? value() : kShippedCharacter;
        else throw std::runtime_error("unknown option " + std::string(a) + " (see the comment at the top of backend_twin.cpp)");
    }
    if (o.detail < 1 || o.detail > 4) throw std::runtime_error("--detail takes 1 to 4");
    if (o.resync < 0 || o.report < 0) throw std::runtime_error("--resync and --report take 0 or more");
    if (o.script.empty() && o.frames == 0) throw std::runtime_error("give --script or --frames");
#if !WEFT_HAVE_ASSETS
    if (!o.character.empty()) throw std::runtime_error("--character needs Weft's asset importer (Weft::assets), which this build lacks");
#endif
    return o;
}

/// One backend's account of a frame.
struct FrameFacts {
    weft::StepStats stats;
    long long cloth_through_cloth = 0, cloth_through_body = 0;
};

FrameFacts facts(const weft::StepStats& s) {
    FrameFacts f{.stats = s};
    f.cloth_through_body = s.collision.remaining_collider_intersections;
    f.cloth_through_cloth = s.collision.remaining_intersections - f.cloth_through_body;
    return f;
}

/// The largest distance (m) between a vertex on the GPU and the same vertex on the CPU.
double largest_gap(const weft::World& gpu, const weft::World& cpu) {
    double gap = 0.0;
    for (std::size_t c = 0; c < gpu.cloth_count(); ++c) {
        const std::vector<Vec3d> a = gpu.positions(c), b = cpu.positions(c);
        for (std::size_t i = 0; i < a.size(); ++i) gap = std::max(gap, weft::math::length(a[i] - b[i]));
    }
    return gap;
}

/// Every cloth vertex's position (m), cloth after cloth.
std::vector<Vec3d> all_positions(const weft::World& world) {
    std::vector<Vec3d> x;
    for (std::size_t c = 0; c < world.cloth_count(); ++c) {
        const std::vector<Vec3d> p = world.positions(c);
        x.insert(x.end(), p.begin(), p.end());
    }
    return x;
}

/// The farthest a vertex moved (m) from `before` to the world's positions now.
double farthest_move(const std::vector<Vec3d>& before, const weft::World& world) {
    const std::vector<Vec3d> after = all_positions(world);
    double d = 0.0;
    for (std::size_t i = 0; i < after.size(); ++i) d = std::max(d, weft::math::length(after[i] - before[i]));
    return d;
}

void copy_state(const weft::World& from, weft::World& to) {
    for (std::size_t c = 0; c < from.cloth_count(); ++c) to.set_state(c, from.positions(c), from.velocities(c));
}

/// Running sums of one backend's frames.
struct Totals {
    double step_ms = 0.0, zone_ms = 0.0, slowest_ms = 0.0;
    long long contacts = 0, zones = 0, frozen = 0, unresolved = 0, through_frames = 0;
    int most_rounds = 0;
    void add(const FrameFacts& f) {
        const weft::StepStats& s = f.stats;
        step_ms += s.step_ms;
        zone_ms += s.ms(weft::Stage::ImpactZones);
        slowest_ms = std::max(slowest_ms, s.step_ms);
        contacts += s.collision.contacts;
        zones += s.collision.impact_zones;
        frozen += s.collision.frozen_vertices;
        unresolved += s.collision.unresolved_substeps;
        through_frames += (f.cloth_through_cloth + f.cloth_through_body) > 0 ? 1 : 0;
        most_rounds = std::max(most_rounds, s.collision.impact_iterations);
    }
    void print(const char* name, int frames) const {
        const double n = std::max(frames, 1);
        std::printf("cape_runner_twin: %s: mean step %.2f ms (zones %.2f), slowest %.1f ms; contacts %.0f a frame, zones %.1f a "
                    "frame, at most %d rounds a substep; %lld vertices frozen, %lld substeps unresolved, cloth through "
                    "something after %lld frames\n",
                    name, step_ms / n, zone_ms / n, slowest_ms, static_cast<double>(contacts) / n, static_cast<double>(zones) / n,
                    most_rounds, frozen, unresolved, through_frames);
    }
};

/// A frame the two backends handled differently enough to look at (or one of them took over a second).
bool differs(const FrameFacts& g, const FrameFacts& c) {
    const auto& gs = g.stats.collision;
    const auto& cs = c.stats.collision;
    const bool through = (g.cloth_through_cloth + g.cloth_through_body) > 0 && (c.cloth_through_cloth + c.cloth_through_body) == 0;
    const bool more_contact = gs.contacts > 2 * std::max(cs.contacts, 50);
    const bool longer_zones = gs.impact_iterations > 2 * std::max(cs.impact_iterations, 2);
    const bool frozen = gs.frozen_vertices > 0 && cs.frozen_vertices == 0;
    return through || more_contact || longer_zones || frozen || g.stats.non_finite != c.stats.non_finite;
}

int twin(const Options& o) {
    weft::cuda::register_cuda_backend();
    if (const std::string why = weft::cuda::unavailable_reason(); !why.empty()) {
        std::printf("cape_runner_twin: skipped: the CUDA backend is not available here: %s\n", why.c_str());
        return kExitNoDevice;
    }
    weft::WorldDesc desc;
    desc.wind.velocity = {3.0, 0.0, 0.5};
    desc.wind.turbulence = 1.5;
    desc.collision.self_collision = true;
    desc.collision.check = true;  // both: the exact check after every step
    weft::apply_solver_preset(desc, o.preset);
    weft::World gpu(desc, "cuda"), cpu(desc, "cpu");
    std::shared_ptr<const weft::SkinnedMesh> skin;
#if WEFT_HAVE_ASSETS
    if (!o.character.empty()) skin = std::make_shared<const weft::SkinnedMesh>(weft::assets::import_skinned_mesh(o.character));
#endif
    Runner runner({0.0, 0.0, 0.0});
    const Level gpu_level = build_level(gpu, runner, o.detail, skin), cpu_level = build_level(cpu, runner, o.detail, skin);
    std::optional<InputScript> script;
    if (!o.script.empty()) script.emplace(o.script);
    std::printf("cape_runner_twin: detail %d, preset %s, the GPU set to the CPU's state every %d frames%s\n", o.detail,
                o.preset.c_str(), o.resync, o.resync == 0 ? " (never)" : "");

    constexpr double dt = 1.0 / 60.0;
    Totals gpu_totals, cpu_totals;
    int frame = 0, reported = 0, differing = 0, gpu_only_through = 0, gpu_failed = 0, cpu_failed = 0, gpu_only_failed = 0;
    double widest_gap = 0.0;
    while (true) {
        if (o.frames > 0 && frame >= o.frames) break;
        if (script && o.frames == 0 && cpu.time() > script->length() + 1.0) break;
        if (o.resync > 0 && frame % o.resync == 0) copy_state(cpu, gpu);
        const Controls c = script ? script->at(cpu.time()) : Controls{};
        runner.advance(c, dt);
        const std::vector<Vec3d> gpu_before = all_positions(gpu), cpu_before = all_positions(cpu);
        drive(gpu, gpu_level, runner, gpu.time(), dt);
        drive(cpu, cpu_level, runner, cpu.time(), dt);
        const FrameFacts g = facts(gpu.step()), k = facts(cpu.step());
        if ((g.cloth_through_cloth + g.cloth_through_body) > 0 && (k.cloth_through_cloth + k.cloth_through_body) == 0)
            ++gpu_only_through;
        // A NaN rolled back, or a solve dropped.
        const bool gpu_fails = g.stats.non_finite || g.stats.runaway_solves > 0;
        const bool cpu_fails = k.stats.non_finite || k.stats.runaway_solves > 0;
        gpu_failed += gpu_fails ? 1 : 0;
        cpu_failed += cpu_fails ? 1 : 0;
        gpu_only_failed += gpu_fails && !cpu_fails ? 1 : 0;
        if (gpu_fails || cpu_fails)
            std::printf("frame %4d  failed on the %s\n", frame, gpu_fails && cpu_fails ? "GPU and the CPU" : gpu_fails ? "GPU only" : "CPU only");
        gpu_totals.add(g);
        cpu_totals.add(k);
        const double gap = largest_gap(gpu, cpu);
        const double gpu_moved = farthest_move(gpu_before, gpu), cpu_moved = farthest_move(cpu_before, cpu);
        widest_gap = std::max(widest_gap, gap);
        if (differs(g, k) || std::max(g.stats.step_ms, k.stats.step_ms) > 1000.0) {
            ++differing;
            if (reported++ < o.report) {
                const auto& gs = g.stats.collision;
                const auto& ks = k.stats.collision;
                std::printf("frame %4d  gap %.4f m, moved %.3f / %.3f m | contacts %6d / %6d | zones %3d / %3d, rounds %2d / %2d | frozen %5d / %5d | "
                            "through: cloth %3lld / %3lld, body %3lld / %3lld | zones %.1f / %.1f ms, step %.0f / %.0f ms   (GPU / CPU)\n",
                            frame, gap, gpu_moved, cpu_moved, gs.contacts, ks.contacts, gs.impact_zones, ks.impact_zones, gs.impact_iterations,
                            ks.impact_iterations, gs.frozen_vertices, ks.frozen_vertices, g.cloth_through_cloth,
                            k.cloth_through_cloth, g.cloth_through_body, k.cloth_through_body,
                            g.stats.ms(weft::Stage::ImpactZones), k.stats.ms(weft::Stage::ImpactZones), g.stats.step_ms,
                            k.stats.step_ms);
            }
        }
        ++frame;
    }
    std::printf("cape_runner_twin: %d frames, %d where the backends differ (above: the first %d), widest gap after a step %.4f m\n",
                frame, differing, std::min(differing, o.report), widest_gap);
    gpu_totals.print("GPU", frame);
    cpu_totals.print("CPU", frame);
    std::printf("cape_runner_twin: cloth through something on the GPU only after %d frames; failed steps (a NaN rolled back or a solve dropped): GPU %d, "
                "CPU %d, the GPU only %d\n",
                gpu_only_through, gpu_failed, cpu_failed, gpu_only_failed);
    return o.strict && (gpu_only_through > 0 || gpu_only_failed > 0) ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    try {
        return twin(parse(argc, argv));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cape_runner_twin: %s\n", e.what());
        return 2;
    }
}
