// Checkpoints on the CUDA backend (World::save_state / load_state; docs/design.md, "Checkpoints"):
// a world resumed on the same device steps on to the bits the saved world gives, with wind and pins,
// proximity contacts and impact zones, offset contact and the Schwarz preconditioner; the warm start
// travels in the checkpoint (without it the same steps land elsewhere); a checkpoint of the CPU
// backend is refused with the reason and leaves the world as it was; across parts (--gpus N, here
// as parts on one GPU) the same, and a checkpoint moves between part counts and one GPU.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "gpu_test_util.h"
#include "multi/multi_gpu_backend.h"
#include "weft/error.h"
#include "world_snapshot.h"

namespace weft {
namespace {

using test::snapshot;

// One file per test (test::test_state_file).
std::filesystem::path state_file() { return test::test_state_file("weft_test_cuda_checkpoint_"); }

TEST(CudaCheckpoint, AResumedWorldStepsOnToTheSameBits) {
    WEFT_REQUIRE_GPU();
    const std::filesystem::path kFile = state_file();
    struct Case {
        const char* scene;
        std::vector<std::string> overrides;
        bool warm_start_matters;  // whether a cold restart must land elsewhere
    };
    const Case cases[] = {
        {"flag", {}, true},                                          // wind, gusts, pins, a capsule
        {"layers", {}, false},                                       // self-contact: contacts, CCD, impact zones
        {"layers", {"collision.mode=\"offset\""}, false},            // offset contact and its truncation
        {"drape", {"solver.preconditioner=\"mas\""}, true},          // a ball, the Schwarz preconditioner
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(std::string(c.scene) + (c.overrides.empty() ? "" : " " + c.overrides.back()));
        auto saved = test::make_world(c.scene, "cuda", c.overrides);
        for (int f = 0; f < 5; ++f) (void)saved->step();
        (void)saved->pin(0, 3);  // a pin added at run time travels with the checkpoint
        (void)saved->step();
        saved->save_state(kFile);
        for (int f = 0; f < 6; ++f) (void)saved->step();

        auto resumed = test::make_world(c.scene, "cuda", c.overrides);
        resumed->load_state(kFile);
        EXPECT_EQ(resumed->steps(), 6U);
        EXPECT_TRUE(resumed->is_pinned(0, 3));
        for (int f = 0; f < 6; ++f) (void)resumed->step();
        EXPECT_TRUE(snapshot(*resumed) == snapshot(*saved)) << "the continuation differs";

        auto cold = test::make_world(c.scene, "cuda", c.overrides);
        cold->load_state(kFile);
        for (std::size_t k = 0; k < cold->cloth_count(); ++k) cold->set_state(k, cold->positions(k), cold->velocities(k));
        for (int f = 0; f < 6; ++f) (void)cold->step();
        if (c.warm_start_matters) {
            EXPECT_FALSE(snapshot(*cold) == snapshot(*saved)) << "the warm start made no difference";
        }
    }
    std::filesystem::remove(kFile);
}

TEST(CudaCheckpoint, ACheckpointOfTheCpuBackendIsRefusedAndChangesNothing) {
    WEFT_REQUIRE_GPU();
    const std::filesystem::path kFile = state_file();
    const std::vector<std::string> small = {"cloth.flag.mesh.grid.cells=[24,14]"};
    auto cpu = test::make_world("flag", "cpu", small);
    (void)cpu->step();
    cpu->save_state(kFile);
    auto gpu = test::make_world("flag", "cuda", small);
    (void)gpu->step();
    (void)gpu->step();
    const test::WorldSnapshot before = snapshot(*gpu);
    try {
        gpu->load_state(kFile);
        ADD_FAILURE() << "a CPU checkpoint was taken by the CUDA backend";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("cpu backend"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(snapshot(*gpu) == before);
    std::filesystem::remove(kFile);
}

/// Shipped scene `scene` on `parts` parts, all on the first GPU (the multi-GPU test mode); 1: one GPU.
std::unique_ptr<World> world_on_parts(const std::string& scene, const std::vector<std::string>& overrides, int parts) {
    setenv(cuda::multi::kPartsOnOneDeviceEnv, "1", 1);
    BackendOptions options;
    options.gpus = parts;
    auto world = build_world(load_scene(test::scene_file(scene), overrides), "cuda", options);
    unsetenv(cuda::multi::kPartsOnOneDeviceEnv);
    return world;
}

std::vector<char> file_bytes(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Across parts the warm start is every part's owned Δv gathered into the one-GPU layout: resuming
// on the same part count continues to the same bits, and the file is the same whatever the part
// count that reads it (loaded on 2 parts or 1 GPU and saved at once, it comes back byte for byte).
TEST(CudaCheckpoint, AcrossPartsAResumedWorldStepsOnToTheSameBitsAndTheFileMovesBetweenPartCounts) {
    WEFT_REQUIRE_GPU();
    const std::filesystem::path kFile = state_file();
    const std::filesystem::path kAgain = kFile.string() + ".again";
    struct Case {
        const char* scene;
        std::vector<std::string> overrides;
    };
    const Case cases[] = {
        {"flag", {"solver.preconditioner=\"jacobi\""}},
        {"flag", {"solver.preconditioner=\"mas\"", "cloth.flag.mesh.grid.cells=[90,54]"}},
        {"layers", {"collision.mode=\"offset\""}},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(std::string(c.scene) + " " + c.overrides.front());
        auto saved = world_on_parts(c.scene, c.overrides, 2);
        for (int f = 0; f < 5; ++f) (void)saved->step();
        saved->save_state(kFile);
        for (int f = 0; f < 6; ++f) (void)saved->step();

        auto resumed = world_on_parts(c.scene, c.overrides, 2);
        resumed->load_state(kFile);
        for (int f = 0; f < 6; ++f) (void)resumed->step();
        EXPECT_TRUE(snapshot(*resumed) == snapshot(*saved)) << "the continuation on 2 parts differs";

        for (const int parts : {1, 3}) {
            auto other = world_on_parts(c.scene, c.overrides, parts);
            other->load_state(kFile);
            other->save_state(kAgain);
            EXPECT_TRUE(file_bytes(kAgain) == file_bytes(kFile)) << "2 parts' checkpoint through " << parts << " part(s)";
        }
    }
    // The warm start is in the file: a cold restart of the same state on 2 parts lands elsewhere.
    const std::vector<std::string> flag{"solver.preconditioner=\"jacobi\""};
    auto saved = world_on_parts("flag", flag, 2);
    for (int f = 0; f < 5; ++f) (void)saved->step();
    saved->save_state(kFile);
    for (int f = 0; f < 6; ++f) (void)saved->step();
    auto cold = world_on_parts("flag", flag, 2);
    cold->load_state(kFile);
    for (std::size_t k = 0; k < cold->cloth_count(); ++k) cold->set_state(k, cold->positions(k), cold->velocities(k));
    for (int f = 0; f < 6; ++f) (void)cold->step();
    EXPECT_FALSE(snapshot(*cold) == snapshot(*saved)) << "the warm start made no difference across parts";
    std::filesystem::remove(kFile);
    std::filesystem::remove(kAgain);
}

}  // namespace
}  // namespace weft
