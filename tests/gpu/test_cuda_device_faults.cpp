// Device faults on the CUDA backend (docs/design.md, "Device faults"), provoked with the device
// memory limit (BackendOptions::device_memory_limit): a scene larger than the limit fails at build
// with the bytes asked for, held and free; a collision buffer that cannot grow mid-run fails its
// substep with the stage named and leaves the world at the last good state (the bits of a world that
// never failed, at the same step), from which it can still be saved; a fault does not crash the
// next step, which fails again with the same reason; and while the rebuild after it fails too, the
// audit, an output buffer and a restored warm start read no freed buffer.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include <cuda_runtime_api.h>

#include "backend_access.h"
#include "weft/cuda/cuda_backend.h"
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
    std::vector<std::size_t> memory{reference->memory_bytes()};
    std::vector<std::vector<Vec3d>> x{reference->positions(0)}, v{reference->velocities(0)};
    int growth = -1;
    for (int f = 1; f <= kFrames && growth < 0; ++f) {
        (void)reference->step();
        memory.push_back(reference->memory_bytes());
        x.push_back(reference->positions(0));
        v.push_back(reference->velocities(0));
        if (f >= 2 && memory[static_cast<std::size_t>(f)] > memory[static_cast<std::size_t>(f - 1)]) growth = f;
    }
    ASSERT_GT(growth, 1) << "layers' collision buffers did not grow in " << kFrames << " frames";
    const std::size_t before = memory[static_cast<std::size_t>(growth - 1)], after = memory[static_cast<std::size_t>(growth)];

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

}  // namespace
}  // namespace weft
