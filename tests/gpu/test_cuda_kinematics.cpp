// Mesh colliders placed on the device (cuda/src/device_kinematics.h): linear blend skinning of a
// character playing a clip, and the one-map placement of a rigid mesh, against the host's double
// placement (weft::collider_mesh_positions) at t and t + h, with the substep's velocities; and, with
// weft::assets, the shipped runner scene stepped on the cuda backend: the cape's pins follow the
// skin, and the exact check after every frame finds no intersection. A mesh collider that jumps
// between substeps is reported as on the CPU.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "collider_jump.h"
#include "device_kinematics.h"
#include "weft/backend/collision_geometry.h"
#include "weft/backend/model.h"
#include "weft/collider.h"
#include "weft/mesh.h"
#include "weft/scene.h"
#include "weft/skinning.h"
#if WEFT_TEST_HAVE_ASSETS
#include "weft/assets/assimp_loader.h"
#endif

#include "gpu_test_util.h"

namespace weft {
namespace {

Quatd about_z(double radians) { return {std::cos(radians / 2), 0.0, 0.0, std::sin(radians / 2)}; }

/// A strip 2 m long along +X of 2 × 9 vertices, joint 0 at the origin and joint 1 (its child) at
/// x = 1: vertices left of x = 0.75 follow joint 0, right of 1.25 joint 1, between them a blend. The
/// clip "bend" lifts the root and turns the elbow about z by up to 90°.
std::shared_ptr<const SkinnedMesh> strip() {
    auto m = std::make_shared<SkinnedMesh>();
    m->mesh.source = "strip";
    for (int i = 0; i < 9; ++i)
        for (int k = 0; k < 2; ++k) {
            const double x = 0.25 * i;
            m->mesh.positions.push_back({x, 0.0, 0.1 * k});
            const double w1 = std::clamp((x - 0.75) / 0.5, 0.0, 1.0);
            m->vertex_joints.push_back({0, 1, 0, 0});
            m->vertex_weights.push_back({1.0 - w1, w1, 0.0, 0.0});
        }
    for (std::uint32_t i = 0; i + 1 < 9; ++i)
        m->mesh.triangles.push_back({{2 * i, 2 * i + 2, 2 * i + 1}}), m->mesh.triangles.push_back({{2 * i + 1, 2 * i + 2, 2 * i + 3}});
    Joint root{.name = "root"};
    Joint elbow{.name = "elbow", .parent = 0};
    elbow.rest.translation = {1, 0, 0};
    elbow.inverse_bind.translation = {-1, 0, 0};
    m->joints = {root, elbow};
    AnimationClip bend{.name = "bend", .duration = 1.0};
    bend.tracks.push_back({.joint = 1, .rotation_times = {0.0, 0.5, 1.0},
                           .rotations = {about_z(0.0), about_z(1.5707963), about_z(0.3)}});
    bend.tracks.push_back({.joint = 0, .translation_times = {0.0, 1.0}, .translations = {{0, 0, 0}, {0, 0.4, 0}}});
    m->clips.push_back(bend);
    validate(*m);
    return m;
}

/// A unit cube's corners and two triangles (the placement does not look at the triangles).
std::shared_ptr<const MeshData> cube() {
    auto m = std::make_shared<MeshData>();
    m->source = "cube";
    for (int k = 0; k < 8; ++k) m->positions.push_back({(k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5});
    m->triangles = {{{0, 1, 3}}, {{4, 5, 7}}};
    return m;
}

TEST(CudaKinematics, SkinningOnTheDeviceEqualsTheHosts) {
    WEFT_REQUIRE_GPU();
    Model model;
    ColliderDesc character{.name = "character", .shape = ColliderShape::Mesh};
    character.skin = strip();
    character.mesh = std::make_shared<const MeshData>(character.skin->mesh);
    character.clip = "bend";
    character.clip_speed = 0.8;
    character.motion.origin = {3.0, 1.0, -2.0};  // root motion: running and turning
    character.motion.linear_velocity = {2.0, 0.0, 1.0};
    character.motion.angular_velocity = {0.0, 1.5, 0.0};
    ColliderDesc spinning{.name = "spinning", .shape = ColliderShape::Mesh, .mesh = cube()};
    spinning.motion.origin = {-1.0, 0.5, 0.0};
    spinning.motion.angular_velocity = {0.3, 0.0, 2.0};
    spinning.motion.amplitude = {0.0, 0.2, 0.0};
    spinning.motion.frequency = 1.0;
    ColliderDesc still{.name = "still", .shape = ColliderShape::Mesh, .mesh = cube()};
    still.motion.origin = {0.0, 0.0, 4.0};
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};  // analytic: not placed here
    model.colliders = {character, ball, spinning, still};

    // The collision index space of three mesh colliders and no cloth vertex before them.
    collision::CollisionGeometry g;
    std::uint32_t first = 0;
    for (std::size_t k : {std::size_t{0}, std::size_t{2}, std::size_t{3}}) {
        g.meshes.push_back({k, first});
        const MeshData& m = *model.colliders[k].mesh;
        g.kinematic_local.insert(g.kinematic_local.end(), m.positions.begin(), m.positions.end());
        first += static_cast<std::uint32_t>(m.positions.size());
    }
    const std::size_t nk = g.kinematic_local.size();
    cuda::MemoryLedger ledger;
    cuda::DeviceKinematics kinematics;
    kinematics.build(model, g, ledger);
    ASSERT_EQ(kinematics.count(), nk);
    EXPECT_EQ(kinematics.map_count(), 2U + 1U + 1U) << "two joints, then one map a rigid mesh";

    // Collision-space arrays with 5 cloth vertices before the kinematic ones.
    const std::uint32_t cloth = 5, stride = cloth + static_cast<std::uint32_t>(nk);
    cuda::DeviceArray<float> x0c, x1c;
    x0c.allocate(3 * stride, ledger, "test");
    x1c.allocate(3 * stride, ledger, "test");
    test::Stream stream;
    const double h = 1.0 / 240.0;
    double worst_x = 0.0, worst_v = 0.0, fastest = 0.0;
    for (const double t : {0.0, 0.37, 0.62, 1.4}) {
        kinematics.place(model, t, h, x0c.get(), x1c.get(), stride, cloth, stream.s);
        std::vector<float> a(3 * stride), b(3 * stride), end(3 * nk), v(3 * nk);
        WEFT_CUDA_CHECK(cudaMemcpyAsync(a.data(), x0c.get(), a.size() * sizeof(float), cudaMemcpyDeviceToHost, stream.s));
        WEFT_CUDA_CHECK(cudaMemcpyAsync(b.data(), x1c.get(), b.size() * sizeof(float), cudaMemcpyDeviceToHost, stream.s));
        WEFT_CUDA_CHECK(cudaMemcpyAsync(end.data(), kinematics.end_positions(), end.size() * sizeof(float),
                                        cudaMemcpyDeviceToHost, stream.s));
        WEFT_CUDA_CHECK(cudaMemcpyAsync(v.data(), kinematics.velocities(), v.size() * sizeof(float), cudaMemcpyDeviceToHost,
                                        stream.s));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(stream.s));
        std::vector<Vec3d> p0, p1;
        for (const auto& mc : g.meshes) {
            const ColliderDesc& c = model.colliders[mc.collider];
            std::vector<Vec3d> q0(c.mesh->positions.size()), q1(q0.size());
            collider_mesh_positions(c, t, q0);
            collider_mesh_positions(c, t + h, q1);
            p0.insert(p0.end(), q0.begin(), q0.end());
            p1.insert(p1.end(), q1.begin(), q1.end());
        }
        const auto d = [](float f) { return static_cast<double>(f); };
        for (std::size_t j = 0; j < nk; ++j)
            for (std::size_t c = 0; c < 3; ++c) {
                const int ci = static_cast<int>(c);
                const double host_v = (p1[j][ci] - p0[j][ci]) / h;
                worst_x = std::max({worst_x, std::abs(d(a[c * stride + cloth + j]) - p0[j][ci]),
                                    std::abs(d(b[c * stride + cloth + j]) - p1[j][ci])});
                worst_v = std::max(worst_v, std::abs(d(v[c * nk + j]) - host_v));
                fastest = std::max(fastest, std::abs(host_v));
                EXPECT_EQ(end[c * nk + j], b[c * stride + cloth + j]) << "vertex " << j;
            }
        // The still cube: exactly at rest.
        for (std::size_t j = nk - 8; j < nk; ++j)
            for (std::size_t c = 0; c < 3; ++c) EXPECT_EQ(v[c * nk + j], 0.0F) << "still cube vertex " << j;
    }
    // The character switches clips between substeps: its bind pose (no clip), then "bend" from t = 2.
    for (const auto& [clip, start] : {std::pair<std::string, double>{"", 0.0}, {"bend", 2.0}}) {
        model.colliders[0].clip = clip;
        model.colliders[0].clip_start = start;
        const double t = 2.3;
        kinematics.place(model, t, h, x0c.get(), x1c.get(), stride, cloth, stream.s);
        std::vector<float> b(3 * stride);
        WEFT_CUDA_CHECK(cudaMemcpyAsync(b.data(), x1c.get(), b.size() * sizeof(float), cudaMemcpyDeviceToHost, stream.s));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(stream.s));
        std::vector<Vec3d> host(model.colliders[0].mesh->positions.size());
        collider_mesh_positions(model.colliders[0], t + h, host);
        for (std::size_t j = 0; j < host.size(); ++j)
            for (std::size_t c = 0; c < 3; ++c)
                worst_x = std::max(worst_x, std::abs(static_cast<double>(b[c * stride + cloth + j]) - host[j][static_cast<int>(c)]));
    }
    std::printf("[ kinematics ] device against host: positions %.2e m, velocities %.2e m/s at worst (fastest %.2f m/s)\n",
                worst_x, worst_v, fastest);
    EXPECT_LT(worst_x, 2e-6);               // float rounding of coordinates of a few metres
    EXPECT_LT(worst_v, 1e-4 * fastest + 1e-5);  // from the maps' difference, not two positions'
    EXPECT_GT(fastest, 1.0) << "nothing moved: the test proves nothing";
}

#if WEFT_TEST_HAVE_ASSETS
// The shipped runner scene on the device: the character is skinned on the GPU each substep; the
// cape's pinned edge follows it as on the CPU backend, the cape stays free of intersections, and
// its shape tracks the CPU backend's (float against double).
TEST(CudaKinematics, TheRunnerSceneRunsOnTheDevice) {
    WEFT_REQUIRE_GPU();
    assets::install_mesh_loader();
    const SceneDesc scene = load_scene(test::scene_file("runner"), std::vector<std::string>{"collision.check=true"});
    auto gpu = build_world(scene, "cuda");
    auto cpu = build_world(scene, "cpu");
    const Model& model = gpu->model();
    const ColliderDesc& runner = model.colliders[0];
    std::vector<Vec3d> skin(runner.mesh->positions.size());
    collider_mesh_positions(runner, 0.0, skin);
    const std::vector<PinDesc>& pins = model.cloths[0].pins;
    const std::vector<Vec3d> start = gpu->positions(0);
    std::vector<Vec3d> offsets;
    for (const PinDesc& p : pins) offsets.push_back(start[p.vertex] - skin[p.collider_vertex]);
    long long intersecting = 0;
    double worst_pin = 0.0, apart = 0.0;
    for (int frame = 1; frame <= 60; ++frame) {
        const StepStats& s = gpu->step();
        ASSERT_FALSE(s.non_finite) << "frame " << frame;
        intersecting += s.collision.remaining_intersections;
        (void)cpu->step();
        collider_mesh_positions(runner, gpu->time(), skin);
        const std::vector<Vec3d> x = gpu->positions(0), y = cpu->positions(0);
        for (std::size_t k = 0; k < pins.size(); ++k)
            worst_pin = std::max(worst_pin, length(x[pins[k].vertex] - (skin[pins[k].collider_vertex] + offsets[k])));
        for (std::size_t i = 0; i < x.size(); ++i) apart = std::max(apart, length(x[i] - y[i]));
    }
    std::printf("[ kinematics ] runner on the device, 60 frames: pins %.2e m off the skin, %.3f m from the CPU at worst\n",
                worst_pin, apart);
    EXPECT_EQ(intersecting, 0);
    EXPECT_LT(worst_pin, 1e-5);  // float positions of ~1.6 m
    EXPECT_LT(apart, 0.05) << "the device's cape left the CPU's";
}
#endif

// The same check as the CPU backend's (tests/common/collider_jump.h): the jump from the maps on the
// host, the same number.
TEST(CudaKinematics, AMeshColliderThatJumpsBetweenSubstepsIsReportedLikeOnTheCpu) {
    WEFT_REQUIRE_GPU();
    test::expect_collider_jumps_reported("cuda");
}

}  // namespace
}  // namespace weft
