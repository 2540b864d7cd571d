// Collision stages of a CUDA substep (see device_collisions.h and docs/collisions.md). Mirrors
// runtime/src/cpu/cpu_collisions.cpp: same collision index space, groups and inputs.
#include "device_collisions.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstddef>
#include <string>

#include "weft/backend/impact_zone_report.h"
#include "weft/backend/patch_hierarchy.h"
#include "cuda_check.h"
#include "kernels.h"
#include "weft/backend/timing.h"
#include "weft/error.h"

namespace weft::cuda {
namespace {

using Clock = std::chrono::steady_clock;

// The GPU narrow phase writes the solver's contact list as is: same layout, field for field.
using collision::GpuProximityContact;
static_assert(sizeof(GpuProximityContact) == sizeof(DeviceContact));
static_assert(offsetof(GpuProximityContact, vertex) == offsetof(DeviceContact, vertex));
static_assert(offsetof(GpuProximityContact, weight) == offsetof(DeviceContact, weight));
static_assert(offsetof(GpuProximityContact, normal) == offsetof(DeviceContact, normal));
static_assert(offsetof(GpuProximityContact, gap) == offsetof(DeviceContact, gap));
static_assert(offsetof(GpuProximityContact, thickness) == offsetof(DeviceContact, thickness));
static_assert(offsetof(GpuProximityContact, stiffness) == offsetof(DeviceContact, stiffness));
static_assert(offsetof(GpuProximityContact, friction) == offsetof(DeviceContact, friction));
static_assert(offsetof(GpuProximityContact, pair) == offsetof(DeviceContact, pair));
// launch_collision_scatter reads the outcome codes as numbers.
static_assert(static_cast<int>(weft::collision::VertexOutcome::Fixed) == 0);
static_assert(static_cast<int>(weft::collision::VertexOutcome::Untouched) == 1);

}  // namespace

// WEFT_CUDA_ZONES_TRACE=1: one line per substep in which the impact zones ran (diagnostics).
// WEFT_CUDA_ZONE_PROJECTION=colored: every zone that fits projected by colours (projected
// Gauss–Seidel) instead of the projected gradient; WEFT_CUDA_ZONE_COLORED_ABOVE=N: by colours only
// zones of more than N constraints. For measuring one against the other (docs/collisions.md).
DeviceCollisions::DeviceCollisions() {
    const char* trace = std::getenv("WEFT_CUDA_ZONES_TRACE");
    trace_zones_ = trace != nullptr && std::string(trace) == "1";
    const char* projection = std::getenv("WEFT_CUDA_ZONE_PROJECTION");
    colored_zones_ = projection != nullptr && std::string(projection) == "colored";
    if (const char* above = std::getenv("WEFT_CUDA_ZONE_COLORED_ABOVE")) colored_above_ = std::strtoul(above, nullptr, 10);
}
DeviceCollisions::~DeviceCollisions() = default;

void DeviceCollisions::release() {
    geometry_ = {};
    active_ = false;
    n_ = 0;
    kinematic_count_ = 0;
    vertices_ = 0;
    triangle_count_ = edge_count_ = 0;
    ledger_.clear();
    positions_ = {};
    triangles_ = {};
    edges_ = {};
    triangle_group_ = {};
    inverse_mass_ = {};
    thickness_ = {};
    friction_ = {};
    rest_ = {};
    vertex_cloth_ = {};
    kinematics_.release();
    cones_.release();
}

void DeviceCollisions::build(const FlatModel& flat, const Model& model) {
    release();
    if (!needs_cloth_collisions(model)) return;
    geometry_ = weft::collision::build_collision_geometry(flat, model);
    const weft::collision::CollisionGeometry& g = geometry_;
    n_ = static_cast<std::uint32_t>(g.cloth_vertices);
    kinematic_count_ = g.kinematic_vertices();
    const std::size_t total = g.vertex_count();
    if (total > 0xffffffffu / 3) throw Error("CUDA backend: too many collision vertices (" + std::to_string(total) + ")");
    vertices_ = static_cast<std::uint32_t>(total);
    triangle_count_ = static_cast<std::uint32_t>(g.triangles.size());
    edge_count_ = static_cast<std::uint32_t>(g.edges.size());

    const auto to_float = [](const std::vector<double>& d) { return std::vector<float>(d.begin(), d.end()); };
    positions_.allocate(std::max<std::size_t>(1, 6 * total), ledger_, "collision positions");
    std::vector<std::uint32_t> ids(3 * g.triangles.size());
    for (std::size_t t = 0; t < g.triangles.size(); ++t)
        for (int a = 0; a < 3; ++a) ids[3 * t + static_cast<std::size_t>(a)] = g.triangles[t].v[a];
    triangles_.upload(ids, ledger_, "collision geometry");
    ids.resize(2 * g.edges.size());
    for (std::size_t e = 0; e < g.edges.size(); ++e) {
        ids[2 * e] = g.edges[e].v[0];
        ids[2 * e + 1] = g.edges[e].v[1];
    }
    edges_.upload(ids, ledger_, "collision geometry");
    triangle_group_.upload(g.triangle_group, ledger_, "collision geometry");
    inverse_mass_.upload(to_float(g.inverse_mass), ledger_, "collision vertex attributes");
    thickness_.upload(to_float(g.thickness), ledger_, "collision vertex attributes");
    friction_.upload(to_float(g.friction), ledger_, "collision vertex attributes");
    kinematics_.build(model, g, ledger_);
    if (g.self && n_ > 0) {
        // Rest exclusion (CollisionSettings::rest_exclusion) only concerns pairs inside one cloth.
        std::vector<float> rest(3 * static_cast<std::size_t>(n_));
        for (std::size_t i = 0; i < n_; ++i)
            for (int c = 0; c < 3; ++c) rest[static_cast<std::size_t>(c) * n_ + i] = static_cast<float>(g.rest[i][c]);
        rest_.upload(rest, ledger_, "collision rest shape");
        vertex_cloth_.upload(g.vertex_cloth, ledger_, "collision rest shape");
    }
    if (g.self) {
        // The hierarchy as the CPU builds it (cpu_collisions.cpp), so that patch ids are node ids of
        // the same tree; only the cloth's primitives get ids on the GPU (colliders never need them).
        std::vector<Vec3d> rest(flat.initial_positions);
        rest.insert(rest.end(), g.kinematic_local.begin(), g.kinematic_local.end());
        const weft::collision::PatchHierarchy hierarchy =
            weft::collision::build_patch_hierarchy(rest, g.triangles, g.edges, g.triangle_group);
        std::uint32_t cloth_edges = 0;  // build_edges sorts by first vertex: the cloth's edges come first
        while (cloth_edges < edge_count_ && g.edges[cloth_edges].v[0] < n_) ++cloth_edges;
        collision::GpuNormalConeLayout layout;
        layout.vertex_count = vertices_;
        layout.edge_count = edge_count_;
        layout.triangle_count = triangle_count_;
        layout.cloth_vertices = n_;
        layout.cloth_edges = cloth_edges;
        layout.cloth_triangles = static_cast<std::uint32_t>(flat.triangle_count());
        cones_.build(hierarchy, layout);
    }
    free_vertices_ = 0;
    for (std::size_t i = 0; i < n_; ++i) free_vertices_ += g.inverse_mass[i] > 0.0 ? 1 : 0;
    active_ = true;
}

void DeviceCollisions::cull(const Model& model, collision::GpuBroadPhaseInput& in, cudaStream_t stream) {
    if (!cones_.built() || model.settings.collision.culling != CollisionCulling::NormalCone) return;
    cones_.enqueue(in.x0, in.x1, vertices_, stream);
    in.vertex_patch = cones_.vertex_patch();
    in.edge_patch = cones_.edge_patch();
    in.triangle_patch = cones_.triangle_patch();
}

collision::GpuBroadPhaseInput DeviceCollisions::broad_phase_input(double thickness) const {
    collision::GpuBroadPhaseInput in;
    in.x0 = positions_.get();
    in.x1 = positions_.get() + 3 * static_cast<std::size_t>(vertices_);
    in.vertex_count = vertices_;
    in.triangles = triangles_.get();
    in.triangle_count = triangle_count_;
    in.edges = edges_.get();
    in.edge_count = edge_count_;
    in.triangle_cloth = triangle_group_.get();
    in.self_pairs = geometry_.self;
    in.thickness = thickness;
    return in;
}

collision::GpuProximityInput DeviceCollisions::proximity_input(const CollisionSettings& settings, const float* x0,
                                                             const float* x1, double h) const {
    collision::GpuProximityInput p;
    p.x0 = x0;
    p.x1 = x1;
    p.vertex_count = vertices_;
    p.inverse_mass = inverse_mass_.get();
    p.thickness = thickness_.get();
    p.friction = friction_.get();
    p.triangles = triangles_.get();
    p.edges = edges_.get();
    p.rest = rest_.get();
    p.vertex_cloth = vertex_cloth_.get();
    p.rest_count = rest_.get() != nullptr ? n_ : 0U;
    p.rest_exclusion = static_cast<float>(settings.rest_exclusion);
    p.h = static_cast<float>(h);
    p.thickness_override = static_cast<float>(settings.thickness);
    p.stiffness_override = static_cast<float>(settings.stiffness);
    return p;
}

std::size_t DeviceCollisions::detect(const Model& model, double t, double h, const float* x, const float* v,
                                     const float* dv_previous, cudaStream_t stream, StepStats& stats) {
    if (!active_) return 0;
    auto clock = Clock::now();
    const CollisionSettings& settings = model.settings.collision;
    const std::size_t nk = kinematic_count_;
    float* x0c = positions_.get();
    float* x1c = x0c + 3 * static_cast<std::size_t>(vertices_);
    launch_collision_predict(x, v, n_, static_cast<float>(h), x0c, x1c, vertices_, stream);
    // The mesh colliders at t and t + h, skinned and placed on the device (device_kinematics.h).
    kinematics_.place(model, t, h, x0c, x1c, vertices_, n_, stream);
    // A mesh collider that does not start this substep where it ended the last one was moved by
    // something no substep's motion covers: counted, not fixed (as on the CPU, cpu_collisions.cpp).
    if (const double jump = kinematics_.jump(); jump > 0.1 * geometry_.gap(settings)) {
        ++stats.collision.collider_jumps;
        stats.collision.collider_jump_max = std::max(stats.collision.collider_jump_max, jump);
    }

    offset_ = settings.mode == CollisionMode::Offset;
    if (offset_) {
        fallback_ = false;
        redetections_ = 0;
        if (detect_positions_.size() < 3 * static_cast<std::size_t>(vertices_)) {
            detect_positions_.allocate(3 * static_cast<std::size_t>(vertices_), ledger_, "offset: detection positions");
            radius_.allocate(vertices_, ledger_, "offset: query radii");
            remainder_.allocate(std::max<std::uint32_t>(n_, 1), ledger_, "offset: truncation remainders");
            offset_sums_.allocate(4, ledger_, "offset: frame");
            offset_partials_.allocate(4 * kOffsetMomentumBlocks, ledger_, "offset: frame");
            offset_shift_.allocate(3, ledger_, "offset: frame");
            offset_largest_.allocate(1, ledger_, "offset: frame");
            offset_host_.allocate(4);
        }
        // The frame the moves are bounded in translates with the cloth's mean velocity (mass-weighted
        // over the free vertices), as on the CPU.
        launch_offset_momentum(v, inverse_mass_.get(), n_, offset_sums_.get(), offset_partials_.get(), stream);
        WEFT_CUDA_CHECK(cudaMemcpyAsync(offset_host_.get(), offset_sums_.get(), 4 * sizeof(double), cudaMemcpyDeviceToHost, stream));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
        const double* sums = offset_host_.get();
        float host_shift[3] = {0.0F, 0.0F, 0.0F};
        if (sums[3] > 0.0)
            for (int c = 0; c < 3; ++c) host_shift[c] = static_cast<float>(h * sums[c] / sums[3]);
        // On the detection's stream, which the kernels below follow (a blocking cudaMemcpy would go
        // through the default stream, which this non-blocking stream does not wait for); host_shift
        // is on the stack, so the copy is waited for.
        WEFT_CUDA_CHECK(cudaMemcpyAsync(offset_shift_.get(), host_shift, sizeof(host_shift), cudaMemcpyHostToDevice, stream));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
        const float contact = static_cast<float>(geometry_.gap(settings));
        launch_offset_radius(x0c, x1c, nullptr, dv_previous, static_cast<float>(h), n_, vertices_, offset_shift_.get(),
                             static_cast<float>(settings.relaxation),
                             contact, static_cast<float>(settings.max_query_radius) * contact, radius_.get(),
                             offset_largest_.get(), stream);
        WEFT_CUDA_CHECK(cudaMemcpyAsync(detect_positions_.get(), x0c, 3 * static_cast<std::size_t>(vertices_) * sizeof(float),
                                        cudaMemcpyDeviceToDevice, stream));
        stats.ms(Stage::BroadPhase) += ms_since(clock);
        const std::size_t found = detect_offset(model, h, stream, stats);
        if (nk > 0) {
            // Mesh colliders move as prescribed: their whole move is checked against their bounds.
            collision::GpuTruncateInput k;
            k.x_detect = detect_positions_.get();
            k.x0 = x1c + n_;
            k.first = n_;
            k.vertex_count = static_cast<std::uint32_t>(nk);
            k.stride = vertices_;
            k.detect_stride = vertices_;
            k.shift_device = offset_shift_.get();
            k.planar = settings.bound_shape == BoundShape::Planar;
            bounds_.truncate(k, stream, true, reduce_);
            fallback_ = bounds_.read_back(stream).broken > 0;
        }
        return found;
    }

    const double thickness = geometry_.gap(settings);
    collision::GpuBroadPhaseInput in = broad_phase_input(thickness);
    in.share_index = share_index_;
    in.share_count = share_count_;
    stats.ms(Stage::BroadPhase) += ms_since(clock);
    clock = Clock::now();
    if (settings.cull_contacts) cull(model, in, stream);  // CollisionSettings::cull_contacts says why
    if (in.triangle_patch != nullptr) WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));  // its own stage time
    stats.ms(Stage::Culling) += ms_since(clock);
    clock = Clock::now();
    const collision::GpuBroadPhaseCounters& bc = broad_.find(in, stream);
    stats.collision.candidate_pairs += static_cast<std::int64_t>(bc.pairs);
    stats.ms(Stage::BroadPhase) += ms_since(clock);

    clock = Clock::now();
    const collision::GpuProximityInput p = proximity_input(settings, x0c, x1c, h);
    const collision::GpuProximityCounters& pc = proximity_.find(p, broad_.pairs(), stream);
    stats.collision.contacts = static_cast<int>(pc.contacts);
    stats.ms(Stage::NarrowPhase) += ms_since(clock);
    return pc.contacts;
}

std::size_t DeviceCollisions::detect_offset(const Model& model, double h, cudaStream_t stream, StepStats& stats) {
    auto clock = Clock::now();
    const CollisionSettings& settings = model.settings.collision;
    collision::GpuBoundsInput b;
    b.x = detect_positions_.get();
    b.vertex_count = vertices_;
    b.stride = vertices_;
    b.triangles = triangles_.get();
    b.triangle_count = triangle_count_;
    b.edges = edges_.get();
    b.edge_count = edge_count_;
    b.self_pairs = geometry_.self;
    b.triangle_cloth = triangle_group_.get();
    b.radius = radius_.get();
    b.relaxation = static_cast<float>(settings.relaxation);
    b.share_index = share_index_;
    b.share_count = share_count_;
    bounds_.compute(b, broad_, stream, reduce_);
    const collision::GpuBoundsCounters& c = bounds_.read_back(stream);
    stats.collision.candidate_pairs += static_cast<std::int64_t>(c.measured_vf + c.measured_ee);
    std::uint32_t largest = 0;
    WEFT_CUDA_CHECK(cudaMemcpyAsync(&largest, offset_largest_.get(), sizeof(largest), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    stats.collision.query_radius_max = std::max(stats.collision.query_radius_max, static_cast<double>(std::bit_cast<float>(largest)));
    stats.ms(Stage::BroadPhase) += ms_since(clock);

    clock = Clock::now();
    collision::GpuProximityInput p = proximity_input(settings, detect_positions_.get(), detect_positions_.get(), h);
    p.offset_bound = bounds_.bound();
    const collision::GpuProximityCounters& pc = proximity_.find(p, bounds_.pairs(), stream);
    stats.collision.contacts = static_cast<int>(pc.contacts);
    stats.ms(Stage::NarrowPhase) += ms_since(clock);
    return pc.contacts;
}

collision::GpuTruncateInput DeviceCollisions::cloth_truncation(const Model& model, const float* x0, float* vk, float* wk,
                                                               const std::uint8_t* fixed, const float* h_device) const {
    collision::GpuTruncateInput t;
    t.x_detect = detect_positions_.get();
    t.x0 = x0;
    t.v = vk;
    t.v_copy = wk;
    t.remainder = remainder_.get();
    t.vertex_count = n_;
    t.stride = n_;
    t.detect_stride = vertices_;
    t.prescribed = fixed;
    t.h_device = h_device;
    t.shift_device = offset_shift_.get();
    t.planar = model.settings.collision.bound_shape == BoundShape::Planar;
    return t;
}

void DeviceCollisions::enqueue_truncation(const Model& model, const float* x0, float* vk, float* wk,
                                          const std::uint8_t* fixed, const float* h_device, cudaStream_t stream) {
    bounds_.truncate(cloth_truncation(model, x0, vk, wk, fixed, h_device), stream);
}

void DeviceCollisions::enqueue_share_limits(const Model& model, const float* x0, const float* vk, const float* h_device,
                                            cudaStream_t stream) {
    bounds_.limit_shares(cloth_truncation(model, x0, const_cast<float*>(vk), nullptr, nullptr, h_device), stream);
}

void DeviceCollisions::enqueue_reduced_truncation(const Model& model, std::span<const std::uint32_t* const> shares,
                                                  const float* x0, float* vk, const std::uint8_t* fixed,
                                                  const float* h_device, cudaStream_t stream) {
    const std::uint32_t* reduced = bounds_.reduce_across(shares, vertices_, stream);
    bounds_.apply_shares(cloth_truncation(model, x0, vk, nullptr, fixed, h_device), reduced, stream);
}

bool DeviceCollisions::finish_truncation(const Model& model, cudaStream_t stream, StepStats& stats) {
    const collision::GpuBoundsCounters& c = bounds_.read_back(stream);
    stats.collision.truncated_vertices += c.truncated;
    if (c.broken > 0) fallback_ = true;
    const CollisionSettings& settings = model.settings.collision;
    return redetections_ < settings.max_redetections &&
           static_cast<double>(c.truncated) > settings.redetect_share * static_cast<double>(free_vertices_);
}

std::size_t DeviceCollisions::redetect(const Model& model, double h, const float* x0, const float* vk,
                                       const float* h_device, cudaStream_t stream, StepStats& stats) {
    const CollisionSettings& settings = model.settings.collision;
    float* x1c = positions_.get() + 3 * static_cast<std::size_t>(vertices_);
    // From here the colliders stand at t + h and the cloth where the truncation left it; each radius
    // covers 1.5× what the truncation cut from the vertex's last move; no frame shift.
    launch_offset_detect_positions(x0, vk, n_, h_device, x1c, vertices_, detect_positions_.get(), stream);
    WEFT_CUDA_CHECK(cudaMemsetAsync(offset_shift_.get(), 0, 3 * sizeof(float), stream));
    const float contact = static_cast<float>(geometry_.gap(settings));
    launch_offset_radius(nullptr, nullptr, remainder_.get(), nullptr, 0.0F, n_, vertices_, offset_shift_.get(),
                         static_cast<float>(settings.relaxation), contact,
                         static_cast<float>(settings.max_query_radius) * contact, radius_.get(), offset_largest_.get(),
                         stream);
    ++redetections_;
    ++stats.collision.redetections;
    return detect_offset(model, h, stream, stats);
}

const DeviceContact* DeviceCollisions::contacts() const {
    return reinterpret_cast<const DeviceContact*>(proximity_.contacts());  // the same layout (asserted above)
}

void DeviceCollisions::publish(const ContactInputs& list, cudaStream_t stream, StepStats& stats) {
    if (!active_) return;
    count_buffer_growths(stats);
    const auto clock = Clock::now();
    const std::size_t count = proximity_.counters().contacts;
    if (count > list.capacity || kinematic_count_ > list.kinematic_capacity || list.count == nullptr)
        throw Error("CUDA backend: the contact list holds " + std::to_string(list.capacity) + " contacts, " +
                    std::to_string(count) + " found (internal: reserve before publish)");
    WEFT_CUDA_CHECK(cudaMemcpyAsync(list.count, proximity_.device_count(), sizeof(std::uint32_t),
                                    cudaMemcpyDeviceToDevice, stream));
    if (count > 0)
        WEFT_CUDA_CHECK(cudaMemcpyAsync(list.list, proximity_.contacts(), count * sizeof(DeviceContact),
                                        cudaMemcpyDeviceToDevice, stream));
    const std::size_t nk = kinematic_count_;
    for (std::size_t c = 0; c < 3 && nk > 0; ++c) {
        WEFT_CUDA_CHECK(cudaMemcpyAsync(list.kinematic_x1 + c * list.kinematic_capacity, kinematics_.end_positions() + c * nk,
                                        nk * sizeof(float), cudaMemcpyDeviceToDevice, stream));
        WEFT_CUDA_CHECK(cudaMemcpyAsync(list.kinematic_v + c * list.kinematic_capacity, kinematics_.velocities() + c * nk,
                                        nk * sizeof(float), cudaMemcpyDeviceToDevice, stream));
    }
    stats.ms(Stage::NarrowPhase) += ms_since(clock);
}

bool DeviceCollisions::resolve(const Model& model, double h, float* x, float* v, const float* v0, float* dv_previous,
                               bool moved_after_solve, cudaStream_t stream, StepStats& stats) {
    const CollisionSettings& settings = model.settings.collision;
    if (!active_) return false;
    if (offset_) {
        if (!fallback_ && !moved_after_solve) return false;
        ++stats.collision.bound_fallbacks;
    }
    if (!settings.continuous) return false;
    float* x0c = positions_.get();
    float* x1c = x0c + 3 * static_cast<std::size_t>(vertices_);
    // x0c and the kinematic part of x1c still hold what `detect` placed there.
    launch_collision_gather(x, n_, x1c, vertices_, stream);
    const collision::GpuBroadPhaseInput broad = broad_phase_input(0.0);
    collision::GpuImpactZoneInput in;
    in.x0 = x0c;
    in.x1 = x1c;
    in.vertex_count = vertices_;
    in.inverse_mass = inverse_mass_.get();
    in.triangles = broad.triangles;
    in.triangle_count = broad.triangle_count;
    in.edges = broad.edges;
    in.edge_count = broad.edge_count;
    in.triangle_group = broad.triangle_cloth;
    in.self_pairs = broad.self_pairs;
    in.thickness = geometry_.gap(settings);
    in.max_iterations = settings.max_impact_iterations;
    in.refresh_broad_phase = [&](int, collision::GpuBroadPhaseInput& bp) { cull(model, bp, stream); };
    if (settings.impact_tolerance > 0.0) in.tolerance_ratio = settings.impact_tolerance;
    in.ccd_time_tolerance = settings.ccd_time_tolerance;
    if (settings.max_impact_sweeps > 0) in.max_sweeps = settings.max_impact_sweeps;
    if (settings.max_impact_work >= 1.0) in.max_work = static_cast<std::int64_t>(settings.max_impact_work);
    if (colored_zones_ || colored_above_ >= 0) in.colored_zone_vertices = collision::kColoredZoneVertices;
    if (colored_above_ >= 0) in.colored_zone_constraints = static_cast<std::uint32_t>(colored_above_);
    const weft::collision::ImpactZoneReport report = zones_.resolve(in, stream);
    weft::collision::add_to_stats(report, stats);
    count_buffer_growths(stats);
    if (report.constraints == 0) return false;  // the gate found nothing: x and v stand
    if (trace_zones_)
        std::fprintf(stderr,
                     "weft: impact zones: contacts %d, rounds %d, detections %d, constraints %d, zones %d (max %d "
                     "vertices), sweeps %lld (%d unconverged), rigid %d, frozen %d, carried %d, resolved %d; broad "
                     "%.2f ms, CCD %.2f ms, zones %.2f ms\n",
                     stats.collision.contacts, report.iterations, report.detections, report.constraints, report.zones,
                     report.max_zone_vertices, static_cast<long long>(report.qp_sweeps), report.qp_unconverged,
                     report.rigid_zones, report.frozen_vertices, report.carried_vertices, report.resolved ? 1 : 0,
                     report.broad_phase_ms, report.ccd_ms, report.zones_ms);
    const auto clock = Clock::now();
    launch_collision_scatter(x1c, x0c, zones_.outcome(), n_, vertices_, static_cast<float>(1.0 / h), x, v, v0,
                             dv_previous, stream);
    stats.ms(Stage::ImpactZones) += ms_since(clock);
    return true;
}

void DeviceCollisions::count_buffer_growths(StepStats& stats) {
    const int total = broad_.reruns() + proximity_.reruns() + zones_.buffer_growths();
    stats.collision.buffer_growths += total - growths_counted_;
    growths_counted_ = total;
}

std::size_t DeviceCollisions::memory_bytes() const {
    if (!active_) return 0;
    return ledger_.total() + broad_.memory_bytes() + proximity_.memory_bytes() + zones_.memory_bytes() +
           cones_.memory_bytes() + bounds_.memory_bytes();
}

std::vector<std::pair<std::string, std::size_t>> DeviceCollisions::memory_breakdown() const {
    std::vector<std::pair<std::string, std::size_t>> parts;
    if (!active_) return parts;
    for (const auto& [what, bytes] : ledger_.entries()) parts.emplace_back("collisions: " + what, bytes);
    const std::size_t pairs = broad_.pair_memory_bytes();
    parts.emplace_back("collisions: broad phase pairs", pairs);
    parts.emplace_back("collisions: broad phase hash", broad_.memory_bytes() - pairs);
    parts.emplace_back("collisions: proximity contacts", proximity_.memory_bytes());
    parts.emplace_back("collisions: impact zones and CCD", zones_.memory_bytes());
    parts.emplace_back("collisions: normal cones", cones_.memory_bytes());
    parts.emplace_back("collisions: offset bounds", bounds_.memory_bytes());
    return parts;
}

}  // namespace weft::cuda
