// World: owns the model and drives the backend one frame at a time.
#include "weft/world.h"

#include "collision/world_check.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "cpu/energy.h"
#include "weft/backend/timing.h"
#include "weft/error.h"

namespace weft {
namespace {

void check_range(const std::string& where, const char* key, double value, double lo, double hi) {
    if (!(value >= lo && value <= hi))
        throw Error(where + ": " + key + " = " + std::to_string(value) + " is outside [" + std::to_string(lo) + ", " +
                    std::to_string(hi) + "]");
}

void validate(const Material& m, const std::string& where) {
    check_range(where, "stretch_stiffness", m.stretch_stiffness, 1.0, 1e8);
    check_range(where, "poisson_ratio", m.poisson_ratio, 0.0, 0.49);
    check_range(where, "bending_stiffness", m.bending_stiffness, 0.0, 1.0);
    check_range(where, "damping_mass", m.damping_mass, 0.0, 100.0);
    check_range(where, "damping_stiffness", m.damping_stiffness, 0.0, 1.0);
    check_range(where, "drag_coefficient", m.drag_coefficient, 0.0, 10.0);
    check_range(where, "lift_coefficient", m.lift_coefficient, 0.0, 10.0);
    check_range(where, "contact_thickness", m.contact_thickness, 1e-5, 0.1);
    check_range(where, "friction", m.friction, 0.0, 10.0);
}

void validate(const SolverSettings& s) {
    check_range("solver", "dt", s.dt, 1e-5, 0.1);
    check_range("solver", "substeps", s.substeps, 1, 1000);
    check_range("solver", "newton_iterations", s.newton_iterations, 1, 50);
    check_range("solver", "cg_tolerance", s.cg_tolerance, 1e-12, 1.0);
    check_range("solver", "cg_max_iterations", s.cg_max_iterations, 1, 100000);
    check_range("solver", "contact_stiffness", s.contact_stiffness, 0.0, 1e12);
    check_range("solver", "threads", s.threads, 0, 1024);
}

// The ranges of settings.h, for worlds built through the API (the scene loader checks them by key).
void validate(const CollisionSettings& c) {
    check_range("collision", "thickness", c.thickness, 0.0, 0.1);
    check_range("collision", "stiffness", c.stiffness, 0.0, 1e9);
    check_range("collision", "rest_exclusion", c.rest_exclusion, 0.0, 10.0);
    check_range("collision", "max_impact_iterations", c.max_impact_iterations, 1, 1000);
    check_range("collision", "impact_tolerance", c.impact_tolerance, 0.0, 0.5);
    check_range("collision", "max_impact_sweeps", c.max_impact_sweeps, 0, 100000);
}

}  // namespace

World::World(const WorldDesc& desc, std::string_view backend, const BackendOptions& options) {
    validate(desc.solver);
    validate(desc.collision);
    model_.settings = desc;
    BackendOptions o = options;
    if (o.threads == 0) o.threads = desc.solver.threads;
    backend_ = create_backend(backend, o);
}

World::~World() = default;

int World::add_motion(const Motion& motion) {
    model_.motions.push_back(motion);
    ++model_.topology_version;
    return static_cast<int>(model_.motions.size()) - 1;
}

std::size_t World::add_cloth(const ClothDesc& cloth) {
    const std::string where = "cloth '" + cloth.name + "'";
    if (!cloth.fabric) throw Error(where + ": no fabric");
    validate(cloth.material, where + " material");
    for (const PinDesc& pin : cloth.pins) {
        if (pin.vertex >= cloth.fabric->vertex_count())
            throw Error(where + ": pinned vertex " + std::to_string(pin.vertex) + " is out of range (the fabric has " +
                        std::to_string(cloth.fabric->vertex_count()) + " vertices)");
        if (pin.motion >= static_cast<int>(model_.motions.size()))
            throw Error(where + ": pin follows motion " + std::to_string(pin.motion) + " which does not exist");
    }
    model_.cloths.push_back(cloth);
    ++model_.topology_version;
    return model_.cloths.size() - 1;
}

std::size_t World::add_collider(const ColliderDesc& collider) {
    const std::string where = "collider '" + collider.name + "'";
    if (collider.shape == ColliderShape::Sphere || collider.shape == ColliderShape::Capsule)
        check_range(where, "radius", collider.radius, 1e-6, 1e6);
    if (collider.shape == ColliderShape::Capsule) check_range(where, "half_height", collider.half_height, 0.0, 1e6);
    if (collider.shape == ColliderShape::Box)
        for (int k = 0; k < 3; ++k) check_range(where, "half_extents", collider.half_extents[k], 1e-6, 1e6);
    if (collider.friction > 10.0) check_range(where, "friction", collider.friction, 0.0, 10.0);
    model_.colliders.push_back(collider);
    ++model_.topology_version;
    return model_.colliders.size() - 1;
}

void World::ensure_built() const {
    if (built_version_ == model_.topology_version) return;
    // A world built before keeps the state of each cloth that is still the same size: adding a
    // pin, a collider or another cloth does not send the others back to their start.
    std::vector<std::vector<Vec3d>> x, v;
    if (built_version_ != ~std::uint64_t{0})
        for (std::size_t c = 0; c < built_vertex_counts_.size() && c < model_.cloths.size(); ++c) {
            if (model_.cloths[c].fabric->vertex_count() != built_vertex_counts_[c]) break;
            x.emplace_back(built_vertex_counts_[c]);
            v.emplace_back(built_vertex_counts_[c]);
            backend_->read_state(c, x.back(), v.back());
        }
    backend_->build(model_);
    for (std::size_t c = 0; c < x.size(); ++c) backend_->write_state(c, x[c], v[c]);
    built_version_ = model_.topology_version;
    built_vertex_counts_.clear();
    for (const ClothDesc& c : model_.cloths) built_vertex_counts_.push_back(c.fabric->vertex_count());
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
    check_vertex(model_, grab.cloth, grab.vertex, "grab");
    check_range("grab", "stiffness", grab.stiffness, 0.0, 1e9);
    check_range("grab", "damping", grab.damping, 0.0, 1e6);
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(grab.target[k])) throw Error("grab: the target is not finite");
    model_.grab = grab;
}


bool World::is_pinned(std::size_t cloth, std::uint32_t vertex) const {
    check_vertex(model_, cloth, vertex, "pin");
    const auto& pins = model_.cloths[cloth].pins;
    return std::any_of(pins.begin(), pins.end(), [&](const PinDesc& p) { return p.vertex == vertex; });
}

bool World::pin(std::size_t cloth, std::uint32_t vertex) {
    if (is_pinned(cloth, vertex)) return false;
    PinDesc p;
    p.vertex = vertex;
    p.position = positions(cloth)[vertex];
    model_.cloths[cloth].pins.push_back(p);
    ++model_.topology_version;
    return true;
}

bool World::unpin(std::size_t cloth, std::uint32_t vertex) {
    if (!is_pinned(cloth, vertex)) return false;
    auto& pins = model_.cloths[cloth].pins;
    pins.erase(std::remove_if(pins.begin(), pins.end(), [&](const PinDesc& p) { return p.vertex == vertex; }), pins.end());
    ++model_.topology_version;
    return true;
}

std::unique_ptr<SharedOutput> World::share_output(std::span<const SharedSlotHandle> slots, const DeviceUuid& device,
                                                 std::string& why) {
    ensure_built();
    return backend_->share_output(slots, device, why);
}

const StepStats& World::step() {
    validate(model_.settings.solver);
    validate(model_.settings.collision);
    ensure_built();
    const auto start = std::chrono::steady_clock::now();
    stats_ = StepStats{};
    const int substeps = model_.settings.solver.substeps;
    const double h = model_.settings.solver.dt / substeps;
    for (int s = 0; s < substeps; ++s) {
        backend_->substep(model_, time_, h, stats_);
        time_ += h;
        ++stats_.substeps;
    }
    ++steps_;
    if (model_.settings.collision.check) {
        const auto check_start = std::chrono::steady_clock::now();
        std::vector<std::vector<Vec3d>> x(model_.cloths.size());
        for (std::size_t c = 0; c < x.size(); ++c) x[c] = positions(c);
        stats_.collision.remaining_intersections =
            static_cast<std::int64_t>(collision::check_world_intersections(model_, x, time_).intersecting_pairs);
        stats_.ms(Stage::Check) += ms_since(check_start);
    }
    stats_.step_ms = ms_since(start);
    return stats_;
}

std::vector<Vec3d> World::positions(std::size_t cloth) const {
    const auto n = model_.cloths.at(cloth).fabric->vertex_count();
    std::vector<Vec3d> x(n), v(n);
    ensure_built();
    backend_->read_state(cloth, x, v);
    return x;
}

std::vector<Vec3d> World::velocities(std::size_t cloth) const {
    const auto n = model_.cloths.at(cloth).fabric->vertex_count();
    std::vector<Vec3d> x(n), v(n);
    ensure_built();
    backend_->read_state(cloth, x, v);
    return v;
}

void World::set_state(std::size_t cloth, std::span<const Vec3d> positions, std::span<const Vec3d> velocities) {
    const auto n = model_.cloths.at(cloth).fabric->vertex_count();
    if (positions.size() != n || velocities.size() != n)
        throw Error("set_state: cloth " + std::to_string(cloth) + " has " + std::to_string(n) + " vertices, got " +
                    std::to_string(positions.size()) + " positions and " + std::to_string(velocities.size()) +
                    " velocities");
    ensure_built();
    backend_->write_state(cloth, positions, velocities);
}

double World::energy() const {
    double e = 0.0;
    for (std::size_t c = 0; c < model_.cloths.size(); ++c)
        e += cpu::cloth_energy(model_.cloths[c], model_.settings, positions(c), velocities(c)).total();
    return e;
}

}  // namespace weft
