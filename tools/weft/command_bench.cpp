// `weft bench SCENE...`: warm-up, then timed frames; per-stage medians, frames/s, CG iterations per
// step and memory per triangle, as a table and as JSON.
#include <algorithm>
#include <chrono>
#include <fstream>
#include <optional>
#include <vector>

#include "weft/error.h"

#include "commands.h"
#include "output_file.h"
#include "scene_lookup.h"
#include "stats_report.h"
#include "text_table.h"
#include "world_setup.h"

namespace weft::cli {

namespace {

using json::JsonWriter;

struct BenchResult {
    int gpus = 1;
    RunContext context;
    RunSummary summary;
    double wall_seconds = 0.0;
};

BenchResult bench_scene(const std::string& scene, const BenchOptions& options, int gpus, std::ostream& err) {
    SimulationOptions sim = options.sim;
    sim.gpus = gpus;
    LoadedScene loaded = load_world(scene, sim);
    World& world = *loaded.world;
    err << "bench " << loaded.desc.name << (gpus > 1 ? " on " + std::to_string(gpus) + " GPUs" : std::string()) << ": "
        << options.warmup << " warm-up + " << options.frames << " timed frames" << std::endl;
    for (int i = 0; i < options.warmup; ++i) world.step();

    std::vector<StepStats> stats;
    stats.reserve(static_cast<std::size_t>(std::min(options.frames, 1'000'000)));
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < options.frames; ++i) stats.push_back(world.step());
    BenchResult result;
    result.gpus = gpus > 0 ? gpus : loaded.desc.world.solver.gpus;
    result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.context = describe_run(loaded.desc, world, options.sim.threads, options.sim.host_wait);
    result.summary = summarize(stats);
    return result;
}

void write_bench_json(AtomicFile& out, const std::filesystem::path& file, const BenchOptions& options,
                      const std::vector<BenchResult>& results) {
    JsonWriter json(out.stream());
    json.begin_array();
    for (const BenchResult& r : results) {
        json.begin_object();
        write_summary_fields(json, r.context, r.summary);
        json.field("gpus", r.gpus);
        json.field("warmup_frames", options.warmup).field("timed_frames", options.frames);
        json.field("wall_seconds", r.wall_seconds);
        json.key("overrides").begin_array();
        for (const std::string& o : options.sim.overrides) json.value(o);
        json.end_array();
        json.end_object();
    }
    json.end_array();
    close_output_file(out, file, "bench results");
}

void print_bench_table(std::ostream& out, const std::vector<BenchResult>& results) {
    std::vector<TextTable::Column> columns{{"scene", TextTable::Align::Left}, {"GPUs"}, {"triangles"}, {"frames/s"}, {"step ms"}};
    for (const std::string_view stage : kStageNames) columns.push_back({std::string(stage)});
    columns.push_back({"CG it/step"});
    columns.push_back({"B/triangle"});
    columns.push_back({"warnings", TextTable::Align::Left});
    TextTable table(std::move(columns));
    for (const BenchResult& r : results) {
        const RunSummary& s = r.summary;
        std::vector<std::string> row{r.context.scene, std::to_string(r.gpus), std::to_string(r.context.triangles), format_fixed(s.fps, 2),
                                     format_fixed(s.step_ms.median, 3)};
        for (const Distribution& d : s.stage_ms) row.push_back(format_fixed(d.median, 3));
        row.push_back(format_fixed(s.cg_iterations.mean, 1));
        row.push_back(format_fixed(r.context.memory_bytes_per_triangle(), 0));
        std::string flags;
        if (s.cg_not_converged > 0) flags += std::to_string(s.cg_not_converged) + " not converged";
        if (s.non_finite_frames > 0)
            flags += (flags.empty() ? "" : ", ") + std::to_string(s.non_finite_frames) + " NaN";
        if (s.runaway_solves > 0)
            flags += (flags.empty() ? "" : ", ") + std::to_string(s.runaway_solves) + " runaway";
        if (s.energy_gained > 0)
            flags += (flags.empty() ? "" : ", ") + std::to_string(s.energy_gained) + " energy gained";
        if (s.overstretched_frames > 0)
            flags += (flags.empty() ? "" : ", ") + std::to_string(s.overstretched_frames) + " overstretched";
        row.push_back(flags.empty() ? "-" : flags);
        table.add_row(std::move(row));
    }
    out << "\nmedian milliseconds per frame (all substeps of a frame)\n";
    table.print(out);
}

}  // namespace

int bench_command(const BenchOptions& options, std::ostream& out, std::ostream& err) {
    require_backend("bench", options.sim.backend);
    // Find every scene before running any, so a typo in the last one does not cost the whole bench.
    for (const std::string& scene : options.scenes) (void)find_scene(scene);

    // Open the output first: a bad path should fail before minutes of benchmarking, not after.
    std::optional<AtomicFile> json_out;
    if (!options.json_file.empty()) json_out.emplace(open_output_file(options.json_file, "bench results"));

    std::vector<BenchResult> results;
    for (const std::string& scene : options.scenes)
        for (const int gpus : options.gpu_counts) results.push_back(bench_scene(scene, options, gpus, err));
    print_bench_table(out, results);
    if (!options.json_file.empty()) {
        write_bench_json(*json_out, options.json_file, options, results);
        out << "\nresults: " << options.json_file.string() << '\n';
    }
    bool non_finite = false;
    for (const BenchResult& r : results) {
        for (const std::string& w : run_warnings(r.context, r.summary)) {
            err << "weft: WARNING: " << r.context.scene << ": " << w << '\n';
        }
        non_finite = non_finite || r.summary.non_finite_frames > 0 || r.summary.runaway_solves > 0;
    }
    return non_finite ? kExitNonFinite : kExitOk;
}

}  // namespace weft::cli
