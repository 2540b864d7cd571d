// cape_runner: a small game on Weft. The player runs a character, wearing a cape and a skirt, round
// a level with a flag on a pole and a banner hanging across the way, which the runner can run
// through. The runner is capsules, or (--character, where the package has the asset importer) Weft's
// rigged runner playing its run and jump clips: an experiment for now, see examples/README.md. The cloth runs on the GPU when the package has the CUDA backend and a device
// answers (drawn straight from the solver's buffer, no copy through the host), on the CPU otherwise.
//
//   cape_runner [--cpu] [--detail N] [--script FILE] [--frames N] [--check] [--screenshot FILE.png]
//               [--validation] [--offscreen] [--cg-tolerance EPS] [--preset NAME]
//               [--character [FILE.gltf]] [--threads N]
//
// --offscreen draws every frame with the Vulkan renderer but into no window (a fixed camera): for
// timing on a machine without a display. --threads caps the CPU backend's threads (0: every core).
//
// W/Up and S/Down run forward and back, A/Left and D/Right turn, Space jumps, Shift runs faster; a
// gamepad's left stick, A and right bumper do the same. Esc quits. The window's title shows the
// frame time and the cloth's share of it. examples/README.md walks through this file.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <numbers>

#include "input_script.h"
#include "level.h"
#include "runner.h"
#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/presets.h"
#include "weft/render/cloth_feed.h"
#include "weft/render/image.h"
#include "weft/render/render_scene.h"
#include "weft/render/renderer.h"
#include "weft/render/window.h"
#include "weft/world.h"
#if WEFT_HAVE_ASSETS
#include "weft/assets/skinned_import.h"
#endif
#if WEFT_HAVE_CUDA_BACKEND
#include "weft/cuda/cuda_backend.h"
#endif

namespace {

using weft::Vec3d;
using namespace cape_runner;

#ifdef CAPE_RUNNER_CHARACTER
constexpr const char* kShippedCharacter = CAPE_RUNNER_CHARACTER;  // assets/characters/runner.gltf, built or installed
#else
constexpr const char* kShippedCharacter = "";
#endif

struct Options {
    bool cpu = false;
    int detail = 0;  // cloth resolution: 1 coarse … 4 fine; 0 = 3 on the GPU, 1 on the CPU
    std::string script, screenshot;
    int frames = 0;  // 0: until the window closes (or the script ends)
    bool check = false, validation = false, offscreen = false;
    double cg_tolerance = 0.0;  // 0: the engine's default (SolverSettings::cg_tolerance)
    std::string preset;         // a solver preset (weft/presets.h); empty: "game"
    std::string character;  // a rigged character file (--character); empty: capsules
    int threads = 0;        // the CPU backend's threads; 0: every core
};

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        const auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw std::runtime_error(std::string(a) + " needs a value");
            return argv[++i];
        };
        if (a == "--cpu") o.cpu = true;
        else if (a == "--detail") o.detail = std::stoi(value());
        else if (a == "--script") o.script = value();
        else if (a == "--frames") o.frames = std::stoi(value());
        else if (a == "--check") o.check = true;
        else if (a == "--screenshot") o.screenshot = value();
        else if (a == "--validation") o.validation = true;
        else if (a == "--offscreen") o.offscreen = true;
        else if (a == "--cg-tolerance") o.cg_tolerance = std::stod(value());
        else if (a == "--preset") o.preset = value();
        else if (a == "--threads") o.threads = std::stoi(value());
        else if (a == "--character") {
            // The file that follows, or the shipped runner (found where the package installs it).
            o.character = i + 1 < argc && argv[i + 1][0] != '-' ? argv[++i] : kShippedCharacter;
            if (o.character.empty()) throw std::runtime_error("--character needs a file (this build does not know where the runner is)");
        }
        else throw std::runtime_error("unknown option " + std::string(a) + " (see the comment at the top of main.cpp)");
    }
    if (o.detail < 0 || o.detail > 4) throw std::runtime_error("--detail takes 1 to 4");
    if (o.threads < 0) throw std::runtime_error("--threads takes 0 (every core) or more");
#if !WEFT_HAVE_ASSETS
    if (!o.character.empty()) throw std::runtime_error("--character needs Weft's asset importer (Weft::assets), which this build lacks");
#endif
    if (o.offscreen && o.script.empty() && o.frames == 0) throw std::runtime_error("--offscreen needs --script or --frames");
    return o;
}

/// Where the cloth is caught in the character (--check): the character's triangles that the exact
/// check finds a cloth through, counted by cloth and by the joint that moves each triangle most (the
/// largest summed skin weight over its corners).
void print_body_pairs(const weft::World& world, std::size_t character, const weft::SkinnedMesh& skin, int frame) {
    std::map<std::string, int> by_place;
    for (const weft::IntersectingTriangles& p : world.intersections()) {
        if (!p.with_collider || p.other != character) continue;
        std::map<std::uint32_t, double> weight;
        for (const std::uint32_t v : skin.mesh.triangles[p.other_triangle].v)
            for (std::size_t k = 0; k < 4; ++k) weight[skin.vertex_joints[v][k]] += skin.vertex_weights[v][k];
        const auto heaviest = std::max_element(weight.begin(), weight.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
        ++by_place[world.cloth(p.cloth).name + " through " + skin.joints[heaviest->first].name];
    }
    std::printf("cape_runner: frame %d, cloth through the body:", frame);
    for (const auto& [place, pairs] : by_place) std::printf(" %s %d;", place.c_str(), pairs);
    std::printf("\n");
}

/// A camera behind and above the runner, looking a little ahead of it.
weft::render::Camera follow_camera(const Runner& runner) {
    const Vec3d p = runner.position(), f = runner.facing();
    const Vec3d eye = p - 4.5 * f + Vec3d{0.0, 2.4, 0.0}, at = p + 1.5 * f + Vec3d{0.0, 1.0, 0.0};
    weft::render::Camera c;
    c.position = {static_cast<float>(eye.x), static_cast<float>(eye.y), static_cast<float>(eye.z)};
    c.target = {static_cast<float>(at.x), static_cast<float>(at.y), static_cast<float>(at.z)};
    c.fov_degrees = 55.0F;
    return c;
}

/// Where the cape hangs, in the runner's frame (x right of its back, y up from the feet, z ahead).
Vec3d cape_in_runner_frame(const weft::World& world, const Level& level, const Runner& runner) {
    Vec3d sum{};
    const std::vector<Vec3d> x = world.positions(level.cape);
    for (const Vec3d& p : x) sum += p;
    const weft::Transform frame = runner.frame();
    return weft::math::transpose(frame.rotation) * (sum / static_cast<double>(x.size()) - frame.translation);
}

std::string choose_backend(bool force_cpu, std::string& why) {
    why = force_cpu ? "forced by --cpu" : "built without the CUDA backend";
#if WEFT_HAVE_CUDA_BACKEND
    weft::cuda::register_cuda_backend();
    if (!force_cpu) {
        why = weft::cuda::unavailable_reason();
        if (why.empty()) {
            why = weft::cuda::devices().front().name;
            return "cuda";
        }
    }
#endif
    return "cpu";
}

int play(const Options& options) {
    std::string why;
    const std::string backend = choose_backend(options.cpu, why);
    const int detail = options.detail > 0 ? options.detail : (backend == "cuda" ? 3 : 1);

    weft::WorldDesc desc;
    desc.wind.velocity = {3.0, 0.0, 0.5};  // m/s: a breeze for the flag
    desc.wind.turbulence = 1.5;
    desc.collision.self_collision = true;  // cape against skirt, and each against itself
    desc.collision.check = options.check;  // the exact intersection check after every step (tests)
    // The solver's speed against accuracy: a preset (a game's cloth: one float step a frame, split
    // where the runner drags the banner, docs/tuning.md), then an explicit CG tolerance over it.
    weft::apply_solver_preset(desc, !options.preset.empty() ? options.preset : "game");
    if (options.cg_tolerance > 0.0) desc.solver.cg_tolerance = options.cg_tolerance;
    weft::World world(desc, backend, weft::BackendOptions{.threads = options.threads});
    Runner runner({0.0, 0.0, 0.0});
    std::shared_ptr<const weft::SkinnedMesh> skin;
#if WEFT_HAVE_ASSETS
    if (!options.character.empty())
        skin = std::make_shared<const weft::SkinnedMesh>(weft::assets::import_skinned_mesh(options.character));
#endif
    const Level level = build_level(world, runner, detail, skin);
    std::optional<InputScript> script;
    if (!options.script.empty()) script.emplace(options.script);

    weft::render::RendererOptions view{.width = 1280, .height = 720, .validation = options.validation};
    // A window, or (--offscreen) the same renderer with no window: a camera that watches the way.
    std::unique_ptr<weft::render::Window> window;
    std::unique_ptr<weft::render::Renderer> offscreen;
    weft::CameraDesc start_camera;  // in a window, replaced by the follow camera from the first frame
    start_camera.position = {5.0, 3.0, -2.0};
    start_camera.target = {0.0, 1.0, 6.0};
    const weft::render::RenderScene scene = weft::render::make_render_scene(world, start_camera);
    if (options.offscreen) {
        offscreen = weft::render::create_renderer("vulkan", view);
        offscreen->load(scene);
    } else {
        window = std::make_unique<weft::render::Window>(view, "cape_runner");
        window->load(scene);
    }
    weft::render::Renderer& renderer = window ? window->renderer() : *offscreen;
    weft::render::ClothFeed feed(world, renderer, scene);  // zero-copy where it can be
    std::printf("cape_runner: %zu cloth triangles on %s (%s); cloth by %s\n", [&] {
        std::size_t n = 0;
        for (std::size_t c = 0; c < world.cloth_count(); ++c) n += world.cloth(c).fabric->triangle_count();
        return n;
    }(), backend.c_str(), why.c_str(), feed.describe().c_str());

    using Clock = std::chrono::steady_clock;
    constexpr double dt = 1.0 / 60.0;  // the world's step (WorldDesc's default dt)
    int frame = 0, cape_lost = 0, intersections = 0, failed_steps = 0;
    // The exact check's finds by kind: cloth through cloth, and cloth through the body (a mesh collider).
    int first_intersecting = -1, body_intersections = 0;
    long long most_cloth_pairs = 0, most_body_pairs = 0;
    double cloth_ms_sum = 0.0, frame_ms_sum = 0.0;
    std::array<double, weft::kStageNames.size()> stage_ms_sum{};  // where the cloth's time goes
    int split_substeps = 0, substeps_taken = 0;  // redone as halves where a body dragged cloth open (split_stretch); all pieces
    long long cg_iterations = 0, capped_solves = 0, fallback_solves = 0;
    // The most any cloth triangle stretched, and the frames where cloth tore or was dragged along.
    double most_stretch = 0.0;
    int overstretched = 0, first_overstretched = -1;
    // Hitches: the slowest cloth step, and the collision work that makes one.
    double slowest_ms = 0.0;
    int slowest_frame = 0, most_zone_rounds = 0, hitches = 0;
    long long frozen_vertices = 0, unresolved = 0, moved_out = 0, body_jumps = 0;
    Clock::time_point last = Clock::now();
    weft::render::RenderFrame previous;
    weft::render::Image last_picture;  // --offscreen: the frame just drawn
    while (window ? window->poll_events() : true) {
        if (options.frames > 0 && frame >= options.frames) break;
        if (script && options.frames == 0 && world.time() > script->length() + 1.0) break;

        // 1. Input: the script's keys, or what the player holds.
        Controls c;
        if (script) {
            c = script->at(world.time());
        } else if (window) {
            const weft::render::GameInput in = window->game_input();
            c = {.forward = in.forward, .turn = in.turn, .jump = in.jump, .run = in.run};
        }
        // 2. Game logic, then tell Weft where the runner goes during this frame.
        runner.advance(c, dt);
        drive(world, level, runner, world.time(), dt);
        // 3. Step the cloth; the feed has the backend write the renderer's buffer directly.
        weft::StepStats stats;
        weft::render::RenderFrame next = feed.simulate([&] { stats = world.step(); });
        // 4. Draw from behind the runner.
        if (window) {
            window->set_camera(follow_camera(runner));
            window->present(next);
            if (frame > 0) (void)feed.check(previous, window->transfer());
        } else {
            renderer.submit(next);
            last_picture = renderer.collect();
            (void)feed.check(next, renderer.transfer());
        }
        previous = std::move(next);

        // What the tests look at (--check; it reads the cape back from the backend, which a game
        // need not do): the cape hangs behind the runner within its length of the shoulders, and
        // nothing went through anything.
        if (options.check) {
            const Vec3d cape = cape_in_runner_frame(world, level, runner);
            const double from_shoulders = weft::math::length(cape - Vec3d{0.0, kShoulderHeight, -0.25});
            if (cape.z > 0.05 || from_shoulders > kCapeHeight) ++cape_lost;
        }
        if (frame == 0 && stats.collision.remaining_intersections > 0) std::printf("cape_runner: the level starts intersecting\n");
        if (stats.collision.remaining_intersections > 0) {
            if (intersections == 0) first_intersecting = frame;
            ++intersections;
            const long long body = stats.collision.remaining_collider_intersections;
            if (body > 0) ++body_intersections;
            // Where, at the first such frame and every second after it.
            if (body > 0 && level.character && (body_intersections == 1 || body_intersections % 60 == 0))
                print_body_pairs(world, *level.character, *skin, frame);
            most_cloth_pairs = std::max(most_cloth_pairs, stats.collision.remaining_intersections - body);
            most_body_pairs = std::max(most_body_pairs, body);
        }
        if (stats.non_finite || stats.runaway_solves > 0) ++failed_steps;  // a NaN rolled back, or a solve dropped
        most_stretch = std::max(most_stretch, stats.max_stretch);
        if (stats.max_stretch >= weft::kOverstretch && overstretched++ == 0) first_overstretched = frame;

        const Clock::time_point now = Clock::now();
        const double frame_ms = std::chrono::duration<double, std::milli>(now - last).count();
        last = now;
        cloth_ms_sum += stats.step_ms;
        if (stats.step_ms > slowest_ms) slowest_ms = stats.step_ms, slowest_frame = frame;
        most_zone_rounds = std::max(most_zone_rounds, stats.collision.impact_iterations);
        frozen_vertices += stats.collision.frozen_vertices;
        unresolved += stats.collision.unresolved_substeps;
        moved_out += stats.collision.ejected_vertices;
        body_jumps += stats.collision.collider_jumps;
        // A cloth step of four frames' time: the first five, and every one over a second.
        if (stats.step_ms > 4.0 * dt * 1000.0 && (++hitches <= 5 || stats.step_ms > 1000.0))
            std::printf("cape_runner: frame %d: cloth step %.0f ms (impact zones %.0f, CCD %.0f, broad phase %.0f ms; %d zone "
                        "rounds, %d vertices frozen; %lld candidate pairs, %lld CCD tests, %lld hits)\n",
                        frame, stats.step_ms, stats.ms(weft::Stage::ImpactZones), stats.ms(weft::Stage::Ccd),
                        stats.ms(weft::Stage::BroadPhase), stats.collision.impact_iterations, stats.collision.frozen_vertices,
                        static_cast<long long>(stats.collision.candidate_pairs), static_cast<long long>(stats.collision.ccd_tests),
                        static_cast<long long>(stats.collision.ccd_hits));
        for (std::size_t k = 0; k < stage_ms_sum.size(); ++k) stage_ms_sum[k] += stats.stage_ms[k];
        cg_iterations += stats.cg_iterations;
        split_substeps += stats.split_substeps;
        substeps_taken += stats.substeps;
        capped_solves += stats.cg_not_converged;
        fallback_solves += stats.cg_preconditioner_fallbacks;
        frame_ms_sum += frame_ms;
        ++frame;
        if (frame % 15 == 0) {
            char title[160];
            std::snprintf(title, sizeof(title), "cape_runner  |  frame %.1f ms  |  cloth %.2f ms (%s)%s", frame_ms, stats.step_ms,
                          backend.c_str(), feed.zero_copy() ? ", zero-copy" : "");
            if (window) window->set_title(title);
        }
    }
    if (!options.screenshot.empty() && frame > 0)
        weft::render::write_png(options.screenshot, window ? window->screenshot() : last_picture);

    std::printf("cape_runner: %d frames, mean frame %.2f ms, mean cloth step %.2f ms; runner at (%.2f, %.2f, %.2f)\n", frame,
                frame > 0 ? frame_ms_sum / frame : 0.0, frame > 0 ? cloth_ms_sum / frame : 0.0, runner.position().x,
                runner.position().y, runner.position().z);
    std::printf("cape_runner: mean ms per frame by stage:");
    for (std::size_t k = 0; k < stage_ms_sum.size(); ++k)
        if (frame > 0 && stage_ms_sum[k] > 0.0) std::printf(" %s %.2f", std::string(weft::kStageNames[k]).c_str(), stage_ms_sum[k] / frame);
    std::printf("; CG %.0f iterations a frame, %lld solves capped, %lld redone with block-Jacobi\n",
                frame > 0 ? static_cast<double>(cg_iterations) / frame : 0.0, capped_solves, fallback_solves);
    std::printf("cape_runner: slowest cloth step %.1f ms (frame %d); collisions: at most %d impact-zone rounds in a substep, "
                "%lld vertices frozen, %lld substeps unresolved, %lld vertices moved out of the body, %lld jumps of a body; "
                "%d substeps split, %d taken\n",
                slowest_ms, slowest_frame, most_zone_rounds, frozen_vertices, unresolved, moved_out, body_jumps, split_substeps, substeps_taken);
    std::printf("cape_runner: cape away from the shoulders in %d frames%s, intersections after %d, failed steps %d, "
                "torn frames %lld, validation messages %d\n",
                cape_lost, options.check ? "" : " (not checked; --check does)", intersections, failed_steps, static_cast<long long>(feed.torn_frames()), renderer.validation_messages());
    std::printf("cape_runner: cloth stretched at most %.2fx its rest length; %gx or more (torn, or dragged along) in %d frames",
                most_stretch, weft::kOverstretch, overstretched);
    if (overstretched > 0) std::printf(", first after frame %d", first_overstretched);
    std::printf("\n");
    if (intersections > 0)
        std::printf("cape_runner: intersections first after frame %d; cloth through cloth at most %lld pairs a frame, cloth through "
                    "the body in %d frames, at most %lld pairs a frame\n",
                    first_intersecting, most_cloth_pairs, body_intersections, most_body_pairs);
    const bool ok = cape_lost == 0 && intersections == 0 && failed_steps == 0 && feed.torn_frames() == 0 &&
                    renderer.validation_messages() == 0;
    return options.check && !ok ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
    // Line by line even into a file or pipe: a run killed by a time limit still shows how far it got.
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    try {
        return play(parse(argc, argv));
    } catch (const std::exception& e) {  // weft::Error and the example's own
        std::fprintf(stderr, "cape_runner: %s\n", e.what());
        return 2;
    }
}
