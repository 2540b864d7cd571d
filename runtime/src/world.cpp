// World: owns the model and drives the backend one frame at a time.
#include "weft/world.h"

#include "weft/backend/backend.h"

#include "collision/world_check.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>

#include "cpu/energy.h"
#include "weft/backend/energy_audit.h"
#include "weft/backend/timing.h"
#include "weft/error.h"
#include "weft/parameters.h"

namespace weft {
namespace {

void check_range(const std::string& where, const char* key, double value, double lo, double hi) {
    if (!(value >= lo && value <= hi))
        throw Error(where + ": " + key + " = " + std::to_string(value) + " is outside [" + std::to_string(lo) + ", " +
                    std::to_string(hi) + "]");
}

}  // namespace

// The ranges are the parameter table's (weft/parameters.h), the same the scene loader checks by key:
// a world built through the API is held to what a scene file may say.
World::World(const WorldDesc& desc, std::string_view backend, const BackendOptions& options)
    : model_(std::make_unique<Model>()) {
    check_parameter_ranges(desc);
    model_->settings = desc;
    BackendOptions o = options;
    if (o.threads == 0) o.threads = desc.solver.threads;
    if (o.gpus == 0) o.gpus = desc.solver.gpus;
    backend_ = create_backend(backend, o);
}

World::~World() = default;

void World::forget_audit() { carried_audit_.reset(); }

int World::add_motion(const Motion& motion) {
    forget_audit();
    check_parameter_ranges(motion, "motion " + std::to_string(model_->motions.size()));
    model_->motions.push_back(motion);
    ++model_->topology_version;
    return static_cast<int>(model_->motions.size()) - 1;
}

std::size_t World::add_cloth(const ClothDesc& cloth) {
    forget_audit();
    const std::string where = "cloth '" + cloth.name + "'";
    if (!cloth.fabric) throw Error(where + ": no fabric");
    check_parameter_ranges(cloth.material, where + " material");
    for (const PinDesc& pin : cloth.pins) {
        if (pin.vertex >= cloth.fabric->vertex_count())
            throw Error(where + ": pinned vertex " + std::to_string(pin.vertex) + " is out of range (the fabric has " +
                        std::to_string(cloth.fabric->vertex_count()) + " vertices)");
        if (pin.motion >= static_cast<int>(model_->motions.size()))
            throw Error(where + ": pin follows motion " + std::to_string(pin.motion) + " which does not exist");
    }
    model_->cloths.push_back(cloth);
    ++model_->topology_version;
    return model_->cloths.size() - 1;
}

std::size_t World::add_collider(const ColliderDesc& collider) {
    forget_audit();
    const std::string where = "collider '" + collider.name + "'";
    check_parameter_ranges(collider, where);
    ColliderDesc c = collider;
    if (c.skin != nullptr) {
        if (c.shape != ColliderShape::Mesh) throw Error(where + ": a skin needs shape = mesh");
        validate(*c.skin);
        if (!c.mesh) c.mesh = std::make_shared<const MeshData>(c.skin->mesh);
        if (c.mesh->positions.size() != c.skin->mesh.positions.size())
            throw Error(where + ": its mesh has " + std::to_string(c.mesh->positions.size()) + " vertices, its skin " +
                        std::to_string(c.skin->mesh.positions.size()));
        if (!c.clip.empty()) (void)c.skin->clip(c.clip);  // names the clips there are
        if (!(c.clip_speed >= 0.0) || !std::isfinite(c.clip_speed))
            throw Error(where + ": clip_speed " + std::to_string(c.clip_speed) + " (expected a finite speed >= 0)");
        if (!std::isfinite(c.clip_start))
            throw Error(where + ": clip_start " + std::to_string(c.clip_start) + " (expected a finite time in s)");
        if (!(c.clip_fade >= 0.0) || !std::isfinite(c.clip_fade) || !std::isfinite(c.fade_start) ||
            !std::isfinite(c.fade_from_start) || !(c.fade_from_speed >= 0.0) || !std::isfinite(c.fade_from_speed))
            throw Error(where + ": clip_fade " + std::to_string(c.clip_fade) + ", fade_from_speed " +
                        std::to_string(c.fade_from_speed) + " (expected a finite fade >= 0 s, speed >= 0 and finite times)");
        if (!c.fade_from_clip.empty()) (void)c.skin->clip(c.fade_from_clip);
        if (!c.fade_from_pose.empty() && c.fade_from_pose.size() != c.skin->joints.size())
            throw Error(where + ": fade_from_pose has " + std::to_string(c.fade_from_pose.size()) + " joint poses for a skin of " +
                        std::to_string(c.skin->joints.size()) + " joints");
    }
    model_->colliders.push_back(std::move(c));
    ++model_->topology_version;
    return model_->colliders.size() - 1;
}

void World::ensure_built() const {
    if (built_version_ == model_->topology_version) return;
    // A world built before keeps the state of each cloth that is still the same size: adding a
    // pin, a collider or another cloth does not send the others back to their start.
    std::vector<std::vector<Vec3d>> x, v;
    if (built_version_ != ~std::uint64_t{0})
        for (std::size_t c = 0; c < built_vertex_counts_.size() && c < model_->cloths.size(); ++c) {
            if (model_->cloths[c].fabric->vertex_count() != built_vertex_counts_[c]) break;
            x.emplace_back(built_vertex_counts_[c]);
            v.emplace_back(built_vertex_counts_[c]);
            backend_->read_state(c, x.back(), v.back());
        }
    backend_->build(*model_);
    for (std::size_t c = 0; c < x.size(); ++c) backend_->write_state(c, x[c], v[c]);
    built_version_ = model_->topology_version;
    built_vertex_counts_.clear();
    for (const ClothDesc& c : model_->cloths) built_vertex_counts_.push_back(c.fabric->vertex_count());
}

namespace {
void check_vertex(const Model& m, std::size_t cloth, std::uint32_t vertex, const char* what) {
    if (cloth >= m.cloths.size())
        throw Error(std::string(what) + ": cloth " + std::to_string(cloth) + " of " + std::to_string(m.cloths.size()));
    if (vertex >= m.cloths[cloth].fabric->vertex_count())
        throw Error(std::string(what) + ": vertex " + std::to_string(vertex) + " of cloth '" + m.cloths[cloth].name +
                    "', which has " + std::to_string(m.cloths[cloth].fabric->vertex_count()));
}
}  // namespace

void World::set_grab(const VertexGrab& grab) {
    forget_audit();
    check_vertex(*model_, grab.cloth, grab.vertex, "grab");
    check_range("grab", "stiffness", grab.stiffness, 0.0, 1e9);
    check_range("grab", "damping", grab.damping, 0.0, 1e6);
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(grab.target[k])) throw Error("grab: the target is not finite");
    model_->grab = grab;
}


bool World::is_pinned(std::size_t cloth, std::uint32_t vertex) const {
    check_vertex(*model_, cloth, vertex, "pin");
    const auto& pins = model_->cloths[cloth].pins;
    return std::any_of(pins.begin(), pins.end(), [&](const PinDesc& p) { return p.vertex == vertex; });
}

bool World::pin(std::size_t cloth, std::uint32_t vertex) {
    forget_audit();
    if (is_pinned(cloth, vertex)) return false;
    PinDesc p;
    p.vertex = vertex;
    p.position = positions(cloth)[vertex];
    model_->cloths[cloth].pins.push_back(p);
    ++model_->topology_version;
    return true;
}

bool World::unpin(std::size_t cloth, std::uint32_t vertex) {
    forget_audit();
    if (!is_pinned(cloth, vertex)) return false;
    auto& pins = model_->cloths[cloth].pins;
    pins.erase(std::remove_if(pins.begin(), pins.end(), [&](const PinDesc& p) { return p.vertex == vertex; }), pins.end());
    ++model_->topology_version;
    return true;
}

void World::build() {
    forget_audit();
    ensure_built();
}

WorldDesc& World::settings() {
    forget_audit();
    return model_->settings;
}
const WorldDesc& World::settings() const { return model_->settings; }
Material& World::material(std::size_t cloth) {
    forget_audit();
    return model_->cloths.at(cloth).material;
}
Motion& World::motion(int index) {
    forget_audit();
    return model_->motions.at(static_cast<std::size_t>(index));
}
ColliderDesc& World::collider(std::size_t index) {
    forget_audit();
    return model_->colliders.at(index);
}
void World::set_collider_shape(std::size_t index, ColliderShape shape) {
    const auto names = parameter("collider", "shape").choices;
    if (index >= model_->colliders.size())
        throw Error("set_collider_shape: collider " + std::to_string(index) + " of " + std::to_string(model_->colliders.size()));
    ColliderDesc& c = model_->colliders[index];
    if (static_cast<std::size_t>(shape) >= names.size())
        throw Error("collider '" + c.name + "': shape " + std::to_string(static_cast<int>(shape)) + " is not a shape");
    const std::string from(names[static_cast<std::size_t>(c.shape)]), to(names[static_cast<std::size_t>(shape)]);
    if (c.shape == ColliderShape::Mesh || shape == ColliderShape::Mesh)
        throw Error("collider '" + c.name + "': a " + from + " cannot become a " + to +
                    " live (a mesh collider's triangles come from a file: add a collider)");
    if (shape == c.shape) return;
    forget_audit();
    // The new shape the old one's extent: along the local y axis (a capsule's) and across it.
    const Vec3d& h = c.half_extents;
    const double across = c.shape == ColliderShape::Box ? std::max(h.x, h.z) : c.radius;
    const double along = c.shape == ColliderShape::Box       ? h.y
                         : c.shape == ColliderShape::Capsule ? c.half_height + c.radius
                                                             : c.radius;
    switch (shape) {
        case ColliderShape::Sphere: c.radius = std::max(across, along); break;
        case ColliderShape::Capsule:
            c.radius = across;
            c.half_height = std::max(0.0, along - across);
            break;
        case ColliderShape::Box: c.half_extents = Vec3d{across, along, across}; break;
        default: break;  // a plane has no size
    }
    c.shape = shape;
    ++model_->topology_version;  // cooked: rebuilt at the next step, the cloths' state kept (ensure_built)
}
const ClothDesc& World::cloth(std::size_t index) const { return model_->cloths.at(index); }
std::size_t World::cloth_count() const { return model_->cloths.size(); }
std::size_t World::collider_count() const { return model_->colliders.size(); }
std::size_t World::motion_count() const { return model_->motions.size(); }
const Model& World::model() const { return *model_; }
std::string_view World::backend_name() const { return backend_->name(); }
std::string World::device_description() const {
    ensure_built();  // a backend describes what it built (the cpu backend's precision is chosen there)
    return backend_->device_description();
}
std::size_t World::memory_bytes() const { return backend_->memory_bytes(); }
std::vector<std::pair<std::string, std::size_t>> World::memory_breakdown() const { return backend_->memory_breakdown(); }
void World::release_grab() {
    forget_audit();
    model_->grab.reset();
}
const std::optional<VertexGrab>& World::grab() const { return model_->grab; }

const StepStats& World::step() {
    check_parameter_ranges(model_->settings);
    ensure_built();
    const auto start = std::chrono::steady_clock::now();
    stats_ = StepStats{};
    const int substeps = model_->settings.solver.substeps;
    const double h = model_->settings.solver.dt / substeps;
    const EnergyGuard guard = model_->settings.solver.energy_guard;
    EnergyAudit audit;
    // The wind's power is in every audit when there is wind: a substep's allowance needs it at both
    // ends (the first step of a flag from rest in gusty wind gains more than twice the end power
    // alone allows, with a converged solve).
    const bool wind = model_->settings.wind.active();
    // The last step's end audit is this step's start audit while nothing changed since (forget_audit);
    // taken out first, so that a step that throws leaves none behind.
    const std::unique_ptr<EnergyAudit> carried = std::move(carried_audit_);
    // Splitting overstretched substeps (split_stretch) judges each by the audit's stretch, so it
    // audits even with the guard off (the wind's power then left out: only the stretch is read).
    const bool split = model_->settings.solver.split_stretch > 0.0;
    const bool audit_wind = wind && guard != EnergyGuard::Off;
    if (guard != EnergyGuard::Off || split) {
        if (carried && carried_h_ == h && carried_wind_ == audit_wind)
            audit = *carried;
        else
            audit = backend_->energy_audit(*model_, time_, h, audit_wind);
    }
    // Where substeps were split lately, they start split: the state that needed it (a body pushing
    // through cloth) lasts several frames, and a split only once the stretch is past the limit comes
    // late each time. The level steps back one halving after kSplitRelaxSubsteps substeps without a
    // split, as a step-size controller grows its step again.
    const int max_splits = model_->settings.solver.max_substep_splits;
    if (!split) split_level_ = 0;
    split_level_ = std::min(split_level_, max_splits);
    const int pieces = 1 << split_level_;
    deepest_split_ = 0;
    if (split) {  // before the recursion, which holds references into them
        split_start_.resize(static_cast<std::size_t>(max_splits) + 1);
        split_whole_.resize(split_start_.size());
    }
    for (int s = 0; s < substeps; ++s) {
        if (split) {
            // The guard judges each piece against an audit at the piece's length (the collider
            // penalty's stiffness depends on it).
            if (pieces > 1 && guard != EnergyGuard::Off) audit = backend_->energy_audit(*model_, time_, h / pieces, audit_wind);
            for (int k = 0; k < pieces; ++k)
                stats_.substeps += split_substep(time_ + h * k / pieces, h / pieces, audit, split_level_);
        } else if (guard == EnergyGuard::Off)
            backend_->substep(*model_, time_, h, stats_);
        else
            guarded_substep(time_, h, guard == EnergyGuard::Retry, audit);
        if (!split) ++stats_.substeps;
        time_ += h;
    }
    ++steps_;
    if (split && pieces > 1 && guard != EnergyGuard::Off)
        audit = backend_->energy_audit(*model_, time_, h, audit_wind);  // at the step's h, to carry
    if (split) {
        if (deepest_split_ > split_level_) {
            split_level_ = deepest_split_;
            substeps_since_split_ = 0;
        } else if (stats_.split_substeps == 0 && (substeps_since_split_ += substeps) >= kSplitRelaxSubsteps && split_level_ > 0) {
            --split_level_;
            substeps_since_split_ = 0;
        }
    }
    if (guard != EnergyGuard::Off || split) {
        stats_.max_stretch = audit.max_stretch;  // the audit of the step's end state
        carried_audit_ = std::make_unique<EnergyAudit>(audit);
        carried_h_ = h;
        carried_wind_ = audit_wind;
    }
    if (model_->settings.collision.check) {
        const auto check_start = std::chrono::steady_clock::now();
        std::vector<std::vector<Vec3d>> x(model_->cloths.size());
        for (std::size_t c = 0; c < x.size(); ++c) x[c] = positions(c);
        const collision::WorldIntersections found = collision::check_world_intersections(*model_, x, time_);
        stats_.collision.remaining_intersections = static_cast<std::int64_t>(found.total());
        stats_.collision.remaining_collider_intersections = static_cast<std::int64_t>(found.cloth_with_collider);
        stats_.ms(Stage::Check) += ms_since(check_start);
    }
    stats_.step_ms = ms_since(start);
    return stats_;
}

void World::read_all_states(std::vector<std::vector<Vec3d>>& x, std::vector<std::vector<Vec3d>>& v) const {
    const std::size_t cloths = model_->cloths.size();
    x.resize(cloths);
    v.resize(cloths);
    for (std::size_t c = 0; c < cloths; ++c) {
        x[c].resize(model_->cloths[c].fabric->vertex_count());
        v[c].resize(x[c].size());
        backend_->read_state(c, x[c], v[c]);
    }
}

void World::write_all_states(const std::vector<std::vector<Vec3d>>& x, const std::vector<std::vector<Vec3d>>& v) {
    for (std::size_t c = 0; c < x.size(); ++c) backend_->write_state(c, x[c], v[c]);
}

void World::audited_substep(double t, double h, EnergyAudit& audit) {
    const EnergyGuard guard = model_->settings.solver.energy_guard;
    if (guard != EnergyGuard::Off) {
        guarded_substep(t, h, guard == EnergyGuard::Retry, audit);
        return;
    }
    backend_->substep(*model_, t, h, stats_);
    audit = backend_->energy_audit(*model_, t + h, h, false);
}

// A substep split where it overstretched the cloth (SolverSettings::split_stretch; docs/methods.md
// §1c). The criterion is geometric, not an error estimate of the integrator: a triangle past the
// limit and longer than at the substep's start was stretched within the substep, and with a long
// step that is how a fast kinematic body drags light cloth (the solve moves it through the body, the
// collision stages put it back in front, and the cloth behind it opens). Two halves from the same
// start take the body's motion in shorter pieces, each of which may split again. The whole attempt
// is kept where the halves stretched more (a stretch the pins impose, which no step length cures).
// `audit` holds the audit at t and is left holding the one at t + h, taken at length h.
int World::split_substep(double t, double h, EnergyAudit& audit, int depth) {
    const double limit = model_->settings.solver.split_stretch;
    const EnergyAudit start = audit;
    const bool may_split = depth < model_->settings.solver.max_substep_splits;
    SavedStates& saved_start = split_start_[static_cast<std::size_t>(depth)];
    if (may_split) read_all_states(saved_start.x, saved_start.v);
    audited_substep(t, h, audit);
    if (!may_split || !(audit.max_stretch > limit && audit.max_stretch > start.max_stretch)) return 1;
    ++stats_.split_substeps;
    const EnergyAudit whole = audit;
    SavedStates& saved_whole = split_whole_[static_cast<std::size_t>(depth)];
    read_all_states(saved_whole.x, saved_whole.v);
    write_all_states(saved_start.x, saved_start.v);
    // The guard judges each half against an audit at the half's length (the collider penalty's
    // stiffness depends on it); without the guard only the stretch is read, which h does not change.
    const bool guarded = model_->settings.solver.energy_guard != EnergyGuard::Off;
    const bool wind = model_->settings.wind.active() && guarded;
    EnergyAudit halves = guarded ? backend_->energy_audit(*model_, t, 0.5 * h, wind) : start;
    const int deepest_before = deepest_split_;
    int pieces = split_substep(t, 0.5 * h, halves, depth + 1);
    pieces += split_substep(t + 0.5 * h, 0.5 * h, halves, depth + 1);
    if (halves.max_stretch > whole.max_stretch) {
        write_all_states(saved_whole.x, saved_whole.v);
        audit = whole;
        deepest_split_ = deepest_before;  // the halves' own splits went with them: they set no level
        return 1;
    }
    deepest_split_ = std::max(deepest_split_, depth + 1);  // only a split that helped makes the next substeps start split
    audit = guarded ? backend_->energy_audit(*model_, t + h, h, wind) : halves;
    return pieces;
}

// One substep under the energy guard (docs/methods.md §1b). `audit` holds the audit of the state at
// t and is left holding the one at t + h. What a redo restores is what the substep reads:
// every cloth's positions and velocities (through the backend) and the time, which the World advances
// only after this returns; motions, colliders and the gust field are functions of the time. What it
// does not restore is the backend's own carry-over from the failed attempt: the CPU backend's CG
// warm start is cleared by write_state (the redo starts cold, which only costs iterations), and the
// collision stages' caches are rebuilt each substep from the state. The stats of both attempts are
// summed: the work was done.
void World::guarded_substep(double t, double h, bool retry, EnergyAudit& audit) {
    if (retry) read_all_states(guard_x_, guard_v_);
    // Two corrections after the solve change the state by rules that are not an implicit step, so
    // the criterion does not hold for them and a substep they acted in is not judged: a fast
    // analytic collider that carried vertices along (they take its velocity), and impact zones
    // (their projections move vertices by geometry alone, and can stretch the cloth: on `layers`
    // they put 25 J of strain into four sheets that fell with 2 J). Returns whether it is judged.
    const auto attempt = [&](EnergyAudit& end, int pieces = 1) {
        const int swept = stats_.collision.swept_collider_hits;
        const int zones = stats_.collision.impact_zones;
        for (int k = 0; k < pieces; ++k) backend_->substep(*model_, t + h * k / pieces, h / pieces, stats_);
        end = backend_->energy_audit(*model_, t + h, h, model_->settings.wind.active());
        return audit.bounded && end.bounded && stats_.collision.swept_collider_hits == swept &&
               stats_.collision.impact_zones == zones;
    };
    const auto judge = [&](const EnergyAudit& end) { return energy_excess(audit, end, h); };
    EnergyAudit end;
    if (!attempt(end)) {
        ++stats_.energy_unchecked;
        audit = end;
        return;
    }
    double excess = judge(end);
    if (excess > 0.0 && retry) {
        ++stats_.energy_retries;
        // The redos (below) can do worse than the attempt before them (plain Newton from a poor
        // linearisation can diverge): the attempt that gained least is kept, its state saved as the
        // best so far before the next redo starts from the substep's start.
        std::vector<std::vector<Vec3d>> best_x, best_v;
        EnergyAudit best_end = end;
        double best = excess;
        const auto save_best = [&] { read_all_states(best_x, best_v); };
        const auto restart = [&] { write_all_states(guard_x_, guard_v_); };
        save_best();
        restart();
        SolverSettings& solver = model_->settings.solver;
        const double tolerance = solver.cg_tolerance;
        const double velocity_tolerance = solver.cg_velocity_tolerance;
        const int cap = solver.cg_max_iterations;
        const int newton = solver.newton_iterations;
        // The parameter table's bounds (1e-12, 100000 and 50), so the settings stay valid while
        // changed. More Newton iterations: a gain that is not the CG's stopping point is the
        // linearisation's (one Baraff–Witkin step of a stiff sheet over a long step, a fast
        // collider's penalty): measured on the stability matrix, they cure the moving ball and the
        // 2.5 mm cells where the tighter CG alone cured nothing. Where they do not either, the
        // substep is redone once more as four quarter substeps.
        const bool line_search = solver.line_search;
        solver.line_search = true;  // and backtracking on each update: plain Newton may diverge (CPU backend)
        solver.cg_tolerance = std::max(1e-12, tolerance / 100.0);
        solver.cg_velocity_tolerance = velocity_tolerance / 10.0;  // the energy test's floor / 100
        solver.cg_max_iterations = static_cast<int>(std::min<long>(100'000, 4L * cap));
        solver.newton_iterations = std::min(50, 4 * newton);
        bool judged = attempt(end);
        double current = judged ? judge(end) : 0.0;
        if (judged && current > 0.0) {
            if (current < best) {
                best = current;
                best_end = end;
                save_best();
            }
            restart();
            judged = attempt(end, 4);
            current = judged ? judge(end) : 0.0;
        }
        solver.cg_tolerance = tolerance;
        solver.cg_velocity_tolerance = velocity_tolerance;
        solver.cg_max_iterations = cap;
        solver.newton_iterations = newton;
        solver.line_search = line_search;
        if (!judged) {
            ++stats_.energy_unchecked;
            audit = end;
            return;
        }
        if (current > best) {
            write_all_states(best_x, best_v);
            end = best_end;
            current = best;
        }
        excess = current;
    }
    if (excess > 0.0) {
        ++stats_.energy_gained;
        stats_.energy_gain += excess;
    }
    audit = end;
}

std::vector<Vec3d> World::positions(std::size_t cloth) const {
    const auto n = model_->cloths.at(cloth).fabric->vertex_count();
    std::vector<Vec3d> x(n), v(n);
    ensure_built();
    backend_->read_state(cloth, x, v);
    return x;
}

std::optional<std::vector<std::uint32_t>> World::contact_vertices(std::size_t cloth) const {
    (void)model_->cloths.at(cloth);  // a cloth that does not exist is an error, not an empty list
    ensure_built();
    std::vector<std::uint32_t> out;
    if (!backend_->contact_vertices(cloth, out)) return std::nullopt;
    return out;
}

std::optional<std::vector<std::uint32_t>> World::collider_contact_vertices(std::size_t cloth) const {
    (void)model_->cloths.at(cloth);
    ensure_built();
    std::vector<std::uint32_t> out;
    if (!backend_->collider_contact_vertices(cloth, out)) return std::nullopt;
    return out;
}

std::vector<Vec3d> World::velocities(std::size_t cloth) const {
    const auto n = model_->cloths.at(cloth).fabric->vertex_count();
    std::vector<Vec3d> x(n), v(n);
    ensure_built();
    backend_->read_state(cloth, x, v);
    return v;
}

void World::set_state(std::size_t cloth, std::span<const Vec3d> positions, std::span<const Vec3d> velocities) {
    const auto n = model_->cloths.at(cloth).fabric->vertex_count();
    if (positions.size() != n || velocities.size() != n)
        throw Error("set_state: cloth " + std::to_string(cloth) + " has " + std::to_string(n) + " vertices, got " +
                    std::to_string(positions.size()) + " positions and " + std::to_string(velocities.size()) +
                    " velocities");
    ensure_built();
    forget_audit();
    backend_->write_state(cloth, positions, velocities);
}

std::vector<IntersectingTriangles> World::intersections(std::size_t max_pairs) const {
    std::vector<std::vector<Vec3d>> x(model_->cloths.size());
    for (std::size_t c = 0; c < x.size(); ++c) x[c] = positions(c);
    return collision::list_world_intersections(*model_, x, time_, max_pairs);
}

double World::energy() const {
    double e = 0.0;
    for (std::size_t c = 0; c < model_->cloths.size(); ++c)
        e += cpu::cloth_energy(model_->cloths[c], model_->settings, positions(c), velocities(c)).total();
    return e;
}

}  // namespace weft
