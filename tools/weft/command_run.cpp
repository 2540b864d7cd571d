// `weft run SCENE`: simulate, write meshes and stats, print a summary.
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <optional>
#include <vector>

#include "weft/error.h"

#include "commands.h"
#include "frame_capture.h"
#include "cache_writer.h"
#include "frame_writer.h"
#include "output_file.h"
#include "progress_bar.h"
#include "stats_report.h"
#include "world_setup.h"

namespace weft::cli {

namespace {

// Ctrl-C (SIGINT) and SIGTERM (a job scheduler, `timeout`, `kill`) stop after the current frame, so
// that the stats, meshes and caches of the frames done are still written.
volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void on_interrupt(int /*signal*/) { g_interrupted = 1; }

class InterruptGuard {
public:
    InterruptGuard() : previous_int_(std::signal(SIGINT, on_interrupt)), previous_term_(std::signal(SIGTERM, on_interrupt)) {
        g_interrupted = 0;
    }
    ~InterruptGuard() {
        std::signal(SIGINT, previous_int_ == SIG_ERR ? SIG_DFL : previous_int_);
        std::signal(SIGTERM, previous_term_ == SIG_ERR ? SIG_DFL : previous_term_);
    }
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;

private:
    void (*previous_int_)(int);
    void (*previous_term_)(int);
};

}  // namespace

int run_command(const RunOptions& options, std::ostream& out, std::ostream& err) {
    require_backend("run", options.sim.backend);
    LoadedScene loaded = load_world(options.scene, options.sim);
    World& world = *loaded.world;
    if (options.check) world.settings().collision.check = true;
    const int frames = options.frames.value_or(loaded.desc.frames);
    // A resumed run goes on from the checkpoint's frame: its outputs are numbered from there.
    if (!options.resume_file.empty()) world.load_state(options.resume_file);
    const int first_frame = static_cast<int>(world.steps());
    const auto checkpoint = [&](int frame) {
        char name[32];
        std::snprintf(name, sizeof(name), "frame_%06d.state", frame);
        std::error_code ec;
        std::filesystem::create_directories(options.checkpoint_dir, ec);
        if (ec) throw Error("cannot create the checkpoint folder '" + options.checkpoint_dir.string() + "': " + ec.message());
        world.save_state(options.checkpoint_dir / name);
    };

    std::vector<std::string> cloth_names;
    for (std::size_t c = 0; c < world.cloth_count(); ++c) cloth_names.push_back(world.cloth(c).name);
    std::optional<AtomicFile> stats_out;
    if (!options.stats_file.empty()) stats_out.emplace(open_output_file(options.stats_file, "stats file"));
    std::optional<FrameWriter> writer;
    if (!options.out_dir.empty() && options.meshes)
        writer.emplace(options.out_dir, options.format, cloth_names, first_frame + frames);
    std::optional<CacheWriter> cache;
    if (!options.cache_file.empty()) cache.emplace(options.cache_file, world, world.settings().solver.dt);
    std::optional<FrameCapture> capture;
    if (options.capture != "none") {
        // Without the renderer in the build, this says so (frame_capture.cpp).
        capture.emplace(options.capture, options.out_dir, options.capture_width, options.capture_height, world,
                        loaded.desc.camera, frames);
    }

    const RunContext before = describe_run(loaded.desc, world, options.sim.threads, options.sim.host_wait);
    if (!options.quiet) {
        out << "simulating " << frames << (frames == 1 ? " frame of " : " frames of ") << before.scene << " ("
            << before.vertices << " vertices, " << before.triangles << " triangles) on " << before.backend << ": "
            << before.device << std::endl;
    }

    const auto start = std::chrono::steady_clock::now();
    if (writer) writer->write(first_frame, world);
    if (cache) cache->append(world);
    if (capture) capture->capture(0, {});
    std::vector<StepStats> stats;
    stats.reserve(static_cast<std::size_t>(std::min(frames, 1'000'000)));  // a huge --frames grows as it goes
    bool interrupted = false;
    std::string step_failure;  // a step that threw (a device fault): the run stops, what it did is written
    {
        const InterruptGuard guard;
        ProgressBar bar(err, frames, !options.quiet && ProgressBar::stderr_is_terminal(), start);
        for (int frame = 1; frame <= frames; ++frame) {
            // With a capture, the step runs while the GPU draws the frame before (frame_capture.h).
            const auto step = [&] { stats.push_back(world.step()); };
            try {
                if (capture)
                    capture->capture(frame, step);
                else
                    step();
            } catch (const Error& e) {
                step_failure = e.what();
                break;
            }
            if (writer) writer->write(first_frame + frame, world);
            if (cache) cache->append(world);
            if (options.checkpoint_every > 0 && (first_frame + frame) % options.checkpoint_every == 0)
                checkpoint(first_frame + frame);
            bar.update(frame);
            if (g_interrupted != 0) {
                interrupted = true;
                break;
            }
        }
    }
    const double wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (cache) cache->finish(world);  // also after an interrupt: the frames so far
    const int last_frame = static_cast<int>(world.steps());
    // Not after a failed step: the world stopped inside that frame (at the failed substep's start).
    if (!options.checkpoint_dir.empty() && step_failure.empty() &&
        (options.checkpoint_every == 0 || last_frame % options.checkpoint_every != 0))
        checkpoint(last_frame);  // the end (or where Ctrl-C stopped it) unless just written

    // Describe again: backends may grow scratch memory while stepping (reported: docs/design.md, "Memory").
    const RunContext context = describe_run(loaded.desc, world, options.sim.threads, options.sim.host_wait);
    const RunSummary summary = summarize(stats);
    std::optional<CaptureSummary> captured;
    if (capture) captured = capture->finish(1.0 / world.settings().solver.dt);
    const CaptureSummary* capture_summary = captured ? &*captured : nullptr;
    if (captured && captured->torn_frames > 0)
        err << "weft: WARNING: " << captured->torn_frames
            << " captured frames drew from a cloth slot that held parts of two states (stamps differ)\n";
    if (stats_out) {
        write_run_json(stats_out->stream(), context, summary, stats, wall_seconds, capture_summary);
        close_output_file(*stats_out, options.stats_file, "stats file");
    }

    if (!options.quiet) {
        print_run_summary(out, context, summary, wall_seconds, capture_summary);
        out << '\n';
        if (writer) {
            out << "  meshes         " << writer->files_written()
                << (writer->files_written() == 1 ? " file: " : " files: ") << writer->pattern() << '\n';
        }
        if (cache) {
            const std::vector<std::filesystem::path> files = cache->files();
            out << "  cache          " << cache->frames() << " frames in " << files.size() << " " << cache->format()
                << (files.size() == 1 ? " file: " : " files: ") << files.front().string() << (files.size() > 1 ? " …" : "")
                << (cache->format() == std::string("PC2") ? " (rest meshes beside, .obj)" : "") << "\n";
        }
        if (!options.checkpoint_dir.empty())
            out << "  checkpoints    " << (options.checkpoint_dir / "frame_*.state").string() << " (the last: frame " << last_frame
                << "; resume with --resume FILE)\n";
        if (!options.stats_file.empty()) out << "  stats          " << options.stats_file.string() << '\n';
    } else {
        for (const std::string& w : run_warnings(context, summary)) err << "weft: WARNING: " << w << '\n';
    }

    if (!step_failure.empty()) {
        err << "weft: frame " << first_frame + static_cast<int>(stats.size()) + 1 << " failed: " << step_failure
            << "\nweft: the " << stats.size() << " frames before it are written; exit code " << kExitStepFailed << std::endl;
        return kExitStepFailed;
    }
    if (interrupted) {
        err << "weft: interrupted after " << stats.size() << " of " << frames << " frames" << std::endl;
        return kExitInterrupted;
    }
    if (summary.non_finite_frames > 0) {
        err << "weft: the simulation produced non-finite values (NaN/Inf) in " << summary.non_finite_frames
            << " frames; exit code " << kExitNonFinite << std::endl;
        return kExitNonFinite;
    }
    if (summary.runaway_solves > 0) {
        err << "weft: " << summary.runaway_solves << " solves ran away (cloth over 10 km/s) and were dropped; exit code "
            << kExitNonFinite << std::endl;
        return kExitNonFinite;
    }
    const auto& col = summary.collisions;
    if (col.unresolved_substeps > 0 || col.frames_with_intersections > 0) {
        err << "weft: collisions: " << col.unresolved_substeps << " unresolved substeps, intersections after "
            << col.frames_with_intersections << " of " << col.checked_frames << " checked frames; exit code "
            << kExitCollision << std::endl;
        return kExitCollision;
    }
    return kExitOk;
}

}  // namespace weft::cli
