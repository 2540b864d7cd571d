// The editor's panels (see panels.h). Every parameter widget comes from the ParameterTable, and
// every change — a widget moved, or a value a script left pending — goes through Session::apply.
#include "weft/backend/model.h"
#include "weft/editor/panels.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include <imgui.h>

#include "weft/editor/presets.h"
#include "weft/parameters.h"

namespace weft::editor {
namespace {

constexpr float kColumn = 340.0F;  ///< width of the two side columns at ImGui's 13-pixel font, screen pixels

/// The side columns grow with the panels' scale (the font), up to 45 % of the window each.
float column_width(float window_width) {
    return std::min(kColumn * ImGui::GetFontSize() / 13.0F, 0.45F * window_width);
}

// "%.4g N/m": the unit in the slider's own text, so that every value is shown with it.
std::string format_with_unit(const Parameter& p, const char* number) {
    std::string f = number;
    if (!p.unit.empty()) f += " " + p.unit;
    return f;
}

// A tooltip for the item just drawn, wrapped to a readable width (the docs of the parameter table
// run to a sentence or two).
void wrapped_tooltip(const std::string& text) {
    if (!ImGui::IsItemHovered()) return;
    ImGui::BeginTooltip();
    ImGui::PushTextWrapPos(ImGui::GetFontSize() * 32.0F);
    ImGui::TextUnformatted(text.c_str());
    ImGui::PopTextWrapPos();
    ImGui::EndTooltip();
}

void tooltip(const Parameter& p) {
    std::string text = p.key;
    if (p.kind == ParameterKind::real || p.kind == ParameterKind::integer) {
        char range[96];
        std::snprintf(range, sizeof range, "\nvalid range [%g, %g]%s%s", p.min, p.max, p.unit.empty() ? "" : " ",
                      p.unit.c_str());
        text += range;
    }
    if (!p.hint.empty()) text += "\n" + p.hint;
    wrapped_tooltip(text);
}

// The tooltip of a re-cooked scene key: its doc, valid values and unit (weft/parameters.h).
void key_tooltip(const weft::Parameter& p) {
    std::string text = std::string(p.doc) + "\n" + parameter_range_text(p);
    if (!p.unit.empty()) text.append(" ").append(p.unit);
    wrapped_tooltip(text);
}

// The widget of one parameter; returns true with `value` set when the user changed it.
bool widget(const Parameter& p, double& value) {
    const std::string id = p.label + "##" + p.key;
    bool changed = false;
    switch (p.kind) {
        case ParameterKind::real: {
            const ImGuiSliderFlags flags =
                ImGuiSliderFlags_AlwaysClamp | (p.log_scale ? ImGuiSliderFlags_Logarithmic : ImGuiSliderFlags_None);
            changed = ImGui::SliderScalar(id.c_str(), ImGuiDataType_Double, &value, &p.min, &p.max,
                                          format_with_unit(p, "%.4g").c_str(), flags);
            break;
        }
        case ParameterKind::integer: {
            auto v = static_cast<std::int32_t>(std::lround(value));
            const auto lo = static_cast<std::int32_t>(p.min), hi = static_cast<std::int32_t>(p.max);
            const ImGuiSliderFlags flags =
                ImGuiSliderFlags_AlwaysClamp | (p.log_scale ? ImGuiSliderFlags_Logarithmic : ImGuiSliderFlags_None);
            changed = ImGui::SliderScalar(id.c_str(), ImGuiDataType_S32, &v, &lo, &hi,
                                          format_with_unit(p, "%d").c_str(), flags);
            value = v;
            break;
        }
        case ParameterKind::boolean: {
            bool b = value != 0.0;
            changed = ImGui::Checkbox(id.c_str(), &b);
            value = b ? 1.0 : 0.0;
            break;
        }
        case ParameterKind::choice: {
            int index = static_cast<int>(std::lround(value));
            const std::string& shown = p.choices.at(static_cast<std::size_t>(std::clamp(
                index, 0, static_cast<int>(p.choices.size()) - 1)));
            if (ImGui::BeginCombo(id.c_str(), shown.c_str())) {
                for (std::size_t i = 0; i < p.choices.size(); ++i) {
                    const bool selected = static_cast<int>(i) == index;
                    if (ImGui::Selectable(p.choices[i].c_str(), selected)) {
                        index = static_cast<int>(i);
                        changed = true;
                    }
                    if (selected) ImGui::SetItemDefaultFocus();
                }
                ImGui::EndCombo();
            }
            value = index;
            break;
        }
    }
    tooltip(p);
    return changed;
}

// The parameters of one panel. `visible`: its header is open. A closed header draws nothing but
// still applies pending values, so that a script's `set` never depends on what is folded.
void parameter_rows(Session& session, const char* panel, bool visible) {
    std::string group;
    bool group_open = true;
    for (const Parameter& p : session.parameters().parameters()) {
        if (p.panel != panel) continue;
        bool shown = visible;
        if (visible && !p.group.empty()) {
            if (p.group != group) {
                group = p.group;
                ImGui::SetNextItemOpen(true, ImGuiCond_Once);
                group_open = ImGui::TreeNode(group.c_str());
                if (group_open) ImGui::TreePop();  // flat rows under the node: no nesting to close later
            }
            shown = group_open;
        }
        if (p.shown && !p.shown(session.world())) shown = false;  // a size of another shape
        double value = p.get(session.world());
        bool changed = shown && widget(p, value);
        if (const std::optional<double> pending = session.parameters().take_pending(p)) {
            value = *pending;
            changed = true;
        }
        if (changed) session.apply(p, value);
    }
}

void play_controls(Session& session, bool visible) {
    FrameLoop& loop = session.loop();
    PlayRequests& asked = session.requests();
    bool paused = loop.paused();
    int steps = 0;
    bool reset = false;
    double scale = loop.time_scale();
    if (visible) {
        if (ImGui::Button(paused ? "Play" : "Pause", ImVec2(70.0F, 0.0F))) paused = !paused;
        ImGui::SameLine();
        if (ImGui::Button("Step")) ++steps;
        ImGui::SameLine();
        if (ImGui::Button("Reset")) reset = true;
        ImGui::SameLine();
        // Save: the scene with what was tuned, next to the scene file (docs/editor.md).
        if (ImGui::Button("Save")) {
            const std::filesystem::path file = session.default_save_path();
            try {
                session.save(file);
                session.set_message("saved " + file.string());
            } catch (const std::exception& e) {
                session.set_message(std::string("save failed: ") + e.what());
            }
        }
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("write %s", session.default_save_path().string().c_str());
        // Save as: any path (the script's `save FILE` takes the same code path).
        static std::array<char, 1024> save_as{};
        ImGui::InputTextWithHint("##saveas", "save as (.toml)", save_as.data(), save_as.size());
        ImGui::SameLine();
        if (ImGui::Button("Save as") && save_as[0] != '\0') {
            const std::filesystem::path file(save_as.data());
            try {
                session.save(file);
                session.set_message("saved " + file.string());
            } catch (const std::exception& e) {
                session.set_message(std::string("save failed: ") + e.what());
            }
        }
        // Recording: every displayed frame, panels included, as numbered PNGs (and an MP4 at the
        // end when ffmpeg is installed).
        static std::array<char, 1024> record_to{"weft_recording"};
        RecordingStatus& rec = session.recording();
        if (rec.active) {
            if (ImGui::Button("Stop recording")) asked.stop_recording = true;
            ImGui::SameLine();
            ImGui::Text("%d frames to %s", rec.frames, rec.folder.string().c_str());
        } else {
            ImGui::InputText("##record", record_to.data(), record_to.size());
            ImGui::SameLine();
            if (ImGui::Button("Record") && record_to[0] != '\0') asked.record = std::filesystem::path(record_to.data());
            if (!rec.folder.empty())
                ImGui::TextWrapped("last: %d frames in %s; video: %s", rec.frames, rec.folder.string().c_str(),
                                   rec.video.c_str());
        }
        if (!session.message().empty()) ImGui::TextWrapped("%s", session.message().c_str());
        const double lo = 0.01, hi = 100.0;
        ImGui::SliderScalar("time scale", ImGuiDataType_Double, &scale, &lo, &hi, "%.3g x",
                            ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_AlwaysClamp);
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("simulated seconds per wall second, [0.01, 100]");
    }
    // Keys and scripts: the same changes as the buttons.
    if (asked.paused) paused = *asked.paused;
    steps += asked.single_steps;
    reset = reset || asked.reset;
    if (asked.time_scale) scale = *asked.time_scale;
    // Only what this panel applies: an `open` request waits for the editor's loop.
    asked.paused.reset();
    asked.single_steps = 0;
    asked.reset = false;
    asked.time_scale.reset();

    if (reset) session.reset();
    FrameLoop& current = session.loop();  // reset() made a new one
    if (steps > 0) {
        current.set_paused(true);  // a single step is a step of a paused simulation
        current.request_single_step();
    } else if (paused != current.paused()) {
        current.set_paused(paused);
    }
    current.set_time_scale(std::clamp(scale, 0.01, 100.0));
}

void status_lines(Session& session, const PanelLayout& layout) {
    const World& world = session.world();
    ImGui::Text("t = %.3f s, %lld steps%s", world.time(), static_cast<long long>(session.loop().steps()),
                session.loop().paused() ? ", paused" : "");
    ImGui::Text("%.1f fps, %lld steps dropped", layout.fps, static_cast<long long>(session.loop().dropped_steps()));
}

void plot(const char* label, const Series& s, const char* format, float height = 42.0F) {
    char overlay[64];
    std::snprintf(overlay, sizeof overlay, format, static_cast<double>(s.last()));
    ImGui::PlotLines(label, s.values().data(), static_cast<int>(s.size()), static_cast<int>(s.offset()), overlay,
                     FLT_MAX, FLT_MAX, ImVec2(0.0F, height));
}

void stats_panel(Session& session, const PanelLayout& layout) {
    const float column = column_width(layout.width);
    ImGui::SetNextWindowPos(ImVec2(layout.width - column, 0.0F), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(column, layout.height), ImGuiCond_FirstUseEver);
    if (!ImGui::Begin("Stats")) {
        ImGui::End();
        return;
    }
    const StatsHistory& h = session.history();
    const StepStats& s = h.last;
    ImGui::Text("last step: %.2f ms, %d substeps", s.step_ms, s.substeps);
    ImGui::Text("CG: %d iterations (largest solve %d)", s.cg_iterations, s.cg_iterations_max);
    ImGui::Text("CG residual %.2e, %d solves capped", s.cg_residual, s.cg_not_converged);
    ImGui::Text("energy: %d substeps gained (%.3g J), %d redone", s.energy_gained, s.energy_gain, s.energy_retries);
    if (s.split_substeps > 0) ImGui::Text("split: %d substeps redone as halves, %d taken", s.split_substeps, s.substeps);
    ImGui::Text("contacts: %d collider, %d cloth", s.collider_contacts, s.collision.contacts);
    // Offset contact (collision.mode = offset): what the displacement bounds did in the last step.
    if (s.collision.query_radius_max > 0.0)
        ImGui::Text("offset: %lld truncated, %d reruns, %d fallbacks", static_cast<long long>(s.collision.truncated_vertices),
                    s.collision.redetections, s.collision.bound_fallbacks);
    ImGui::Text("history: last %zu steps", h.step_ms.size());
    ImGui::PushItemWidth(-110.0F);
    plot("ms / step", h.step_ms, "%.2f ms");
    if (ImGui::TreeNodeEx("ms per stage", ImGuiTreeNodeFlags_DefaultOpen)) {
        for (std::size_t i = 0; i < h.stage_ms.size(); ++i) {
            if (h.stage_ms[i].max() <= 0.0F) continue;  // a stage this scene does not run
            plot(std::string(kStageNames[i]).c_str(), h.stage_ms[i], "%.2f ms", 30.0F);
        }
        ImGui::TreePop();
    }
    plot("CG iterations", h.cg_iterations, "%.0f");
    plot("log10 residual", h.cg_residual_log10, "%.2f");
    plot("contacts", h.contacts, "%.0f");
    // Collision work and failures, where the scene has the collision stages (or the check) on.
    if (session.world().settings().collision.self_collision || h.impact_zones.max() > 0.0F)
        plot("impact zones", h.impact_zones, "%.0f");
    if (session.world().settings().collision.check) plot("intersections", h.intersections, "%.0f");
    plot("ms / frame", h.frame_ms, "%.1f ms");
    ImGui::PopItemWidth();
    ImGui::End();
}

// A red banner while the last step met trouble, with how often it happened since the last reset.
void warning_banner(Session& session, const PanelLayout& layout) {
    const StatsHistory& h = session.history();
    const bool not_converged = h.last.cg_not_converged > 0;
    const bool non_finite = h.last.non_finite;
    const bool energy = h.last.energy_gained > 0;
    const bool runaway = h.last.runaway_solves > 0;
    const bool overstretched = h.last.max_stretch >= kOverstretch;
    if (!not_converged && !non_finite && !energy && !runaway && !overstretched) return;
    const float width = std::max(200.0F, layout.width - 2.0F * column_width(layout.width) - 20.0F);
    ImGui::SetNextWindowPos(ImVec2((layout.width - width) * 0.5F, 8.0F), ImGuiCond_Always);
    ImGui::SetNextWindowSize(ImVec2(width, 0.0F), ImGuiCond_Always);
    ImGui::PushStyleColor(ImGuiCol_WindowBg, ImVec4(0.75F, 0.08F, 0.08F, 0.95F));
    ImGui::Begin("##warning", nullptr,
                 ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings |
                     ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoInputs);
    if (non_finite)
        ImGui::TextWrapped("NaN or Inf in the last step: the state was restored (%d of %d steps)", h.non_finite_steps,
                           h.steps);
    if (runaway)
        ImGui::TextWrapped("A solve ran away in %d substeps of the last step (cloth over 10 km/s) and was dropped: the "
                           "cloth kept its velocity (%d of %d steps)",
                           h.last.runaway_solves, h.runaway_steps, h.steps);
    if (overstretched)
        ImGui::TextWrapped("Cloth stretched to %.1fx its rest length: torn, or dragged along by a collider or pin "
                           "(%d of %d steps)",
                           h.last.max_stretch, h.overstretched_steps, h.steps);
    if (not_converged)
        ImGui::TextWrapped("CG did not converge in %d solves of the last step (%d of %d steps): raise the cap, "
                           "the substeps, or loosen the tolerance",
                           h.last.cg_not_converged, h.not_converged_steps, h.steps);
    if (energy)
        ImGui::TextWrapped("Energy gained beyond the external work in %d substeps of the last step, %.3g J (%d of %d "
                           "steps): tighten the CG tolerance, or set the energy guard to retry",
                           h.last.energy_gained, h.last.energy_gain, h.energy_gained_steps, h.steps);
    ImGui::End();
    ImGui::PopStyleColor();
}

// What is cooked into a cloth's fabric: the grid's cells or the mesh file's scale, the density and
// the rest bending. The live world cannot take a change of these: the panel says so, and the
// Re-cook button rebuilds the fabric (timed, in the message under the play controls).
void mesh_rows(Session& session) {
    // What each field holds, per scene and cloth table, until re-cooked.
    struct Fields {
        std::array<int, 2> cells{};
        double scale = 1.0, density = 0.0;
        bool flat = false;
    };
    static std::map<std::string, Fields> edited;
    const SceneDesc& scene = session.scene();
    for (std::size_t e = 0; e < scene.cloth_placements.size(); ++e) {
        const std::string& name = scene.cloth_placements[e].name;
        const auto cloth = std::find_if(scene.cloths.begin(), scene.cloths.end(),
                                        [&](const SceneCloth& c) { return c.entry == e; });
        if (cloth == scene.cloths.end()) continue;
        const bool grid = cloth->source.kind == ClothSource::Kind::Grid;
        const Fields cooked{{cloth->source.cells_x, cloth->source.cells_y},
                            cloth->source.scale,
                            cloth->fabric.density,
                            cloth->fabric.flat_rest_bending};
        // Keyed by what is cooked too: after a re-cook (a button, a preset, a script) the fields
        // start from the new fabric.
        char key[160];
        std::snprintf(key, sizeof key, "/%dx%d/%.17g/%.17g/%d", cooked.cells[0], cooked.cells[1], cooked.scale,
                      cooked.density, cooked.flat ? 1 : 0);
        Fields& v = edited.try_emplace(scene.name + "/" + name + key, cooked).first->second;
        ImGui::PushID(name.c_str());
        ImGui::TextUnformatted(grid ? ("cloth " + name + " (grid)").c_str()
                                    : ("cloth " + name + " (" + cloth->source.file.filename().string() + ")").c_str());
        // The scene keys a re-cook changes (weft/parameters.h): labels, units and ranges.
        const weft::Parameter& cells = parameter("cloth.mesh.grid", "cells");
        const weft::Parameter& scale = parameter("cloth.mesh", "scale");
        const weft::Parameter& density = parameter("cloth", "density");
        const weft::Parameter& flat = parameter("cloth", "flat_rest_bending");
        if (grid) {
            ImGui::InputInt2(std::string(cells.label).c_str(), v.cells.data());
            key_tooltip(cells);
        } else {
            ImGui::InputDouble(std::string(scale.label).c_str(), &v.scale, 0.0, 0.0, "%.4g");
            key_tooltip(scale);
        }
        ImGui::InputDouble(std::string(density.label).c_str(), &v.density, 0.0, 0.0,
                           ("%.4g " + std::string(density.unit)).c_str());
        key_tooltip(density);
        ImGui::Checkbox(std::string(flat.label).c_str(), &v.flat);
        key_tooltip(flat);
        ClothRecook change;
        if (grid && v.cells != cooked.cells) change.cells = v.cells;
        if (!grid && v.scale != cooked.scale) change.scale = v.scale;
        if (v.density != cooked.density) change.density = v.density;
        if (v.flat != cooked.flat) change.flat_rest_bending = v.flat;
        if (!change.empty()) {
            ImGui::TextColored(ImVec4(1.0F, 0.8F, 0.3F, 1.0F), "needs re-cooking (the fabric is built again)");
            ImGui::SameLine();
            if (ImGui::Button("Re-cook")) session.requests().recook = PlayRequests::Recook{name, change};
        }
        ImGui::PopID();
    }
}

// A preset menu: a click asks for the preset (applied by Session::apply_preset, below).
void preset_menu(Session& session, const std::string& target, std::span<const Preset> presets) {
    const std::string label = target == "solver" ? std::string("preset") : "preset: " + target;
    if (!ImGui::BeginCombo(label.c_str(), "choose...")) return;
    for (const Preset& p : presets) {
        if (ImGui::Selectable(p.name.c_str())) session.requests().preset = PlayRequests::PresetChoice{target, p.name};
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", p.description.c_str());
    }
    ImGui::EndCombo();
}

// A preset asked for by a menu or a script, applied before the parameter rows draw the new values.
void apply_requested_preset(Session& session) {
    const std::optional<PlayRequests::PresetChoice> choice = std::exchange(session.requests().preset, std::nullopt);
    if (!choice) return;
    try {
        session.apply_preset(choice->target, choice->name);
    } catch (const std::exception& e) {
        session.set_message(std::string("preset failed: ") + e.what());
    }
}

// Every pin of every cloth, with an Unpin button each (Shift+click on the cloth pins more).
void pin_rows(Session& session) {
    World& world = session.world();
    ImGui::TextDisabled("Shift+click a cloth vertex to pin or unpin it");
    std::optional<std::pair<std::size_t, std::uint32_t>> unpin;
    for (std::size_t c = 0; c < world.cloth_count(); ++c) {
        const ClothDesc& cloth = world.cloth(c);
        const std::string title = "cloth " + cloth.name + ": " + std::to_string(cloth.pins.size()) + " pins";
        if (!ImGui::TreeNode(title.c_str())) continue;
        // A long edge pins hundreds of vertices: the list scrolls, drawing only the rows in view.
        const float row = ImGui::GetFrameHeightWithSpacing();
        ImGui::BeginChild("pins", ImVec2(0.0F, std::min(8.0F, static_cast<float>(cloth.pins.size()) + 0.5F) * row), true);
        ImGuiListClipper clipper;
        clipper.Begin(static_cast<int>(cloth.pins.size()));
        while (clipper.Step())
            for (int k = clipper.DisplayStart; k < clipper.DisplayEnd; ++k) {
                const PinDesc& pin = cloth.pins[static_cast<std::size_t>(k)];
                ImGui::PushID(k);
                if (ImGui::SmallButton("Unpin")) unpin = std::make_pair(c, pin.vertex);
                ImGui::SameLine();
                if (pin.motion >= 0)
                    ImGui::Text("vertex %u, follows motion %d", pin.vertex, pin.motion);
                else
                    ImGui::Text("vertex %u", pin.vertex);
                ImGui::PopID();
            }
        ImGui::EndChild();
        ImGui::TreePop();
    }
    if (unpin) (void)session.toggle_pin(unpin->first, unpin->second);  // after the list: it changes the pins
}

// A mesh collider's rows are its friction and position: its triangles are cooked.
void collider_rows(Session& session, bool visible) {
    parameter_rows(session, "colliders", visible);
    if (!visible) return;
    const auto& colliders = session.world().model().colliders;
    if (colliders.empty()) ImGui::TextDisabled("no colliders");
}

void display_rows(Session& session) {
    DisplayOptions& d = session.display();
    ImGui::Checkbox("wireframe", &d.wireframe);
    ImGui::SameLine();
    ImGui::Checkbox("normals", &d.normals);
    ImGui::Checkbox("contacts", &d.contacts);
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("orange: vertices the solver found in a contact with an analytic collider; magenta: vertices in "
                          "a contact with cloth or a mesh collider (both reported by the backend)");
    ImGui::SameLine();
    ImGui::Checkbox("pins", &d.pins);
    if (d.contacts) ImGui::TextDisabled("contact marks: the backend's vertex ids, read back each frame");
}

// The scene browser: the shipped scenes by name, and any scene file by path. Opening replaces the
// session (the editor's loop does it after the panels, docs/editor.md "Scenes").
void scene_browser(Session& session, const PanelLayout& layout) {
    if (layout.scenes != nullptr) {
        for (const std::string& name : *layout.scenes)
            if (ImGui::Selectable(name.c_str(), name == session.scene().name)) session.requests().open = name;
        if (layout.scenes->empty()) ImGui::TextDisabled("no scene folder found");
    }
    // One text field for the whole process: ImGui widgets keep their text in the caller's buffer.
    static std::array<char, 1024> path{};
    ImGui::InputTextWithHint("##file", "a scene file (.toml)", path.data(), path.size());
    ImGui::SameLine();
    if (ImGui::Button("Open file") && path[0] != '\0') session.requests().open = std::string(path.data());
}

}  // namespace

// The keys and mouse actions (docs/editor.md, "Keys and mouse"), listed where the user looks for them.
void help_rows() {
    static constexpr const char* kHelp[][2] = {
        {"left drag", "orbit the camera"},         {"right/middle drag", "pan"},
        {"Ctrl+left drag", "pull a cloth vertex"}, {"Shift+click", "pin / unpin a vertex"},
        {"scroll", "zoom"},                        {"Space", "pause / resume"},
        {"Right arrow, N", "one step (pauses)"},   {"+ / -", "time scale x2 / /2"},
        {"R", "reset the camera"},                 {"S", "screenshot"},
        {"Esc, Q", "quit"},                        {"Ctrl+click a slider", "type a value"},
    };
    for (const auto& row : kHelp) {
        ImGui::TextUnformatted(row[0]);
        ImGui::SameLine(150.0F);
        ImGui::TextDisabled("%s", row[1]);
    }
}

void draw_panels(Session& session, const PanelLayout& layout) {
    ImGui::SetNextWindowPos(ImVec2(0.0F, 0.0F), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(column_width(layout.width), layout.height), ImGuiCond_FirstUseEver);
    const bool open = ImGui::Begin(("Weft: " + session.scene().name).c_str());
    ImGui::PushItemWidth(-150.0F);
    // Play first: a reset replaces the world the other panels edit.
    const bool play = open && ImGui::CollapsingHeader("Play", ImGuiTreeNodeFlags_DefaultOpen);
    play_controls(session, play);
    if (play) status_lines(session, layout);
    if (open && ImGui::CollapsingHeader("Scenes")) scene_browser(session, layout);
    apply_requested_preset(session);
    const bool solver = open && ImGui::CollapsingHeader("Solver", ImGuiTreeNodeFlags_DefaultOpen);
    if (solver) preset_menu(session, "solver", solver_presets());
    parameter_rows(session, "solver", solver);
    const bool materials = open && ImGui::CollapsingHeader("Materials", ImGuiTreeNodeFlags_DefaultOpen);
    if (materials)
        for (const ClothPlacement& table : session.scene().cloth_placements)
            preset_menu(session, table.name, material_presets());
    parameter_rows(session, "materials", materials);
    parameter_rows(session, "collision", open && ImGui::CollapsingHeader("Collision"));
    collider_rows(session, open && ImGui::CollapsingHeader("Colliders"));
    if (open && ImGui::CollapsingHeader("Pins")) pin_rows(session);
    if (open && ImGui::CollapsingHeader("Mesh (re-cook)")) mesh_rows(session);
    if (open && ImGui::CollapsingHeader("View")) display_rows(session);
    parameter_rows(session, "world", open && ImGui::CollapsingHeader("Wind and gravity"));
    if (session.world().motion_count() > 0)
        parameter_rows(session, "motions", open && ImGui::CollapsingHeader("Motions (pins and colliders follow)"));
    if (open && ImGui::CollapsingHeader("Help: keys and mouse")) help_rows();
    ImGui::PopItemWidth();
    ImGui::End();
    stats_panel(session, layout);
    warning_banner(session, layout);
}

}  // namespace weft::editor
