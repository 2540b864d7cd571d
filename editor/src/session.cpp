// The editor's session (see session.h).
#include "weft/backend/model.h"
#include "weft/editor/session.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "weft/backend/timing.h"
#include "weft/error.h"
#include "weft/editor/presets.h"
#include "weft/parameters.h"

namespace weft::editor {
namespace {

std::vector<std::string> motion_names(const SceneDesc& scene) {
    std::vector<std::string> names;
    for (const SceneMotion& m : scene.motions) names.push_back(m.name);
    return names;
}

bool same_pins(const std::vector<PinSelection>& a, const std::vector<PinSelection>& b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const PinSelection& x, const PinSelection& y) {
        return x.kind == y.kind && x.vertices == y.vertices && x.edge == y.edge && x.motion == y.motion &&
               x.box_min.x == y.box_min.x && x.box_min.y == y.box_min.y && x.box_min.z == y.box_min.z &&
               x.box_max.x == y.box_max.x && x.box_max.y == y.box_max.y && x.box_max.z == y.box_max.z;
    });
}

// "cells 8x8 -> 10x6, density 0.2 -> 0.3 kg/m²": each field `to` sets, from its value in `from`.
std::string change_text(const ClothRecook& from, const ClothRecook& to) {
    std::string out;
    char text[128];
    const auto add = [&] { out += (out.empty() ? "" : ", ") + std::string(text); };
    if (to.cells) {
        std::snprintf(text, sizeof text, "cells %dx%d -> %dx%d", (*from.cells)[0], (*from.cells)[1], (*to.cells)[0],
                      (*to.cells)[1]);
        add();
    }
    if (to.density) {
        std::snprintf(text, sizeof text, "density %g -> %g kg/m\u00b2", *from.density, *to.density);
        add();
    }
    if (to.scale) {
        std::snprintf(text, sizeof text, "scale %g -> %g", *from.scale, *to.scale);
        add();
    }
    if (to.flat_rest_bending) {
        std::snprintf(text, sizeof text, "flat rest bending %s -> %s", *from.flat_rest_bending ? "on" : "off",
                      *to.flat_rest_bending ? "on" : "off");
        add();
    }
    return out;
}

}  // namespace

Session::Session(SceneDesc scene, std::string backend, BackendOptions options, std::unique_ptr<World> world,
                 double time_scale)
    : scene_(std::move(scene)),
      backend_(std::move(backend)),
      options_(options),
      world_(std::move(world)),
      parameters_(*world_, motion_names(scene_), scene_.collider_motions) {
    for (const SceneCloth& c : scene_.cloths) file_pins_.push_back(c.pins);
    FrameLoop::Options loop_options;
    loop_options.time_scale = time_scale;
    loop_ = std::make_unique<FrameLoop>(*world_, loop_options);
}

double Session::apply(const Parameter& p, double value) {
    applied_at_[p.key] = steps_before_reset_ + loop_->steps();
    return ParameterTable::apply(p, *world_, value);
}

std::optional<std::int64_t> Session::applied_at(const std::string& key) const {
    const auto it = applied_at_.find(key);
    if (it == applied_at_.end()) return std::nullopt;
    // Reported in the current loop's count (a reset starts a new loop at 0).
    return it->second - steps_before_reset_;
}

void Session::save(const std::filesystem::path& path) const {
    SceneDesc tuned = scene_;
    update_scene_from_world(tuned, *world_);
    save_scene(tuned, path);
}

std::filesystem::path Session::default_save_path() const {
    const std::filesystem::path& source = scene_.path;
    return source.parent_path() / (source.stem().string() + "_tuned.toml");
}

void Session::reset() {
    // What the designer tuned survives: only the state goes back to the start. The scene takes what
    // was tuned (settings, materials, motions, colliders, pins: what Save writes), so the new world
    // is built with it; where the scene cannot hold it (copies of one table pinned differently), the
    // settings and materials are still carried over by rebuild().
    SceneDesc tuned = scene_;
    try {
        update_scene_from_world(tuned, *world_);
        scene_ = std::move(tuned);
    } catch (const Error& e) {
        set_message(std::string("reset: the live pins, colliders and motions were not kept: ") + e.what());
    }
    rebuild();
}

void Session::rebuild() {
    const WorldDesc settings = world_->settings();
    std::vector<Material> materials;
    for (std::size_t i = 0; i < world_->model().cloths.size(); ++i) materials.push_back(world_->material(i));
    const bool paused = loop_->paused();
    FrameLoop::Options loop_options;
    loop_options.time_scale = loop_->time_scale();
    steps_before_reset_ += loop_->steps();

    loop_.reset();
    grab_anchor_.reset();  // the new world has no grab
    if (before_rebuild_) before_rebuild_();
    world_.reset();
    world_ = build_world(scene_, backend_, options_);
    world_->settings() = settings;
    for (std::size_t i = 0; i < materials.size() && i < world_->model().cloths.size(); ++i)
        world_->material(i) = materials[i];
    loop_ = std::make_unique<FrameLoop>(*world_, loop_options);
    loop_->set_paused(paused);
    history_.clear();
    ++resets_;
}

void Session::apply_preset(const std::string& target, const std::string& name) {
    if (target == "solver") {
        const Preset* preset = find_preset(solver_presets(), name);
        if (preset == nullptr)
            throw Error("unknown solver preset '" + name + "' (presets: " + preset_names(solver_presets()) + ")");
        for (const auto& [key, value] : preset->values) apply(*parameters_.find(key), value);
        set_message("solver preset '" + name + "': " + preset->description);
        return;
    }
    std::size_t entry = scene_.cloth_placements.size();
    for (std::size_t e = 0; e < scene_.cloth_placements.size(); ++e)
        if (scene_.cloth_placements[e].name == target) entry = e;
    if (entry == scene_.cloth_placements.size())
        throw Error("preset: no cloth '" + target + "' in the scene (expected 'solver' or a [[cloth]] table's name)");
    const Preset* preset = find_preset(material_presets(), name);
    if (preset == nullptr)
        throw Error("unknown material preset '" + name + "' (presets: " + preset_names(material_presets()) + ")");
    double density = 0.0;
    for (std::size_t i = 0; i < scene_.cloths.size(); ++i) {
        if (scene_.cloths[i].entry != entry) continue;
        density = scene_.cloths[i].fabric.density;
        for (const auto& [field, value] : preset->values) {
            const Parameter* p = parameters_.find("cloth." + std::to_string(i) + ".material." + field);
            if (p == nullptr) throw Error("preset '" + name + "': no parameter for material field '" + field + "'");
            apply(*p, value);
        }
    }
    std::string said = "material preset '" + name + "' on cloth '" + target + "': " + preset->description;
    if (preset->density > 0.0 && preset->density != density) {
        ClothRecook change;
        change.density = preset->density;
        requests_.recook = PlayRequests::Recook{target, change};
        char text[96];
        std::snprintf(text, sizeof text, "; density %g -> %g kg/m\u00b2 (re-cooking)", density, preset->density);
        said += text;
    }
    set_message(std::move(said));
}

void Session::grab(const VertexPick& pick) {
    double mass = 0.0;
    for (const double m : world_->model().cloths.at(pick.cloth).fabric->masses()) mass += m;
    // Strong enough to carry the whole cloth (2 cm of sag under its weight) and to win against its
    // membrane: ten times the stretch stiffness (N/m), so that the vertex follows the cursor to
    // within about a tenth of how far the cloth is stretched to get there.
    const double k = std::max(grab_stiffness_for(mass), 10.0 * world_->material(pick.cloth).stretch_stiffness);
    // Damping near critical for the grabbed vertex on its own (c = 2·sqrt(k·m_vertex)): the drag
    // does not ring, and the rest of the cloth keeps its own damping.
    const double vertex_mass = world_->model().cloths[pick.cloth].fabric->masses()[pick.vertex];
    world_->set_grab({.cloth = pick.cloth, .vertex = pick.vertex, .target = pick.position, .stiffness = k,
                      .damping = std::min(1e6, 2.0 * std::sqrt(k * vertex_mass))});
    grab_anchor_ = pick.position;
    char text[200];
    std::snprintf(text, sizeof text, "grabbed vertex %u of cloth '%s' (spring %.3g N/m)", pick.vertex,
                  world_->model().cloths[pick.cloth].name.c_str(), k);
    set_message(text);
}

void Session::drag_to(const Vec3d& target) {
    if (!world_->grab()) return;
    VertexGrab g = *world_->grab();
    g.target = target;
    world_->set_grab(g);
}

void Session::release_grab() {
    if (!world_->grab()) return;
    const std::optional<double> d = grab_distance();
    char text[160];
    std::snprintf(text, sizeof text, "released vertex %u, %.3f m from the cursor", world_->grab()->vertex, d.value_or(0.0));
    set_message(text);
    world_->release_grab();
    grab_anchor_.reset();
}

std::optional<double> Session::grab_distance() {
    if (!world_->grab()) return std::nullopt;
    const VertexGrab& g = *world_->grab();
    return math::length(world_->positions(g.cloth)[g.vertex] - g.target);
}

bool Session::toggle_pin(std::size_t cloth, std::uint32_t vertex) {
    if (before_rebuild_) before_rebuild_();
    const bool pinned = world_->is_pinned(cloth, vertex) ? !world_->unpin(cloth, vertex) : world_->pin(cloth, vertex);
    // The rebuild happens at the next read or step; timed here so that the panel can say what it cost.
    const auto start = std::chrono::steady_clock::now();
    (void)world_->positions(cloth);
    const double ms = ms_since(start);
    char text[200];
    std::snprintf(text, sizeof text, "%s vertex %u of cloth '%s' (solver rebuilt in %.1f ms, state kept)",
                  pinned ? "pinned" : "unpinned", vertex, world_->model().cloths[cloth].name.c_str(), ms);
    set_message(text);
    return pinned;
}

double Session::recook(const std::string& cloth, const ClothRecook& change) {
    std::size_t entry = scene_.cloth_placements.size();
    for (std::size_t e = 0; e < scene_.cloth_placements.size(); ++e)
        if (scene_.cloth_placements[e].name == cloth) entry = e;
    if (entry == scene_.cloth_placements.size()) throw Error("re-cook: no cloth '" + cloth + "' in the scene");
    // The ranges of the scene keys (weft/parameters.h).
    if (change.cells) {
        const auto [x, y] = *change.cells;
        const ParameterRange& cells = parameter("cloth.mesh.grid", "cells").range;
        if (!cells.contains(x) || !cells.contains(y))
            throw Error("re-cook: " + std::to_string(x) + "x" + std::to_string(y) + " cells is outside " +
                        cells.integer_text() + " per side");
    }
    const ParameterRange& density = parameter("cloth", "density").range;
    if (change.density && !density.contains(*change.density))
        throw Error("re-cook: density " + std::to_string(*change.density) + " kg/m\u00b2 is outside " + density.text());
    const ParameterRange& scale = parameter("cloth.mesh", "scale").range;
    if (change.scale && !scale.contains(*change.scale))
        throw Error("re-cook: scale " + std::to_string(*change.scale) + " is outside " + scale.text());

    // What was tuned goes into the changed scene, so that the rebuild keeps it, except pins changed
    // live on this cloth when its grid changes: they name vertices of the old mesh, so its file rules
    // stay (density, scale and rest bending keep the vertices). Taken before the mesh changes, while
    // the scene's pin rules still describe the world's fabric.
    SceneDesc changed = scene_;
    update_scene_from_world(changed, *world_);
    bool pins_dropped = false;
    for (std::size_t i = 0; i < changed.cloths.size() && change.cells; ++i) {
        if (changed.cloths[i].entry != entry) continue;
        const std::vector<PinSelection>& file = file_pins_.at(i);
        pins_dropped = pins_dropped || !same_pins(changed.cloths[i].pins, file);
        changed.cloths[i].pins = file;
    }
    std::size_t triangles_before = 0;
    for (std::size_t i = 0; i < world_->model().cloths.size(); ++i)
        if (scene_.cloths[i].entry == entry) triangles_before += world_->model().cloths[i].fabric->triangles().size();
    ClothRecook before;
    for (SceneCloth& c : changed.cloths) {
        if (c.entry != entry) continue;
        before = {std::array<int, 2>{c.source.cells_x, c.source.cells_y}, c.fabric.density, c.source.scale,
                  c.fabric.flat_rest_bending};
        const bool grid = c.source.kind == ClothSource::Kind::Grid;
        if (change.cells && !grid) throw Error("re-cook: cloth '" + cloth + "' comes from a mesh file, not a grid: it has no cells");
        if (change.scale && grid)
            throw Error("re-cook: cloth '" + cloth + "' is a grid: its size is its width and height, not a scale");
        if (change.cells) {
            c.source.cells_x = (*change.cells)[0];
            c.source.cells_y = (*change.cells)[1];
        }
        if (change.scale) c.source.scale = *change.scale;
        if (change.density) c.fabric.density = *change.density;
        if (change.flat_rest_bending) c.fabric.flat_rest_bending = *change.flat_rest_bending;
    }
    const SceneDesc previous = std::exchange(scene_, std::move(changed));
    const auto start = std::chrono::steady_clock::now();
    try {
        rebuild();
    } catch (...) {
        scene_ = previous;
        rebuild();
        throw;
    }
    const double ms = ms_since(start);
    std::size_t triangles_after = 0;
    for (std::size_t i = 0; i < world_->model().cloths.size(); ++i)
        if (scene_.cloths[i].entry == entry) triangles_after += world_->model().cloths[i].fabric->triangles().size();
    char text[320];
    std::snprintf(text, sizeof text, "re-cooked cloth '%s': %s (%zu -> %zu triangles) in %.1f ms", cloth.c_str(),
                  change_text(before, change).c_str(), triangles_before, triangles_after, ms);
    set_message(std::string(text) +
                (pins_dropped ? "; the pins made live on it were dropped (they named vertices of the old mesh)" : ""));
    return ms;
}

}  // namespace weft::editor
