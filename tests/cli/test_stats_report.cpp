// Reducing per-frame StepStats and reporting them: medians, counts of numerical failures, warnings,
// the stats JSON and the summary table.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include "stats_report.h"

namespace weft::cli {
namespace {

StepStats frame(double step_ms, int cg, int cg_max, int not_converged = 0, bool non_finite = false) {
    StepStats s;
    s.substeps = 2;
    s.newton_iterations = 2;
    s.cg_iterations = cg;
    s.cg_iterations_max = cg_max;
    s.cg_not_converged = not_converged;
    s.non_finite = non_finite;
    s.step_ms = step_ms;
    s.ms(Stage::Solve) = step_ms / 2.0;
    s.collider_contacts = cg;
    return s;
}

RunContext context() {
    RunContext c;
    c.scene = "flag";
    c.scene_file = "assets/scenes/flag.toml";
    c.backend = "cpu";
    c.device = "CPU, 2 threads";
    c.cloths = 1;
    c.vertices = 4;
    c.triangles = 2;
    c.dt = 1.0 / 60.0;
    c.substeps = 2;
    c.newton_iterations = 1;
    c.cg_tolerance = 1e-4;
    c.cg_max_iterations = 50;
    c.precision = "double";
    c.backend_memory_bytes = 1000;
    c.fabric_memory_bytes = 24;
    return c;
}

TEST(StatsReport, Distribution) {
    const Distribution odd = distribution({3.0, 1.0, 2.0});
    EXPECT_EQ(odd.median, 2.0);
    EXPECT_EQ(odd.max, 3.0);
    EXPECT_EQ(odd.mean, 2.0);
    EXPECT_EQ(odd.total, 6.0);
    const Distribution even = distribution({4.0, 1.0, 2.0, 3.0});
    EXPECT_EQ(even.median, 2.5);
    const Distribution empty = distribution({});
    EXPECT_TRUE(std::isnan(empty.median));
    EXPECT_EQ(empty.count, 0u);
}

TEST(StatsReport, CountsFailures) {
    const std::vector<StepStats> frames{frame(10.0, 20, 12), frame(30.0, 100, 50, 1), frame(20.0, 40, 25, 0, true),
                                        frame(20.0, 40, 25, 0, true)};
    const RunSummary s = summarize(frames);
    EXPECT_EQ(s.frames, 4u);
    EXPECT_EQ(s.step_ms.median, 20.0);
    EXPECT_EQ(s.step_ms.max, 30.0);
    EXPECT_EQ(s.stage_ms[static_cast<std::size_t>(Stage::Solve)].median, 10.0);
    EXPECT_EQ(s.cg_iterations.mean, 50.0);
    EXPECT_EQ(s.cg_iterations.max, 100.0);
    EXPECT_EQ(s.cg_iterations_max_solve, 50);
    EXPECT_EQ(s.solves, 8);
    EXPECT_EQ(s.cg_not_converged, 1);
    EXPECT_EQ(s.frames_not_converged, 1u);
    EXPECT_EQ(s.non_finite_frames, 2u);
    EXPECT_EQ(s.first_non_finite_frame, 3);
    EXPECT_DOUBLE_EQ(s.simulation_seconds, 0.08);
    EXPECT_DOUBLE_EQ(s.fps, 50.0);
    EXPECT_FALSE(s.ok());

    const auto warnings = run_warnings(context(), s);
    ASSERT_EQ(warnings.size(), 2u);
    EXPECT_NE(warnings[0].find("1 of 8 linear solves hit the CG cap (50 iterations)"), std::string::npos)
        << warnings[0];
    EXPECT_NE(warnings[1].find("NaN/Inf) in 2 of 4 frames, first at frame 3"), std::string::npos) << warnings[1];
}

TEST(StatsReport, EnergyGainedIsAWarningLikeACappedSolve) {
    std::vector<StepStats> frames{frame(10.0, 20, 12), frame(12.0, 22, 12), frame(12.0, 22, 12)};
    frames[1].energy_gained = 1;
    frames[1].energy_gain = 2.5;
    frames[2].energy_retries = 1;
    const RunSummary s = summarize(frames);
    EXPECT_EQ(s.energy_gained, 1);
    EXPECT_EQ(s.first_energy_frame, 2);
    EXPECT_EQ(s.energy_retries, 1);
    EXPECT_FALSE(s.ok());
    RunContext c = context();
    c.energy_guard = "report";
    const auto warnings = run_warnings(c, s);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("1 of 6 substeps gained energy beyond the external work (2.5 J in all) in 1 of 3 "
                               "frames, first at frame 2"),
              std::string::npos)
        << warnings[0];
    std::ostringstream text;
    print_run_summary(text, c, s, 0.5);
    EXPECT_NE(text.str().find("energy guard   report: 1 of 6 substeps gained energy (2.5 J)"), std::string::npos)
        << text.str();
    std::ostringstream json;
    write_run_json(json, c, s, frames, 1.0);
    for (const char* key : {"\"energy_guard\": {", "\"gained_substeps\": 1", "\"energy_gained\": [0, 1, 0]"})
        EXPECT_NE(json.str().find(key), std::string::npos) << key << "\n" << json.str();
}

// A dropped runaway solve and a Schwarz solve redone with block-Jacobi are counted, warned about
// and written to the JSON; the runaway makes the run not ok (the redone solve converged: it does not).
TEST(StatsReport, RunawaySolvesAndPreconditionerFallbacksAreReported) {
    std::vector<StepStats> frames{frame(10.0, 20, 12), frame(12.0, 22, 12), frame(12.0, 22, 12)};
    frames[1].runaway_solves = 2;
    frames[2].cg_preconditioner_fallbacks = 1;
    const RunSummary s = summarize(frames);
    EXPECT_EQ(s.runaway_solves, 2);
    EXPECT_EQ(s.cg_preconditioner_fallbacks, 1);
    EXPECT_FALSE(s.ok());
    const auto warnings = run_warnings(context(), s);
    ASSERT_EQ(warnings.size(), 2u);
    EXPECT_NE(warnings[0].find("1 of 6 linear solves found the multilevel Schwarz preconditioner not SPD"), std::string::npos)
        << warnings[0];
    EXPECT_NE(warnings[1].find("2 substeps dropped their solve"), std::string::npos) << warnings[1];
    std::ostringstream json;
    write_run_json(json, context(), s, frames, 1.0);
    for (const char* key : {"\"runaway_solves\": 2", "\"cg_preconditioner_fallbacks\": 1"})
        EXPECT_NE(json.str().find(key), std::string::npos) << key << "\n" << json.str();
    StepStats one = frames[1];
    EXPECT_FALSE(one.ok());
}

TEST(StatsReport, OverstretchedClothIsReportedNotJudged) {
    std::vector<StepStats> frames{frame(10.0, 20, 12), frame(12.0, 22, 12), frame(12.0, 22, 12), frame(12.0, 22, 12)};
    frames[0].max_stretch = 1.05;
    frames[1].max_stretch = kOverstretch + 0.5;
    frames[2].max_stretch = 40.0;
    frames[3].max_stretch = 2.0;
    const RunSummary s = summarize(frames);
    EXPECT_DOUBLE_EQ(s.max_stretch, 40.0);
    EXPECT_EQ(s.overstretched_frames, 2u);
    EXPECT_EQ(s.first_overstretched_frame, 2);
    EXPECT_TRUE(s.ok());  // soft cloth may stretch so by design: a warning, not a failure
    const auto warnings = run_warnings(context(), s);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("stretched to 40x its rest length"), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find("in 2 of 4 frames, first at frame 2"), std::string::npos) << warnings[0];
    std::ostringstream json;
    write_run_json(json, context(), s, frames, 1.0);
    for (const char* key : {"\"max_stretch\": 40", "\"overstretched_frames\": 2"})
        EXPECT_NE(json.str().find(key), std::string::npos) << key << "\n" << json.str();
}

TEST(StatsReport, CleanRunHasNoWarnings) {
    const std::vector<StepStats> frames{frame(10.0, 20, 12), frame(12.0, 22, 12)};
    const RunSummary s = summarize(frames);
    EXPECT_TRUE(s.ok());
    EXPECT_TRUE(run_warnings(context(), s).empty());
}

TEST(StatsReport, JsonHasDesignKeysAndNullsForUnknowns) {
    std::vector<StepStats> frames{frame(10.0, 20, 12), frame(std::numeric_limits<double>::quiet_NaN(), 22, 12)};
    const RunSummary s = summarize(frames);
    std::ostringstream out;
    write_run_json(out, context(), s, frames, 1.25);
    const std::string json = out.str();
    for (const char* key : {"\"scene\": \"flag\"",
                            "\"backend\": \"cpu\"",
                            "\"device\":",
                            "\"devices\":",
                            "\"vertices\": 4",
                            "\"triangles\": 2",
                            "\"steps\": 2",
                            "\"dt\":",
                            "\"substeps\": 2",
                            "\"stage_ms\":",
                            "\"kinematics\":",
                            "\"solve\":",
                            "\"median\":",
                            "\"cg_iterations\":",
                            "\"total\": 42",
                            "\"cg_not_converged\": 0",
                            "\"contacts\":",
                            "\"impact_zones\": 0",
                            "\"remaining_intersections\": null",
                            "\"memory_bytes\":",
                            "\"total\": 1024",
                            "\"fps\":",
                            "\"series\":",
                            "\"step_ms\": [10, null]",
                            "\"cg_iterations\": [20, 22]"}) {
        EXPECT_NE(json.find(key), std::string::npos) << key << "\n" << json;
    }
    EXPECT_EQ(json.find("nan"), std::string::npos) << json;
    EXPECT_EQ(json.find("inf"), std::string::npos) << json;
    // Only the stages that took time: these frames solve and do nothing else.
    EXPECT_NE(json.find("\"stages_run\": [\"solve\"]"), std::string::npos) << json;
}

TEST(StatsReport, SummaryTablePrintsWarnings) {
    const std::vector<StepStats> frames{frame(10.0, 20, 12), frame(30.0, 100, 50, 2, true)};
    std::ostringstream out;
    print_run_summary(out, context(), summarize(frames), 0.5);
    const std::string text = out.str();
    for (const char* part :
         {"kinematics", "solve", "median ms", "max ms", "CG iterations", "2 of 4 solves not converged", "NaN/Inf",
          "memory", "WARNING: 2 of 4 linear solves", "WARNING: non-finite"}) {
        EXPECT_NE(text.find(part), std::string::npos) << part << "\n" << text;
    }
}

TEST(StatsReport, MemoryPerTriangle) {
    EXPECT_DOUBLE_EQ(context().memory_bytes_per_triangle(), 512.0);
    RunContext empty;
    EXPECT_EQ(empty.memory_bytes_per_triangle(), 0.0);
}

}  // namespace
}  // namespace weft::cli
