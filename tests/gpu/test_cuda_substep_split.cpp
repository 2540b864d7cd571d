// Splitting the substeps that tear the cloth on the CUDA backend (SolverSettings::split_stretch;
// docs/methods.md §1c): the World redoes a substep as halves through the backend's read_state,
// write_state and substeps of any length, so the runner through the banner (tests/common/
// banner_runner.h) tears it on the GPU as on the CPU at one step a frame, and splitting holds it,
// collision-free.
#include <gtest/gtest.h>

#include <cstdio>

#include "banner_runner.h"
#include "gpu_test_util.h"

namespace weft {
namespace {

TEST(CudaSubstepSplit, ABodyRunningThroughABannerTearsItUnlessTheDraggingSubstepsSplitLikeOnTheCpu) {
    WEFT_REQUIRE_GPU();
    auto whole = test::banner_runner(0.0, "cuda");
    const test::BannerRun torn = test::run_frames(*whole, test::kBannerFrames);
    auto split = test::banner_runner(2.0, "cuda");
    const test::BannerRun kept = test::run_frames(*split, test::kBannerFrames);
    std::printf("[   info   ] cuda, one step a frame: stretch up to %.2fx; split at 2x: %.2fx, %d substeps redone, %d taken\n",
                torn.max_stretch, kept.max_stretch, kept.split_substeps, kept.substeps);
    EXPECT_GE(torn.max_stretch, kOverstretch);
    EXPECT_LT(kept.max_stretch, kOverstretch);
    EXPECT_GT(kept.split_substeps, 0);
    EXPECT_GT(kept.substeps, test::kBannerFrames);
    EXPECT_EQ(kept.intersecting_frames, 0);
    EXPECT_EQ(kept.failed, 0);
}

}  // namespace
}  // namespace weft
