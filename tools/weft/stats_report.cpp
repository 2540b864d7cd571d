#include "stats_report.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "weft/backend/model.h"
#include "weft/scene.h"
#include "weft/world.h"

#include "build_info.h"
#include "text_table.h"

namespace weft::cli {

using json::json_number;
using json::JsonWriter;

Distribution distribution(std::vector<double> values) {
    // A NaN has no place in an order (and would break std::sort): drop it, it is not a time.
    std::erase_if(values, [](double v) { return std::isnan(v); });
    Distribution d;
    d.count = values.size();
    if (values.empty()) return d;
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    d.median = n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
    d.max = values.back();
    for (const double v : values) d.total += v;
    d.mean = d.total / static_cast<double>(n);
    return d;
}

RunSummary summarize(std::span<const StepStats> frames) {
    RunSummary s;
    s.frames = frames.size();
    std::array<std::vector<double>, kStageCount> stage;
    std::vector<double> step, cg, kernels, contacts, pairs, culled, pair_contacts, part_contacts;
    for (auto& v : stage) v.reserve(frames.size());
    step.reserve(frames.size());
    cg.reserve(frames.size());
    contacts.reserve(frames.size());
    for (std::size_t f = 0; f < frames.size(); ++f) {
        const StepStats& st = frames[f];
        for (std::size_t k = 0; k < kStageCount; ++k) stage[k].push_back(st.stage_ms[k]);
        step.push_back(st.step_ms);
        cg.push_back(st.cg_iterations);
        kernels.push_back(static_cast<double>(st.kernels_launched));
        contacts.push_back(st.collider_contacts);
        s.swept_collider_hits += st.collision.swept_collider_hits;
        s.collider_overshoots += st.collision.collider_overshoots;
        s.cg_iterations_max_solve = std::max(s.cg_iterations_max_solve, st.cg_iterations_max);
        s.solves += st.newton_iterations;
        s.cg_not_converged += st.cg_not_converged;
        if (st.cg_not_converged > 0) ++s.frames_not_converged;
        s.cg_preconditioner_fallbacks += st.cg_preconditioner_fallbacks;
        s.runaway_solves += st.runaway_solves;
        s.max_stretch = std::fmax(s.max_stretch, st.max_stretch);
        if (st.max_stretch >= kOverstretch) {
            if (s.overstretched_frames == 0) s.first_overstretched_frame = static_cast<long long>(f) + 1;
            ++s.overstretched_frames;
        }
        // fmax ignores a NaN residual; a NaN there comes with non_finite, which is counted below.
        s.cg_residual_max = std::fmax(s.cg_residual_max, st.cg_residual);
        if (st.non_finite) {
            if (s.non_finite_frames == 0) s.first_non_finite_frame = static_cast<long long>(f) + 1;
            ++s.non_finite_frames;
        }
        s.substeps += st.substeps;
        if (st.energy_gained > 0) {
            if (s.frames_energy_gained == 0) s.first_energy_frame = static_cast<long long>(f) + 1;
            ++s.frames_energy_gained;
        }
        s.energy_gained += st.energy_gained;
        s.energy_gain += st.energy_gain;
        s.energy_retries += st.energy_retries;
        s.line_search_halvings += st.line_search_halvings;
        s.energy_unchecked += st.energy_unchecked;
        s.split_substeps += st.split_substeps;
        if (st.split_substeps > 0) ++s.frames_split;
        const CollisionStats& c = st.collision;
        auto& sc = s.collisions;
        sc.active = sc.active || c.candidate_pairs > 0 || c.ccd_tests > 0 || c.remaining_intersections >= 0 ||
                    st.ms(Stage::BroadPhase) > 0.0;
        pairs.push_back(static_cast<double>(c.candidate_pairs));
        culled.push_back(static_cast<double>(c.culled_pairs));
        pair_contacts.push_back(c.contacts);
        part_contacts.push_back(c.contacts_largest_part);
        sc.ccd_tests += c.ccd_tests;
        sc.ccd_hits += c.ccd_hits;
        sc.impact_zones += c.impact_zones;
        sc.impact_iterations_max = std::max(sc.impact_iterations_max, c.impact_iterations);
        sc.rigid_zones += c.rigid_zones;
        sc.frozen_vertices += c.frozen_vertices;
        sc.impact_work_spent += c.impact_work_spent;
        sc.unresolved_substeps += c.unresolved_substeps;
        sc.reused_detections += c.reused_detections;
        sc.ejected_vertices += c.ejected_vertices;
        sc.collider_jumps += c.collider_jumps;
        sc.collider_jump_max = std::max(sc.collider_jump_max, c.collider_jump_max);
        sc.truncated_vertices += c.truncated_vertices;
        sc.redetections += c.redetections;
        sc.bound_fallbacks += c.bound_fallbacks;
        sc.uncullings += c.uncullings;
        sc.buffer_growths += c.buffer_growths;
        sc.parts_recut += c.parts_recut;
        sc.query_radius_max = std::max(sc.query_radius_max, c.query_radius_max);
        if (c.remaining_intersections >= 0) {
            ++sc.checked_frames;
            sc.remaining_intersections_max = std::max<long long>(sc.remaining_intersections_max, c.remaining_intersections);
            if (c.remaining_intersections > 0) {
                if (sc.frames_with_intersections == 0) sc.first_intersecting_frame = static_cast<long long>(f) + 1;
                ++sc.frames_with_intersections;
            }
            if (c.remaining_collider_intersections > 0) {
                ++sc.frames_with_collider_intersections;
                sc.collider_intersections_max = std::max<long long>(sc.collider_intersections_max, c.remaining_collider_intersections);
            }
        }
    }
    s.collisions.candidate_pairs = distribution(std::move(pairs));
    s.collisions.culled_pairs = distribution(std::move(culled));
    s.collisions.contacts = distribution(std::move(pair_contacts));
    s.collisions.contacts_largest_part = distribution(std::move(part_contacts));
    for (std::size_t k = 0; k < kStageCount; ++k) s.stage_ms[k] = distribution(std::move(stage[k]));
    s.step_ms = distribution(std::move(step));
    s.cg_iterations = distribution(std::move(cg));
    s.kernels = distribution(std::move(kernels));
    s.contacts = distribution(std::move(contacts));
    s.simulation_seconds = s.step_ms.total / 1000.0;
    s.fps = s.simulation_seconds > 0.0 ? static_cast<double>(s.frames) / s.simulation_seconds : 0.0;
    return s;
}

RunContext describe_run(const SceneDesc& scene, const World& world, int threads, HostWait host_wait) {
    RunContext c;
    c.scene = scene.name;
    c.scene_file = scene.path.string();
    c.backend = std::string(world.backend_name());
    c.culled_pairs_counted = world.model().settings.collision.count_culled && c.backend == "cpu";
    c.device = world.device_description();
    c.threads = threads;
    c.host_wait = host_wait_name(host_wait);
    const Model& model = world.model();
    const SolverSettings& solver = model.settings.solver;
    c.dt = solver.dt;
    c.substeps = solver.substeps;
    c.newton_iterations = solver.newton_iterations;
    c.cg_tolerance = solver.cg_tolerance;
    c.cg_max_iterations = solver.cg_max_iterations;
    c.precision = solver.precision == Precision::Float ? "float" : "double";
    c.energy_guard = solver.energy_guard == EnergyGuard::Off      ? "off"
                     : solver.energy_guard == EnergyGuard::Report ? "report"
                                                                  : "retry";
    c.split_stretch = solver.split_stretch;
    c.cloths = model.cloths.size();
    c.backend_memory_bytes = world.memory_bytes();
    c.backend_memory_breakdown = world.memory_breakdown();
    std::set<const Fabric*> counted;
    for (const ClothDesc& cloth : model.cloths) {
        if (!cloth.fabric) continue;
        c.vertices += cloth.fabric->vertex_count();
        c.triangles += cloth.fabric->triangle_count();
        if (counted.insert(cloth.fabric.get()).second) {
            c.fabric_memory_bytes += cloth.fabric->memory_bytes();
            for (const std::string& w : cloth.fabric->report().warnings) {
                c.cook_warnings.push_back("cloth '" + cloth.name + "': " + w);
            }
        }
    }
    return c;
}

std::vector<std::string> run_warnings(const RunContext& context, const RunSummary& summary) {
    std::vector<std::string> out;
    if (summary.cg_not_converged > 0) {
        out.push_back(std::to_string(summary.cg_not_converged) + " of " + std::to_string(summary.solves) +
                      " linear solves hit the CG cap (" + std::to_string(context.cg_max_iterations) +
                      " iterations) in " + std::to_string(summary.frames_not_converged) + " of " +
                      std::to_string(summary.frames) + " frames; largest final residual " +
                      json_number(summary.cg_residual_max) + " against tolerance " + json_number(context.cg_tolerance) +
                      " (raise the CG iteration cap or the substeps)");
    }
    if (summary.cg_preconditioner_fallbacks > 0) {
        out.push_back(std::to_string(summary.cg_preconditioner_fallbacks) + " of " + std::to_string(summary.solves) +
                      " linear solves found the multilevel Schwarz preconditioner not SPD in this precision "
                      "and were solved again with block-Jacobi");
    }
    if (summary.runaway_solves > 0) {
        out.push_back(std::to_string(summary.runaway_solves) +
                      " substeps dropped their solve, which gave cloth a speed over 10 km/s (a system singular in this "
                      "precision); the cloth kept its velocity through those substeps");
    }
    if (summary.overstretched_frames > 0) {
        out.push_back("cloth stretched to " + json_number(summary.max_stretch) + "x its rest length (a triangle's largest principal stretch) in " +
                      std::to_string(summary.overstretched_frames) + " of " + std::to_string(summary.frames) +
                      " frames, first at frame " + std::to_string(summary.first_overstretched_frame) +
                      ": torn, or dragged by something it should slide off (look at the colliders and pins there)");
    }
    if (summary.non_finite_frames > 0) {
        out.push_back("non-finite values (NaN/Inf) in " + std::to_string(summary.non_finite_frames) + " of " +
                      std::to_string(summary.frames) + " frames, first at frame " +
                      std::to_string(summary.first_non_finite_frame) +
                      "; the state was rolled back each time, so the motion is wrong from there on "
                      "(try a smaller time step or more substeps)");
    }
    if (summary.energy_gained > 0) {
        out.push_back(std::to_string(summary.energy_gained) + " of " + std::to_string(summary.substeps) +
                      " substeps gained energy beyond the external work (" + json_number(summary.energy_gain) +
                      " J in all) in " + std::to_string(summary.frames_energy_gained) + " of " +
                      std::to_string(summary.frames) + " frames, first at frame " +
                      std::to_string(summary.first_energy_frame) +
                      (context.energy_guard == "retry"
                           ? std::string("; the redo with a tighter CG tolerance did not cure them")
                           : std::string("")) +
                      " (tighten the CG tolerance, raise the CG iteration cap or the substeps, or set "
                      "solver.energy_guard = \"retry\")");
    }
    const auto& c = summary.collisions;
    if (c.unresolved_substeps > 0) {
        out.push_back(std::to_string(c.unresolved_substeps) +
                      " substeps ended with a collision the impact zones could not resolve (raise "
                      "collision.max_impact_iterations or the substeps)");
    }
    if (c.frames_with_intersections > 0) {
        out.push_back("the exact check found intersecting triangles after " +
                      std::to_string(c.frames_with_intersections) + " of " + std::to_string(c.checked_frames) +
                      " frames, first after frame " + std::to_string(c.first_intersecting_frame) + ", at most " +
                      std::to_string(c.remaining_intersections_max) + " pairs" +
                      (c.frames_with_collider_intersections > 0
                           ? " (cloth through a mesh collider in " + std::to_string(c.frames_with_collider_intersections) +
                                 " frames, at most " + std::to_string(c.collider_intersections_max) + " pairs)"
                           : ""));
    }
    if (c.collider_jumps > 0) {
        out.push_back("a mesh collider started " + std::to_string(c.collider_jumps) +
                      " substeps away from where the last one ended it (at most " + format_fixed(1000.0 * c.collider_jump_max, 1) +
                      " mm): it moved with no motion for the collisions to sweep (a pose or motion rewritten for times "
                      "already stepped, or a clip switched with a jump)");
    }
    if (c.ejected_vertices > 0) {
        out.push_back(std::to_string(c.ejected_vertices) +
                      " cloth vertices were found inside a closed mesh collider and moved out (they got in past the "
                      "contacts and the CCD: a thicker collision.thickness or more substeps keep them out)");
    }
    if (c.rigid_zones > 0 || c.frozen_vertices > 0) {
        out.push_back("impact-zone fallbacks used: " + std::to_string(c.rigid_zones) + " rigid zones, " +
                      std::to_string(c.frozen_vertices) + " frozen vertices (the motion there is damped)");
    }
    for (const std::string& w : context.cook_warnings) out.push_back(w);
    return out;
}

namespace {

void write_distribution(JsonWriter& json, const Distribution& d) {
    json.begin_object().field("median", d.median).field("max", d.max).field("mean", d.mean).end_object();
}

}  // namespace

void write_summary_fields(JsonWriter& json, const RunContext& c, const RunSummary& s) {
    json.field("weft_version", build_info().version);
    json.field("scene", c.scene).field("scene_file", c.scene_file);
    json.field("backend", c.backend).field("device", c.device);
    json.key("devices").begin_array(true).value(c.device).end_array();
    json.field("threads", c.threads).field("host_wait", c.host_wait);
    json.field("cloths", c.cloths).field("vertices", c.vertices).field("triangles", c.triangles);
    json.field("steps", s.frames).field("dt", c.dt).field("substeps", c.substeps);
    json.field("newton_iterations", c.newton_iterations);
    json.field("precision", c.precision);
    json.field("cg_tolerance", c.cg_tolerance).field("cg_max_iterations", c.cg_max_iterations);

    json.key("stage_ms").begin_object();
    for (std::size_t k = 0; k < kStageCount; ++k) {
        json.key(kStageNames[k]);
        write_distribution(json, s.stage_ms[k]);
    }
    json.key("step");
    write_distribution(json, s.step_ms);
    json.end_object();
    // The stages that took time in any frame: a scene pays only for what it models.
    json.key("stages_run").begin_array(true);
    for (std::size_t k = 0; k < kStageCount; ++k)
        if (s.stage_ms[k].max > 0.0) json.value(kStageNames[k]);
    json.end_array();

    json.key("cg_iterations").begin_object();
    json.field("mean", s.cg_iterations.mean);  // per step (all solves of a frame)
    json.field("median", s.cg_iterations.median);
    json.field("max", s.cg_iterations.max);
    json.field("max_solve", s.cg_iterations_max_solve);
    json.field("total", static_cast<long long>(std::llround(s.cg_iterations.total)));
    json.field("solves", s.solves);
    json.end_object();
    json.field("cg_not_converged", s.cg_not_converged);
    json.field("cg_not_converged_frames", s.frames_not_converged);
    json.field("cg_preconditioner_fallbacks", s.cg_preconditioner_fallbacks);
    json.field("cg_residual_max", s.cg_residual_max);
    json.field("non_finite_frames", s.non_finite_frames);
    json.field("runaway_solves", s.runaway_solves);
    json.field("max_stretch", s.max_stretch);
    json.field("overstretched_frames", s.overstretched_frames);
    json.key("energy_guard").begin_object();
    json.field("mode", c.energy_guard);
    json.field("gained_substeps", s.energy_gained);
    json.field("gained_frames", s.frames_energy_gained);
    json.field("gain_joules", s.energy_gain);
    json.field("retries", s.energy_retries);
    json.field("unchecked_substeps", s.energy_unchecked);
    json.end_object();
    json.field("line_search_halvings", s.line_search_halvings);
    json.key("split_substeps").begin_object().field("split_stretch", c.split_stretch).field("redone", s.split_substeps)
        .field("frames", s.frames_split).end_object();
    // GPU kernels enqueued per frame (a graph's kernel nodes count at each launch; 0 on the cpu).
    json.key("kernels_per_frame").begin_object();
    json.field("median", s.kernels.median).field("max", s.kernels.max).field("mean", s.kernels.mean);
    json.end_object();

    json.key("contacts").begin_object().field("mean", s.contacts.mean).field("max", s.contacts.max).end_object();
    json.field("swept_collider_hits", s.swept_collider_hits).field("collider_overshoots", s.collider_overshoots);
    const auto& col = s.collisions;
    json.key("collisions").begin_object();
    json.field("active", col.active);
    json.key("candidate_pairs");
    write_distribution(json, col.candidate_pairs);
    json.field("culled_pairs_counted", c.culled_pairs_counted);
    json.key("culled_pairs");
    write_distribution(json, col.culled_pairs);
    json.key("contacts");
    write_distribution(json, col.contacts);
    json.key("contacts_largest_part");
    write_distribution(json, col.contacts_largest_part);
    json.field("ccd_tests", col.ccd_tests).field("ccd_hits", col.ccd_hits);
    json.field("impact_zones", col.impact_zones).field("impact_iterations_max", col.impact_iterations_max);
    json.field("rigid_zones", col.rigid_zones).field("frozen_vertices", col.frozen_vertices);
    json.field("impact_work_spent", col.impact_work_spent);
    json.field("unresolved_substeps", col.unresolved_substeps);
    json.field("reused_detections", col.reused_detections);
    json.field("ejected_vertices", col.ejected_vertices);
    json.field("collider_jumps", col.collider_jumps).field("collider_jump_max", col.collider_jump_max);
    json.field("truncated_vertices", col.truncated_vertices).field("redetections", col.redetections);
    json.field("bound_fallbacks", col.bound_fallbacks).field("query_radius_max", col.query_radius_max);
    json.field("uncullings", col.uncullings).field("buffer_growths", col.buffer_growths);
    json.field("parts_recut", col.parts_recut);
    json.field("checked_frames", col.checked_frames);
    json.end_object();
    json.field("impact_zones", col.impact_zones);
    // null when the exact check did not run: not a misleading 0.
    if (col.checked_frames > 0) {
        json.field("remaining_intersections", col.remaining_intersections_max);
        json.field("remaining_collider_intersections", col.collider_intersections_max);
    } else {
        json.key("remaining_intersections").null();
        json.key("remaining_collider_intersections").null();
    }
    json.key("memory_bytes").begin_object();
    json.field("backend", c.backend_memory_bytes)
        .field("fabric", c.fabric_memory_bytes)
        .field("total", c.memory_bytes());
    json.end_object();
    json.key("backend_memory_breakdown").begin_object();
    for (const auto& [what, bytes] : c.backend_memory_breakdown) json.field(what, bytes);
    json.end_object();
    json.field("memory_bytes_per_triangle", c.memory_bytes_per_triangle());
    json.field("simulation_seconds", s.simulation_seconds);
    json.field("fps", s.fps);
    json.key("warnings").begin_array();
    for (const std::string& w : run_warnings(c, s)) json.value(w);
    json.end_array();
}

void write_run_json(std::ostream& out, const RunContext& context, const RunSummary& summary,
                    std::span<const StepStats> frames, double wall_seconds, const CaptureSummary* capture) {
    JsonWriter json(out);
    json.begin_object();
    write_summary_fields(json, context, summary);
    json.field("wall_seconds", wall_seconds);
    if (capture != nullptr) {
        json.key("capture").begin_object();
        json.field("renderer", capture->renderer);
        json.field("device", capture->device);
        json.field("path", capture->path);
        json.field("bytes_per_frame", static_cast<double>(capture->bytes_per_frame));
        json.field("torn_frames", static_cast<double>(capture->torn_frames));
        json.field("frames", capture->frames);
        json.field("render_ms_median", capture->render_ms_median);
        json.field("write_ms_median", capture->write_ms_median);
        json.end_object();
    }
    json.key("series").begin_object();
    json.key("step_ms").begin_array(true);
    for (const StepStats& f : frames) json.value(f.step_ms);
    json.end_array();
    json.key("cg_iterations").begin_array(true);
    for (const StepStats& f : frames) json.value(f.cg_iterations);
    json.end_array();
    json.key("cg_not_converged").begin_array(true);
    for (const StepStats& f : frames) json.value(f.cg_not_converged);
    json.end_array();
    json.key("contacts").begin_array(true);
    for (const StepStats& f : frames) json.value(f.collider_contacts);
    json.end_array();
    json.key("energy_gained").begin_array(true);
    for (const StepStats& f : frames) json.value(f.energy_gained);
    json.end_array();
    json.end_object();
    json.end_object();
}

void print_run_summary(std::ostream& out, const RunContext& c, const RunSummary& s, double wall_seconds,
                       const CaptureSummary* capture) {
    out << "\nweft run " << c.scene << ": " << c.backend << " (" << c.device << ")\n";
    out << "  scene        " << c.scene_file << ": " << c.cloths << (c.cloths == 1 ? " cloth, " : " cloths, ")
        << c.vertices << " vertices, " << c.triangles << " triangles\n";
    out << "  solver       dt " << format_fixed(c.dt * 1000.0, 3) << " ms x " << c.substeps << " substeps, "
        << c.newton_iterations << " Newton, CG tol " << json_number(c.cg_tolerance) << " cap " << c.cg_max_iterations
        << ", " << c.precision << "\n";
    out << "  frames       " << s.frames << " in " << format_fixed(wall_seconds, 2) << " s wall, "
        << format_fixed(s.simulation_seconds, 2) << " s stepping: " << format_fixed(s.fps, 2) << " fps\n\n";

    TextTable table({{"stage", TextTable::Align::Left}, {"median ms"}, {"max ms"}, {"mean ms"}});
    for (std::size_t k = 0; k < kStageCount; ++k) {
        const Distribution& d = s.stage_ms[k];
        // Collision stages only where the scene has collisions (the check only where it ran).
        if (k >= static_cast<std::size_t>(Stage::BroadPhase) && !(d.max > 0.0)) continue;
        table.add_row(
            {std::string(kStageNames[k]), format_fixed(d.median, 3), format_fixed(d.max, 3), format_fixed(d.mean, 3)});
    }
    table.add_row({"step (total)", format_fixed(s.step_ms.median, 3), format_fixed(s.step_ms.max, 3),
                   format_fixed(s.step_ms.mean, 3)});
    table.print(out);

    out << "\n  CG iterations  per frame: mean " << format_fixed(s.cg_iterations.mean, 1) << ", max "
        << format_fixed(s.cg_iterations.max, 0) << "; largest solve " << s.cg_iterations_max_solve << "; "
        << s.cg_not_converged << " of " << s.solves << " solves not converged";
    if (s.cg_preconditioner_fallbacks > 0) out << ", " << s.cg_preconditioner_fallbacks << " redone with block-Jacobi (the Schwarz preconditioner not SPD)";
    out << "\n";
    if (s.kernels.max > 0.0)
        out << "  GPU kernels    per frame: median " << format_fixed(s.kernels.median, 0) << ", max "
            << format_fixed(s.kernels.max, 0) << " (a CUDA graph's nodes counted at each launch)\n";
    out << "  NaN/Inf        " << s.non_finite_frames << " frames\n";
    if (c.split_stretch > 0.0)
        out << "  split substeps " << s.split_substeps << " redone as halves (a triangle past " << json_number(c.split_stretch)
            << "x), in " << s.frames_split << " frames; " << s.substeps << " substeps taken\n";
    if (c.energy_guard != "off") {
        out << "  energy guard   " << c.energy_guard << ": " << s.energy_gained << " of " << s.substeps
            << " substeps gained energy";
        if (s.energy_gained > 0) out << " (" << json_number(s.energy_gain) << " J)";
        if (c.energy_guard == "retry") out << ", " << s.energy_retries << " redone";
        if (s.energy_unchecked > 0) out << ", " << s.energy_unchecked << " unchecked (fast or moving mesh collider)";
        out << "\n";
    }
    // Vertex–collider contacts of the analytic colliders; the cloth's pair springs are on the next line.
    out << "  colliders      contacts mean " << format_fixed(s.contacts.mean, 1) << ", max "
        << format_fixed(s.contacts.max, 0) << "\n";
    const auto& col = s.collisions;
    if (col.active) {
        out << "  collisions     pairs/frame median " << format_fixed(col.candidate_pairs.median, 0)
            << (c.culled_pairs_counted ? " (culled " + format_fixed(col.culled_pairs.median, 0) + ")"
                                       : std::string(" (culled pairs not counted: collision.count_culled, cpu backend)"))
            << ", pair springs median " << format_fixed(col.contacts.median, 0)
            << (col.contacts_largest_part.max > 0
                    ? " (busiest GPU " + format_fixed(col.contacts_largest_part.median, 0) +
                          (col.parts_recut > 0 ? "; parts re-cut " + std::to_string(col.parts_recut) + " times" : std::string()) +
                          ")"
                    : std::string())
            << ", CCD " << col.ccd_hits << " hits in " << col.ccd_tests << " tests\n";
        out << "  impact zones   " << col.impact_zones << " zones, at most " << col.impact_iterations_max
            << " rounds per substep; fallbacks: " << col.rigid_zones << " rigid, " << col.frozen_vertices
            << " frozen"
            << (col.impact_work_spent > 0 ? " (work cap spent in " + std::to_string(col.impact_work_spent) + " substeps)" : std::string())
            << "; unresolved substeps " << col.unresolved_substeps
            << (col.reused_detections > 0
                    ? "; first detection from the proximity's pairs in " + std::to_string(col.reused_detections) + " substeps"
                    : std::string())
            << (col.ejected_vertices > 0 ? "; moved out of closed colliders " + std::to_string(col.ejected_vertices)
                                         : std::string())
            << "\n";
        if (col.query_radius_max > 0.0)
            out << "  offset bounds  " << col.truncated_vertices << " vertex moves truncated, " << col.redetections
                << " detection reruns, " << col.bound_fallbacks << " substeps sent to the CCD fallback, "
                << col.uncullings << " uncullings; query radius up to " << format_fixed(1000.0 * col.query_radius_max, 2)
                << " mm\n";
    }
    if (col.checked_frames > 0) {
        out << "  intersections  " << col.frames_with_intersections << " of " << col.checked_frames
            << " checked frames intersecting (max " << col.remaining_intersections_max << " pairs; cloth through a mesh collider in "
            << col.frames_with_collider_intersections << " frames, max " << col.collider_intersections_max << " pairs)\n";
    }
    out << "  memory         " << format_bytes(static_cast<double>(c.memory_bytes())) << " (backend "
        << format_bytes(static_cast<double>(c.backend_memory_bytes)) << " + fabric "
        << format_bytes(static_cast<double>(c.fabric_memory_bytes)) << "; "
        << format_fixed(c.memory_bytes_per_triangle(), 0) << " B per triangle";
    if (s.collisions.buffer_growths > 0)
        out << "; collision buffers grown " << s.collisions.buffer_growths << " times while stepping";
    out << ")\n";
    if (capture != nullptr) {
        out << "  capture        " << capture->frames << " frames by " << capture->renderer << " (" << capture->device
            << "): " << format_fixed(capture->render_ms_median, 2) << " ms host time to draw (overlapping the next step), "
            << format_fixed(capture->write_ms_median, 2) << " ms to write a frame (medians); cloth by "
            << capture->path << ", " << capture->bytes_per_frame << " B per frame, " << capture->torn_frames
            << " torn\n";
        if (!capture->contact_sheet.empty()) out << "  contact sheet  " << capture->contact_sheet << '\n';
        out << "  video          " << (capture->video.empty() ? "none: " + capture->video_note : capture->video) << '\n';
    }
    const auto warnings = run_warnings(c, s);
    if (!warnings.empty()) out << '\n';
    for (const std::string& w : warnings) out << "  WARNING: " << w << '\n';
}

}  // namespace weft::cli
