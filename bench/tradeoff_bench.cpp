// Speed against accuracy on one scene (issue 22, item 2; first form, one knob at a time): the scene
// as shipped and with each speed/accuracy knob moved one step either way, each run against a
// converged reference (on the CPU backend in double, 8× the substeps, 3 Newton iterations, CG to
// 1e-8, whatever backend is measured), error measured on
// the positions at fixed times, cost as wall time per simulated second. Use it on scenes that settle
// or follow a forced motion (hanging, cantilever, drape), not on chaotic flutter (the flag), where
// any difference grows. Markdown table on stdout (the configurations on the Pareto front marked),
// JSON with --json. Knobs that change the model rather than how closely it is solved (the bending
// model, the contact mode) are not swept: against the reference they would measure the model.
//
//   weft_tradeoff_bench SCENE [--backend cpu|cuda] [--frames N] [--set KEY=VALUE]... [--json FILE] [--plot FILE.svg|.png]
//
// --plot draws error against cost on log axes, each run labelled, the front joined and filled
// (bench/plot/tradeoff_plot.h: SVG, or PNG where the renderer and ImGui are built).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "json_file.h"
#include "json_writer.h"
#include "scene_lookup.h"
#include "tradeoff_plot.h"
#include "optional_backends.h"
#include "weft/error.h"
#include "weft/presets.h"
#include "weft/scene.h"
#include "weft/world.h"

namespace {

using weft::Vec3d;

struct Config {
    std::string name;
    std::vector<std::string> overrides;  ///< on top of the scene's
};

struct Run {
    std::string name;
    double ms_per_second = 0.0;   ///< wall ms per simulated second
    double error = 0.0;           ///< largest RMS position error over the checkpoints, m
    double relative = 0.0;        ///< the same over the cloths' bounding-box diagonal
    bool ok = true;               ///< no NaN, no capped solve, no energy gained
    bool front = false;
    std::string failure;
};

/// Positions of every cloth at each checkpoint (every `every` frames) and the stepping time.
struct Trajectory {
    std::vector<std::vector<Vec3d>> snapshots;  // per checkpoint: every cloth's vertices, concatenated
    double seconds = 0.0;
    double simulated = 0.0;
    bool ok = true;
    std::string failure;
};

Trajectory simulate(const std::filesystem::path& scene, const std::vector<std::string>& overrides, const std::string& backend,
                    int frames, int every) {
    Trajectory t;
    const weft::SceneDesc desc = weft::load_scene(scene, overrides);
    auto world = weft::build_world(desc, backend);
    for (int f = 1; f <= frames; ++f) {
        const auto start = std::chrono::steady_clock::now();
        const weft::StepStats& s = world->step();
        t.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (s.non_finite || s.cg_not_converged > 0 || s.energy_gained > 0) {
            t.ok = false;
            if (t.failure.empty())
                t.failure = "frame " + std::to_string(f) + (s.non_finite ? ": non-finite" : s.cg_not_converged > 0 ? ": CG capped" : ": energy gained");
        }
        if (f % every == 0) {
            std::vector<Vec3d> all;
            for (std::size_t c = 0; c < world->cloth_count(); ++c) {
                const auto x = world->positions(c);
                all.insert(all.end(), x.begin(), x.end());
            }
            t.snapshots.push_back(std::move(all));
        }
    }
    t.simulated = world->time();
    return t;
}

double rms_gap(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const Vec3d d = a[i] - b[i];
        const double dist2 = d.x * d.x + d.y * d.y + d.z * d.z;
        sum += std::isfinite(dist2) ? dist2 : 1e30;
    }
    return std::sqrt(sum / static_cast<double>(std::max<std::size_t>(1, a.size())));
}

double diagonal(const std::vector<Vec3d>& x) {
    Vec3d lo = x.front(), hi = x.front();
    for (const Vec3d& p : x) {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    const Vec3d d = hi - lo;
    return std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
}

}  // namespace

int main(int argc, char** argv) {
    try {
        weft::bench::install_optional_backends();
        std::string scene_name, backend = "cpu", json, plot;
        int frames = 60;
        std::vector<std::string> base;
        for (int i = 1; i < argc; ++i) {
            const std::string flag = argv[i];
            if (flag.rfind("--", 0) != 0) {
                if (!scene_name.empty()) throw weft::Error("one scene only (got '" + scene_name + "' and '" + flag + "')");
                scene_name = flag;
                continue;
            }
            if (i + 1 >= argc) throw weft::Error(flag + " needs a value");
            const std::string value = argv[++i];
            if (flag == "--backend")
                backend = value;
            else if (flag == "--frames") {
                frames = std::stoi(value);
                if (frames < 4) throw weft::Error("--frames: " + value + " (at least 4: the error is taken every quarter)");
            } else if (flag == "--set")
                base.push_back(value);
            else if (flag == "--json")
                json = value;
            else if (flag == "--plot")
                plot = value;
            else
                throw weft::Error("unknown option '" + flag + "' (--backend, --frames, --set, --json, --plot)");
        }
        if (scene_name.empty()) throw weft::Error("usage: weft_tradeoff_bench SCENE [--backend B] [--frames N] [--set K=V]... [--json F]");
        // Before minutes of runs: a PNG plot this build cannot draw is refused now, not at the end.
        if (plot.ends_with(".png") && !weft::bench::png_plots_available())
            throw weft::Error(plot + ": PNG plots need the renderer and Dear ImGui's font (configure with WEFT_RENDER and "
                              "WEFT_EDITOR on); write .svg instead");
        const std::filesystem::path scene = weft::cli::find_scene(scene_name);
        const weft::SolverSettings shipped = weft::load_scene(scene, base).world.solver;
        const int every = frames / 4;
        const auto with = [&](std::vector<std::string> extra) {
            std::vector<std::string> o = base;
            o.insert(o.end(), extra.begin(), extra.end());
            return o;
        };
        // The reference: what every knob would give at its most accurate, converged, in double on the
        // CPU backend (the accuracy reference, whatever backend is measured: the GPU computes in float).
        const Trajectory reference =
            simulate(scene,
                     with({"solver.substeps=" + std::to_string(8 * shipped.substeps), "solver.newton_iterations=3",
                           "solver.cg_tolerance=1e-8", "solver.cg_max_iterations=20000", "solver.precision=\"double\""}),
                     "cpu", frames, every);
        if (!reference.ok) std::printf("warning: the reference run was not clean (%s)\n", reference.failure.c_str());
        const double size = diagonal(reference.snapshots.front());
        std::vector<Config> configs = {{"as shipped", {}}};
        for (const int n : {std::max(1, shipped.substeps / 2), 2 * shipped.substeps, 4 * shipped.substeps})
            if (n != shipped.substeps) configs.push_back({"substeps " + std::to_string(n), {"solver.substeps=" + std::to_string(n)}});
        for (const int n : {2, 3})
            if (n != shipped.newton_iterations) configs.push_back({"Newton " + std::to_string(n), {"solver.newton_iterations=" + std::to_string(n)}});
        for (const char* tol : {"1e-2", "1e-3", "1e-6"}) configs.push_back({std::string("CG tolerance ") + tol, {std::string("solver.cg_tolerance=") + tol}});
        for (const char* p : {"jacobi", "mas"})
            configs.push_back({std::string("preconditioner ") + p, {std::string("solver.preconditioner=\"") + p + "\""}});
        if (backend == "cpu") configs.push_back({"float", {"solver.precision=\"float\""}});
        configs.push_back({"Hessian projected", {"solver.hessian=\"projected\""}});
        // Knobs together: the pairs that the single-knob runs suggest trade best (more substeps or
        // Newton iterations, paid for with a looser CG).
        const std::string twice = "solver.substeps=" + std::to_string(2 * shipped.substeps);
        const std::string four = "solver.substeps=" + std::to_string(4 * shipped.substeps);
        configs.push_back({"substeps ×2 + Newton 2", {twice, "solver.newton_iterations=2"}});
        configs.push_back({"substeps ×2 + CG 1e-3", {twice, "solver.cg_tolerance=1e-3"}});
        configs.push_back({"Newton 3 + CG 1e-3", {"solver.newton_iterations=3", "solver.cg_tolerance=1e-3"}});
        configs.push_back({"substeps ×4 + Newton 2 + CG 1e-3", {four, "solver.newton_iterations=2", "solver.cg_tolerance=1e-3"}});
        // The shipped presets (weft/presets.h): named points that should lie on the front.
        for (const weft::Preset& p : weft::solver_presets()) configs.push_back({"preset " + p.name, weft::preset_overrides(p)});

        std::vector<Run> runs;
        for (const Config& c : configs) {
            Run r;
            r.name = c.name;
            try {
                const Trajectory t = simulate(scene, with(c.overrides), backend, frames, every);
                r.ms_per_second = 1000.0 * t.seconds / t.simulated;
                for (std::size_t k = 0; k < t.snapshots.size(); ++k) r.error = std::max(r.error, rms_gap(t.snapshots[k], reference.snapshots[k]));
                r.relative = r.error / size;
                r.ok = t.ok;
                r.failure = t.failure;
            } catch (const weft::Error& e) {
                r.ok = false;
                r.failure = e.what();
                r.error = r.relative = r.ms_per_second = NAN;
            }
            runs.push_back(r);
        }
        // The front: no other clean run is both cheaper and closer.
        for (Run& a : runs) {
            if (!a.ok) continue;
            a.front = std::none_of(runs.begin(), runs.end(), [&](const Run& b) {
                return &b != &a && b.ok && b.ms_per_second <= a.ms_per_second && b.error <= a.error &&
                       (b.ms_per_second < a.ms_per_second || b.error < a.error);
            });
        }
        std::printf("%s on %s, %d frames, error against the reference (cpu, double, 8x substeps, 3 Newton, CG 1e-8) every %d frames; "
                    "reference %.0f ms per simulated s\n\n",
                    scene_name.c_str(), backend.c_str(), frames, every, 1000.0 * reference.seconds / reference.simulated);
        std::printf("| configuration | ms per simulated s | RMS position error, mm | of the cloth's size | clean | on the front |\n");
        std::printf("|---|---|---|---|---|---|\n");
        for (const Run& r : runs)
            std::printf("| %s | %.1f | %.3f | %.3f%% | %s | %s |\n", r.name.c_str(), r.ms_per_second, 1000.0 * r.error, 100.0 * r.relative,
                        r.ok ? "yes" : r.failure.c_str(), r.front ? "**yes**" : "");
        if (!json.empty() && !weft::bench::write_json_file(json, "weft_tradeoff_bench", [&](std::ostream& out) {
                weft::json::JsonWriter w(out);
                w.begin_object()
                    .field("scene", scene_name)
                    .field("backend", backend)
                    .field("frames", frames)
                    .field("reference_ms_per_second", 1000.0 * reference.seconds / reference.simulated);
                w.key("runs").begin_array();
                for (const Run& r : runs)
                    w.begin_object()
                        .field("configuration", r.name)
                        .field("ms_per_second", r.ms_per_second)
                        .field("rms_error_m", r.error)
                        .field("relative_error", r.relative)
                        .field("clean", r.ok)
                        .field("front", r.front)
                        .field("failure", r.failure)
                        .end_object();
                w.end_array().end_object();
            }))
            return 1;
        if (!plot.empty()) {
            std::vector<weft::bench::TradeoffPoint> points;
            for (const Run& r : runs) points.push_back({r.name, r.ms_per_second, r.error, r.front, r.ok});
            weft::bench::write_tradeoff_plot(plot, scene_name + " on " + backend + ", " + std::to_string(frames) + " frames: error against cost",
                                             points);
            std::printf("\nplot: %s\n", plot.c_str());
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "weft_tradeoff_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
