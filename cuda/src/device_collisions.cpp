// Collision stages of a CUDA substep (see device_collisions.h and docs/collisions.md). Mirrors
// runtime/src/cpu/cpu_collisions.cpp: same collision index space, groups and inputs.
#include "device_collisions.h"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <string>

#include "collision/broad_phase.h"
#include "collision/impact_zones.h"
#include "collision/proximity_contacts.h"
#include "cuda_check.h"
#include "kernels.h"
#include "weft/error.h"

namespace weft::cuda {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

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

/// The CCD gate runs at a separation this much larger than the impact zones' eta, so that float
/// rounding cannot make it miss a pair the (double) zones would report: a gate without a hit means
/// the zones would find nothing to do.
constexpr double kGateMargin = 1.001;

}  // namespace

struct DeviceCollisions::Host {
    struct MeshCollider {
        std::size_t collider = 0;
        std::size_t first_vertex = 0;  // in the kinematic range
    };
    std::vector<MeshCollider> meshes;
    std::vector<Vec3d> kinematic_local;  // mesh collider vertices in their collider's frame
    std::vector<Triangle> triangles;     // cloth then kinematic, collision vertex ids
    std::vector<std::uint32_t> triangle_group;
    std::vector<weft::collision::Edge> edges;
    std::vector<double> inverse_mass;
    std::vector<Vec3d> kinematic_x0, kinematic_x1, x0, x1;
    weft::collision::ImpactZoneSolver zones;

    void place(const Model& model, double t, std::vector<Vec3d>& out) const {
        for (std::size_t m = 0; m < meshes.size(); ++m) {
            const Transform frame = model.colliders[meshes[m].collider].motion.at(t);
            const std::size_t last = m + 1 < meshes.size() ? meshes[m + 1].first_vertex : kinematic_local.size();
            for (std::size_t j = meshes[m].first_vertex; j < last; ++j) out[j] = frame.apply(kinematic_local[j]);
        }
    }
};

DeviceCollisions::DeviceCollisions() = default;
DeviceCollisions::~DeviceCollisions() = default;

void DeviceCollisions::release() {
    host_.reset();
    active_ = false;
    self_ = false;
    n_ = 0;
    kinematic_count_ = 0;
    vertices_ = 0;
    triangle_count_ = edge_count_ = 0;
    max_thickness_ = 0.0F;
    host_resolves_ = 0;
    ledger_.clear();
    positions_ = {};
    triangles_ = {};
    edges_ = {};
    triangle_group_ = {};
    inverse_mass_ = {};
    thickness_ = {};
    friction_ = {};
    kinematic_host_.allocate(0);
    download_ = {};
}

void DeviceCollisions::build(const FlatModel& flat, const Model& model) {
    release();
    if (!needs_cloth_collisions(model)) return;
    auto host = std::make_unique<Host>();
    self_ = model.settings.collision.self_collision;
    n_ = static_cast<std::uint32_t>(flat.vertex_count);
    const std::size_t cloths = model.cloths.size();
    std::size_t kinematic = 0;
    for (std::size_t k = 0; k < model.colliders.size(); ++k) {
        const ColliderDesc& c = model.colliders[k];
        if (c.is_analytic()) continue;
        if (!c.mesh) throw Error("collider '" + c.name + "' is a mesh collider without a mesh");
        host->meshes.push_back({k, kinematic});
        kinematic += c.mesh->positions.size();
    }
    // Triangles: the cloth's, then each mesh collider's shifted into the kinematic range; groups as on
    // the CPU (each cloth its own group with self-collision, one group without; each mesh its own).
    host->triangles = flat.triangles;
    host->triangle_group.resize(flat.triangle_count());
    for (std::size_t t = 0; t < flat.triangle_count(); ++t) host->triangle_group[t] = self_ ? flat.triangle_cloth[t] : 0;
    for (std::size_t m = 0; m < host->meshes.size(); ++m) {
        const MeshData& mesh = *model.colliders[host->meshes[m].collider].mesh;
        const auto base = static_cast<std::uint32_t>(n_ + host->meshes[m].first_vertex);
        for (const Triangle& tri : mesh.triangles) {
            host->triangles.push_back({{base + tri.v[0], base + tri.v[1], base + tri.v[2]}});
            host->triangle_group.push_back(static_cast<std::uint32_t>(cloths + m));
        }
        host->kinematic_local.insert(host->kinematic_local.end(), mesh.positions.begin(), mesh.positions.end());
    }
    host->edges = weft::collision::build_edges(host->triangles);
    kinematic_count_ = kinematic;
    const std::size_t total = n_ + kinematic;
    if (total > 0xffffffffu / 3) throw Error("CUDA backend: too many collision vertices (" + std::to_string(total) + ")");
    vertices_ = static_cast<std::uint32_t>(total);
    triangle_count_ = static_cast<std::uint32_t>(host->triangles.size());
    edge_count_ = static_cast<std::uint32_t>(host->edges.size());

    host->inverse_mass.assign(total, 0.0);
    std::vector<float> inverse_mass(total, 0.0F), thickness(total, 0.0F), friction(total, 0.0F);
    double max_thickness = 0.0;
    for (std::size_t i = 0; i < n_; ++i) {
        const bool pinned = flat.vertex_pin[i] >= 0;
        host->inverse_mass[i] = pinned || !(flat.mass[i] > 0.0) ? 0.0 : 1.0 / flat.mass[i];
        inverse_mass[i] = static_cast<float>(host->inverse_mass[i]);
        const Material& material = model.cloths[flat.vertex_cloth[i]].material;
        thickness[i] = static_cast<float>(material.contact_thickness);
        friction[i] = static_cast<float>(material.friction);
        max_thickness = std::max(max_thickness, material.contact_thickness);
    }
    for (const Host::MeshCollider& mc : host->meshes) {
        const ColliderDesc& c = model.colliders[mc.collider];
        for (std::size_t j = 0; j < c.mesh->positions.size(); ++j)
            friction[n_ + mc.first_vertex + j] = c.friction >= 0.0 ? static_cast<float>(c.friction) : 0.0F;
    }
    max_thickness_ = static_cast<float>(max_thickness);

    positions_.allocate(std::max<std::size_t>(1, 6 * total), ledger_, "collision positions");
    std::vector<std::uint32_t> ids(3 * host->triangles.size());
    for (std::size_t t = 0; t < host->triangles.size(); ++t)
        for (int a = 0; a < 3; ++a) ids[3 * t + static_cast<std::size_t>(a)] = host->triangles[t].v[a];
    triangles_.upload(ids, ledger_, "collision geometry");
    ids.resize(2 * host->edges.size());
    for (std::size_t e = 0; e < host->edges.size(); ++e) {
        ids[2 * e] = host->edges[e].v[0];
        ids[2 * e + 1] = host->edges[e].v[1];
    }
    edges_.upload(ids, ledger_, "collision geometry");
    triangle_group_.upload(host->triangle_group, ledger_, "collision geometry");
    inverse_mass_.upload(inverse_mass, ledger_, "collision vertex attributes");
    thickness_.upload(thickness, ledger_, "collision vertex attributes");
    friction_.upload(friction, ledger_, "collision vertex attributes");
    kinematic_host_.allocate(4 * 3 * kinematic);
    host->kinematic_x0.resize(kinematic);
    host->kinematic_x1.resize(kinematic);
    host_ = std::move(host);
    active_ = true;
}

std::size_t DeviceCollisions::detect(const Model& model, double t, double h, const float* x, const float* v,
                                     cudaStream_t stream, StepStats& stats) {
    if (!active_) return 0;
    auto clock = Clock::now();
    const CollisionSettings& settings = model.settings.collision;
    Host& host = *host_;
    const std::size_t nk = kinematic_count_;
    float* x0c = positions_.get();
    float* x1c = x0c + 3 * static_cast<std::size_t>(vertices_);
    launch_collision_predict(x, v, n_, static_cast<float>(h), x0c, x1c, vertices_, stream);
    if (nk > 0) {
        // Kinematic poses at t and t + h in double on the host (as the CPU), and the solve's copies:
        // pose at t + h and velocity. Four SoA blocks of 3·nk floats in pinned memory (the stream is
        // idle here: every substep ends with a synchronisation, so the buffer is free to rewrite).
        host.place(model, t, host.kinematic_x0);
        host.place(model, t + h, host.kinematic_x1);
        float* k = kinematic_host_.get();
        for (std::size_t j = 0; j < nk; ++j)
            for (int c = 0; c < 3; ++c) {
                const std::size_t cc = static_cast<std::size_t>(c);
                k[cc * nk + j] = static_cast<float>(host.kinematic_x0[j][c]);
                k[(3 + cc) * nk + j] = static_cast<float>(host.kinematic_x1[j][c]);
                k[(6 + cc) * nk + j] = static_cast<float>(host.kinematic_x1[j][c]);
                k[(9 + cc) * nk + j] = static_cast<float>((host.kinematic_x1[j][c] - host.kinematic_x0[j][c]) / h);
            }
        for (std::size_t c = 0; c < 3; ++c) {
            WEFT_CUDA_CHECK(cudaMemcpyAsync(x0c + c * vertices_ + n_, k + c * nk, nk * sizeof(float),
                                            cudaMemcpyHostToDevice, stream));
            WEFT_CUDA_CHECK(cudaMemcpyAsync(x1c + c * vertices_ + n_, k + (3 + c) * nk, nk * sizeof(float),
                                            cudaMemcpyHostToDevice, stream));
        }
    }

    const double thickness = settings.thickness > 0.0 ? settings.thickness : static_cast<double>(max_thickness_);
    collision::GpuBroadPhaseInput in;
    in.x0 = x0c;
    in.x1 = x1c;
    in.vertex_count = vertices_;
    in.triangles = triangles_.get();
    in.triangle_count = triangle_count_;
    in.edges = edges_.get();
    in.edge_count = edge_count_;
    in.triangle_cloth = triangle_group_.get();
    in.self_pairs = self_;
    in.thickness = thickness;
    // No normal-cone culling on the GPU yet: every overlapping pair is tested (same contacts).
    const collision::GpuBroadPhaseCounters& bc = broad_.find(in, stream);
    stats.collision.candidate_pairs += static_cast<std::int64_t>(bc.pairs);
    stats.ms(Stage::BroadPhase) += ms_since(clock);

    clock = Clock::now();
    collision::GpuProximityInput p;
    p.x0 = x0c;
    p.x1 = x1c;
    p.vertex_count = vertices_;
    p.inverse_mass = inverse_mass_.get();
    p.thickness = thickness_.get();
    p.friction = friction_.get();
    p.triangles = triangles_.get();
    p.edges = edges_.get();
    p.h = static_cast<float>(h);
    p.thickness_override = static_cast<float>(settings.thickness);
    p.stiffness_override = static_cast<float>(settings.stiffness);
    const collision::GpuProximityCounters& pc = proximity_.find(p, broad_.pairs(), stream);
    stats.collision.contacts = static_cast<int>(pc.contacts);
    stats.ms(Stage::NarrowPhase) += ms_since(clock);
    return pc.contacts;
}

void DeviceCollisions::publish(const ContactInputs& list, cudaStream_t stream, StepStats& stats) {
    if (!active_) return;
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
    if (nk > 0) {
        const float* k = kinematic_host_.get();
        for (std::size_t c = 0; c < 3; ++c) {
            WEFT_CUDA_CHECK(cudaMemcpyAsync(list.kinematic_x1 + c * list.kinematic_capacity, k + (6 + c) * nk,
                                            nk * sizeof(float), cudaMemcpyHostToDevice, stream));
            WEFT_CUDA_CHECK(cudaMemcpyAsync(list.kinematic_v + c * list.kinematic_capacity, k + (9 + c) * nk,
                                            nk * sizeof(float), cudaMemcpyHostToDevice, stream));
        }
    }
    stats.ms(Stage::NarrowPhase) += ms_since(clock);
}

bool DeviceCollisions::resolve(const Model& model, double h, float* x, float* v, cudaStream_t stream, StepStats& stats) {
    const CollisionSettings& settings = model.settings.collision;
    if (!active_ || !settings.continuous) return false;
    Host& host = *host_;
    float* x0c = positions_.get();
    float* x1c = x0c + 3 * static_cast<std::size_t>(vertices_);
    // x0c and the kinematic part of x1c still hold what `detect` placed there.
    auto clock = Clock::now();
    launch_collision_gather(x, n_, x1c, vertices_, stream);
    weft::collision::ImpactZoneInput zin;
    const double thickness = settings.thickness > 0.0 ? settings.thickness : static_cast<double>(max_thickness_);
    const double eta = zin.separation_ratio * thickness;
    collision::GpuBroadPhaseInput in;
    in.x0 = x0c;
    in.x1 = x1c;
    in.vertex_count = vertices_;
    in.triangles = triangles_.get();
    in.triangle_count = triangle_count_;
    in.edges = edges_.get();
    in.edge_count = edge_count_;
    in.triangle_cloth = triangle_group_.get();
    in.self_pairs = self_;
    in.thickness = kGateMargin * eta;  // as the zones' broad phase: bounds grown by eta
    const collision::GpuBroadPhaseCounters& bc = ccd_broad_.find(in, stream);
    stats.collision.candidate_pairs += static_cast<std::int64_t>(bc.pairs);
    stats.ms(Stage::BroadPhase) += ms_since(clock);

    clock = Clock::now();
    collision::GpuCcdInput cin;
    cin.x0 = x0c;
    cin.x1 = x1c;
    cin.vertex_count = vertices_;
    cin.inverse_mass = inverse_mass_.get();
    cin.triangles = triangles_.get();
    cin.edges = edges_.get();
    cin.eta = collision::float_at_least(kGateMargin * eta);
    cin.clamp_to_start_distance = true;
    const collision::GpuCcdCounters& cc = ccd_.find(cin, ccd_broad_.pairs(), stream);
    stats.collision.ccd_tests += cc.tests;
    stats.collision.ccd_hits += cc.hits;
    stats.ms(Stage::Ccd) += ms_since(clock);
    if (cc.hits == 0) return false;  // collision-free: nothing leaves the device

    // INTERIM (hybrid): the CPU impact zones (the reference) on the downloaded motion. GPU impact
    // zones come next; until then a substep with a CCD hit pays a round trip of its positions.
    ++host_resolves_;
    clock = Clock::now();
    const std::size_t nv = vertices_, n = n_;
    download_.resize(6 * nv + 3 * n);
    float* d0 = download_.data();
    float* d1 = d0 + 3 * nv;
    float* dv = d1 + 3 * nv;
    WEFT_CUDA_CHECK(cudaMemcpyAsync(d0, x0c, 6 * nv * sizeof(float), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaMemcpyAsync(dv, v, 3 * n * sizeof(float), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    host.x0.resize(nv);
    host.x1.resize(nv);
    for (std::size_t i = 0; i < nv; ++i) {
        host.x0[i] = Vec3d{d0[i], d0[nv + i], d0[2 * nv + i]};
        host.x1[i] = Vec3d{d1[i], d1[nv + i], d1[2 * nv + i]};
    }
    // The kinematic vertices exactly as the CPU places them (double), not their float copies.
    std::copy(host.kinematic_x0.begin(), host.kinematic_x0.end(), host.x0.begin() + static_cast<std::ptrdiff_t>(n));
    std::copy(host.kinematic_x1.begin(), host.kinematic_x1.end(), host.x1.begin() + static_cast<std::ptrdiff_t>(n));
    const double transfer_ms = ms_since(clock);

    zin.x0 = host.x0;
    zin.x1 = host.x1;
    zin.inverse_mass = host.inverse_mass;
    zin.triangles = host.triangles;
    zin.edges = host.edges;
    zin.triangle_cloth = host.triangle_group;
    zin.self_pairs = self_;
    zin.thickness = thickness;
    zin.max_iterations = settings.max_impact_iterations;
    // No culling (as the GPU broad phase): the refresh hook is left empty.
    const weft::collision::ImpactZoneReport r = host.zones.resolve(zin);
    CollisionStats& c = stats.collision;
    c.candidate_pairs += r.candidate_pairs;
    c.ccd_tests += r.ccd_tests;
    c.ccd_hits += r.ccd_hits;
    c.impact_zones += r.zones;
    c.impact_iterations = std::max(c.impact_iterations, r.iterations);
    c.rigid_zones += r.rigid_zones;
    c.frozen_vertices += r.frozen_vertices;
    if (!r.resolved) ++c.unresolved_substeps;
    stats.ms(Stage::BroadPhase) += r.broad_phase_ms;
    stats.ms(Stage::Ccd) += r.ccd_ms;
    stats.ms(Stage::ImpactZones) += r.zones_ms;

    // Vertices the zones moved take the velocity of their corrected motion (float, as CpuCollisions).
    clock = Clock::now();
    const auto inv_h = static_cast<float>(1.0 / h);
    bool moved = false;
    for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const auto kk = static_cast<std::size_t>(k);
            const auto corrected = static_cast<float>(host.x1[i][k]);
            if (corrected == d1[kk * nv + i]) continue;
            moved = true;
            break;
        }
    if (moved) {
        // Rewrite x (cloth part of d1, compacted to stride n) and v of the moved vertices.
        std::vector<float> xs(3 * n);
        for (std::size_t i = 0; i < n; ++i) {
            bool changed = false;
            float corrected[3];
            for (std::size_t k = 0; k < 3; ++k) {
                corrected[k] = static_cast<float>(host.x1[i][static_cast<int>(k)]);
                changed = changed || corrected[k] != d1[k * nv + i];
            }
            for (std::size_t k = 0; k < 3; ++k) {
                xs[k * n + i] = changed ? corrected[k] : d1[k * nv + i];
                if (changed) dv[k * n + i] = (corrected[k] - d0[k * nv + i]) * inv_h;
            }
        }
        WEFT_CUDA_CHECK(cudaMemcpyAsync(x, xs.data(), 3 * n * sizeof(float), cudaMemcpyHostToDevice, stream));
        WEFT_CUDA_CHECK(cudaMemcpyAsync(v, dv, 3 * n * sizeof(float), cudaMemcpyHostToDevice, stream));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    }
    stats.ms(Stage::ImpactZones) += transfer_ms + ms_since(clock);
    return moved;
}

std::size_t DeviceCollisions::memory_bytes() const {
    if (!active_) return 0;
    return ledger_.total() + broad_.memory_bytes() + ccd_broad_.memory_bytes() + proximity_.memory_bytes() +
           ccd_.memory_bytes();
}

}  // namespace weft::cuda
