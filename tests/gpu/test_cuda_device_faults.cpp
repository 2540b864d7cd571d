// Device faults on the CUDA backend (docs/design.md, "Device faults"), provoked with the device
// memory limit (BackendOptions::device_memory_limit): a scene larger than the limit fails at build
// with the bytes asked for, held and free; a collision buffer that cannot grow mid-run fails its
// substep with the stage named and leaves the world at the last good state (the bits of a world that
// never failed, at the same step), from which it can still be saved; a fault does not crash the
// next step, which fails again with the same reason; and while the rebuild after it fails too, the
// audit, an output buffer and a restored warm start read no freed buffer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <cuda_runtime_api.h>

#include "backend_access.h"
#include "weft/cuda/cuda_backend.h"
#include "multi/multi_gpu_backend.h"
#include "gpu_test_util.h"
#include "weft/error.h"

namespace weft {
namespace {

std::unique_ptr<World> layers_world(std::size_t limit) {
    BackendOptions options;
    options.device_memory_limit = limit;
    // One substep a frame: a failed substep's start is the end of the frame before it.
    const std::vector<std::string> one_substep = {"solver.substeps=1"};
    return build_world(load_scene(test::scene_file("layers"), one_substep), "cuda", options);
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// Where a run's device memory first grows after its first frame: the bytes held at that frame and
/// at the one before, between which a second run's budget makes that frame fail.
struct Growth {
    int frame = -1;  ///< -1: it did not grow
    std::size_t before = 0, after = 0;
};

/// Steps the built world `reference` up to `frames` frames, taking `held()` (bytes) and calling
/// `record()` now and after every frame, until the first frame from the second on whose memory grew.
template <typename Held, typename Record>
Growth first_growth(World& reference, int frames, Held&& held, Record&& record) {
    std::vector<std::size_t> memory{held()};
    record();
    for (int f = 1; f <= frames; ++f) {
        (void)reference.step();
        memory.push_back(held());
        record();
        const auto k = static_cast<std::size_t>(f);
        if (f >= 2 && memory[k] > memory[k - 1]) return {f, memory[k - 1], memory[k]};
    }
    return {};
}

TEST(CudaDeviceFaults, ASceneLargerThanTheLimitFailsAtBuildWithTheBytes) {
    WEFT_REQUIRE_GPU();
    BackendOptions options;
    options.device_memory_limit = 1 << 20;  // 1 MiB: the flag's matrix alone needs more
    auto world = build_world(load_scene(test::scene_file("flag"), {}), "cuda", options);
    try {
        world->build();
        FAIL() << "a scene larger than the limit was built";
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_TRUE(contains(what, "out of device memory on GPU")) << what;
        EXPECT_TRUE(contains(what, "needs")) << what;
        EXPECT_TRUE(contains(what, "free of")) << what;
        EXPECT_TRUE(contains(what, "1.00 MiB (device_memory_limit)")) << what;
    }
    // Without the limit the same scene builds and steps.
    auto unlimited = test::make_world("flag", "cuda");
    EXPECT_NO_THROW((void)unlimited->step());
}

TEST(CudaDeviceFaults, ABufferThatCannotGrowMidRunFailsTheSubstepAndKeepsTheLastGoodState) {
    WEFT_REQUIRE_GPU();
    // The reference: the frame at which the collision buffers first grow after the build (the
    // sheets come into contact) and the memory before and after it.
    constexpr int kFrames = 60;
    auto reference = layers_world(0);
    reference->build();
    std::vector<std::vector<Vec3d>> x, v;
    const Growth grew = first_growth(*reference, kFrames, [&] { return reference->memory_bytes(); }, [&] {
        x.push_back(reference->positions(0));
        v.push_back(reference->velocities(0));
    });
    const int growth = grew.frame;
    ASSERT_GT(growth, 1) << "layers' collision buffers did not grow in " << kFrames << " frames";
    const std::size_t before = grew.before, after = grew.after;

    // A limit between the two: every frame before the growth runs, the growth's fails.
    auto capped = layers_world(before + (after - before) / 2);
    for (int f = 1; f < growth; ++f) ASSERT_NO_THROW((void)capped->step()) << "frame " << f;
    std::string first;
    try {
        (void)capped->step();
        FAIL() << "the buffer grew past the limit";
    } catch (const Error& e) {
        first = e.what();
    }
    EXPECT_TRUE(contains(first, "out of device memory")) << first;
    EXPECT_TRUE(contains(first, "failed in collision detection") || contains(first, "failed in CCD")) << first;
    EXPECT_TRUE(contains(first, "the cloth is back where that substep started")) << first;
    // The last good state: the reference's at the frame before, bit for bit, and readable.
    EXPECT_EQ(capped->steps(), static_cast<std::size_t>(growth - 1));
    const auto g = static_cast<std::size_t>(growth - 1);
    EXPECT_TRUE(capped->positions(0) == x[g]) << "the positions are not the last good frame's";
    EXPECT_TRUE(capped->velocities(0) == v[g]) << "the velocities are not the last good frame's";
    const std::filesystem::path file = std::filesystem::temp_directory_path() / "weft_test_cuda_fault.state";
    EXPECT_NO_THROW(capped->save_state(file));
    std::filesystem::remove(file);
    // The next step rebuilds from that state and fails the same way (the limit is still too small),
    // without a crash and without moving the cloth.
    try {
        (void)capped->step();
        ADD_FAILURE() << "the step after the fault passed the limit";
    } catch (const Error& e) {
        EXPECT_TRUE(contains(e.what(), "out of device memory")) << e.what();
    }
    EXPECT_TRUE(capped->positions(0) == x[g]);

    // A rebuild that fails as well (the limit lowered below what the build needs), when the buffers
    // are gone: the step fails cleanly; the state stays readable; the energy audit rebuilds first and
    // fails with the reason instead of reading freed buffers; an output buffer bound meanwhile waits
    // for the rebuild, and a warm start restored meanwhile is kept for it. With the limit raised again
    // the world steps on from the last good state and writes the output.
    Backend& backend = capped->backend();
    cuda::DeviceMemoryBudget* budget = cuda::device_memory_budget(backend);
    ASSERT_NE(budget, nullptr);
    budget->set_limit(1);
    EXPECT_THROW((void)capped->step(), Error);
    EXPECT_TRUE(capped->positions(0) == x[g]);
    const Model& model = capped->model();
    const double h = model.settings.solver.dt / model.settings.solver.substeps;
    try {
        (void)backend.energy_audit(model, capped->time(), h, false);
        ADD_FAILURE() << "the audit ran without its buffers";
    } catch (const Error& e) {
        EXPECT_TRUE(contains(e.what(), "out of device memory")) << e.what();
    }
    cuda::CudaBackendApi* api = cuda::as_cuda(backend);
    ASSERT_NE(api, nullptr);
    const std::size_t n = api->vertex_count();
    constexpr std::size_t kStride = 6 * sizeof(float);
    float* output = nullptr;
    ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&output), n * kStride), cudaSuccess);
    ASSERT_EQ(cudaMemset(output, 0, n * kStride), cudaSuccess);
    EXPECT_NO_THROW(api->set_output(output, kStride));
    std::vector<std::uint8_t> warm;
    EXPECT_NO_THROW(warm = backend.solver_state());
    EXPECT_NO_THROW(backend.restore_solver_state(warm));
    budget->set_limit(0);
    StepStats resumed;
    EXPECT_NO_THROW(resumed = capped->step());
    EXPECT_FALSE(resumed.non_finite);
    EXPECT_EQ(capped->steps(), static_cast<std::size_t>(growth));
    std::vector<float> written(6 * n);
    ASSERT_EQ(cudaMemcpy(written.data(), output, n * kStride, cudaMemcpyDeviceToHost), cudaSuccess);
    const std::vector<Vec3d> now = capped->positions(0);
    std::size_t equal = 0;
    for (std::size_t i = 0; i < now.size(); ++i)
        if (written[6 * i] == static_cast<float>(now[i].x) && written[6 * i + 1] == static_cast<float>(now[i].y) &&
            written[6 * i + 2] == static_cast<float>(now[i].z))
            ++equal;
    EXPECT_EQ(equal, now.size()) << "the output buffer bound during the fault does not hold the state";
    api->set_output(nullptr, 0);
    cudaFree(output);
}

/// `layers` at one substep a frame on two parts of one GPU (the multi-GPU solver's test mode: the
/// partition, the halo and the collision shares of two GPUs), with the budget `limit` on that GPU.
std::unique_ptr<World> layers_on_two_parts(std::size_t limit) {
    setenv(cuda::multi::kPartsOnOneDeviceEnv, "1", 1);
    BackendOptions options;
    options.gpus = 2;
    options.device_memory_limit = limit;
    const std::vector<std::string> one_substep = {"solver.substeps=1"};
    auto world = build_world(load_scene(test::scene_file("layers"), one_substep), "cuda", options);
    unsetenv(cuda::multi::kPartsOnOneDeviceEnv);
    return world;
}

struct WorldState {
    std::vector<std::vector<Vec3d>> x, v;  // per cloth
    bool operator==(const WorldState&) const = default;
};

WorldState state_of(World& world) {
    WorldState s;
    for (std::size_t c = 0; c < world.cloth_count(); ++c) {
        s.x.push_back(world.positions(c));
        s.v.push_back(world.velocities(c));
    }
    return s;
}

// The same promise across parts: a buffer that cannot grow mid-run fails the substep with the stage
// named and puts every part back where the substep started (the bits of a world that never failed,
// every cloth), the state readable and savable; the next step rebuilds the parts and fails again
// while the memory is not there, and steps on once it is.
TEST(CudaDeviceFaults, AcrossPartsAFailedSubstepPutsEveryPartBack) {
    WEFT_REQUIRE_GPU();
    // The reference: the budget's own count on the GPU, frame by frame, to the first growth after
    // the first frames (the audit's buffers come with the first step).
    constexpr int kFrames = 60;
    auto reference = layers_on_two_parts(0);
    reference->build();
    cuda::DeviceMemoryBudget* reference_budget = cuda::device_memory_budget(reference->backend());
    ASSERT_NE(reference_budget, nullptr) << "the multi-GPU backend has no budget";
    const int device = 0;
    std::vector<WorldState> states;
    const Growth grew = first_growth(*reference, kFrames, [&] { return reference_budget->held(device); },
                                     [&] { states.push_back(state_of(*reference)); });
    const int growth = grew.frame;
    ASSERT_GT(growth, 1) << "layers' device memory on two parts did not grow in " << kFrames << " frames";
    const std::size_t before = grew.before, after = grew.after;
    std::printf("[ fault    ] two parts: the device memory grows at frame %d, %zu -> %zu bytes\n", growth, before, after);

    auto capped = layers_on_two_parts(before + (after - before) / 2);
    ASSERT_NO_THROW(capped->build());
    for (int f = 1; f < growth; ++f) ASSERT_NO_THROW((void)capped->step()) << "frame " << f;
    std::string first;
    try {
        (void)capped->step();
        FAIL() << "the buffer grew past the limit";
    } catch (const Error& e) {
        first = e.what();
    }
    std::printf("[ fault    ] %s\n", first.c_str());
    EXPECT_TRUE(contains(first, "out of device memory")) << first;
    EXPECT_TRUE(contains(first, "parts: the substep from t =")) << first;
    EXPECT_TRUE(contains(first, "every part is back where that substep started")) << first;
    const auto g = static_cast<std::size_t>(growth - 1);
    EXPECT_EQ(capped->steps(), g);
    EXPECT_TRUE(state_of(*capped) == states[g]) << "the state is not the last good frame's on every cloth";
    const std::filesystem::path file = std::filesystem::temp_directory_path() / "weft_test_cuda_parts_fault.state";
    EXPECT_NO_THROW(capped->save_state(file));
    std::filesystem::remove(file);
    // The next step rebuilds the parts from that state and fails the same way, the cloth unmoved.
    try {
        (void)capped->step();
        ADD_FAILURE() << "the step after the fault passed the limit";
    } catch (const Error& e) {
        EXPECT_TRUE(contains(e.what(), "out of device memory")) << e.what();
    }
    EXPECT_TRUE(state_of(*capped) == states[g]);
    // With the limit lifted the parts are rebuilt and step on from the last good state. The rebuild
    // starts the CG cold, so the step is near the reference's, not its bits.
    cuda::DeviceMemoryBudget* budget = cuda::device_memory_budget(capped->backend());
    ASSERT_NE(budget, nullptr);
    budget->set_limit(0);
    StepStats resumed;
    EXPECT_NO_THROW(resumed = capped->step());
    EXPECT_FALSE(resumed.non_finite);
    EXPECT_EQ(capped->steps(), g + 1);
    const WorldState now = state_of(*capped);
    double apart = 0.0, moved = 0.0;
    for (std::size_t c = 0; c < now.x.size(); ++c)
        for (std::size_t i = 0; i < now.x[c].size(); ++i) {
            apart = std::max(apart, length(now.x[c][i] - states[g + 1].x[c][i]));
            moved = std::max(moved, length(now.x[c][i] - states[g].x[c][i]));
        }
    std::printf("[ fault    ] resumed: %.3e m from the reference's frame %d, moved %.3e m\n", apart, growth, moved);
    EXPECT_GT(moved, 0.0) << "the resumed step did not move the cloth";
    EXPECT_LT(apart, 5e-3) << "the resumed step is not the reference's";
}

}  // namespace
}  // namespace weft
