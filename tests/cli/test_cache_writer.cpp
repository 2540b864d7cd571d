// `weft run --cache` (tools/weft/cache_writer.h): every cloth of a world gets a PC2 cache whose
// frames are the world's positions after each step and a rest OBJ with the same vertices in the
// same order; a file name that is not .pc2 is refused.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cache_writer.h"
#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/point_cache.h"
#include "weft/scene.h"
#include "weft/world.h"

namespace weft::cli {
namespace {

TEST(CacheWriter, EveryClothsFramesAreTheWorldsPositions) {
    const auto dir = std::filesystem::temp_directory_path() / "weft_cache_writer";
    std::filesystem::remove_all(dir);
    const std::filesystem::path scene = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / "layers.toml";
    const std::vector<std::string> overrides{"solver.substeps=1"};
    auto world = build_world(load_scene(scene, overrides), "cpu");
    ASSERT_GT(world->cloth_count(), 1U);
    CacheWriter cache(dir / "run.pc2", *world);
    std::vector<std::vector<std::vector<Vec3d>>> expected(world->cloth_count());
    cache.append(*world);
    for (std::size_t c = 0; c < world->cloth_count(); ++c) expected[c].push_back(world->positions(c));
    for (int f = 0; f < 3; ++f) {
        (void)world->step();
        cache.append(*world);
        for (std::size_t c = 0; c < world->cloth_count(); ++c) expected[c].push_back(world->positions(c));
    }
    EXPECT_EQ(cache.frames(), 4U);
    const std::vector<std::filesystem::path> files = cache.files();
    ASSERT_EQ(files.size(), world->cloth_count());
    for (std::size_t c = 0; c < files.size(); ++c) {
        SCOPED_TRACE(files[c].string());
        EXPECT_EQ(files[c].parent_path(), dir);
        EXPECT_EQ(files[c].extension(), ".pc2");
        const PointCache read = read_point_cache(files[c]);
        ASSERT_EQ(read.frames.size(), 4U);
        ASSERT_EQ(read.points, expected[c][0].size());
        for (std::size_t k = 0; k < 4; ++k)
            for (std::size_t i = 0; i < read.points; ++i) {
                EXPECT_EQ(read.frames[k][i].x, static_cast<float>(expected[c][k][i].x));
                EXPECT_EQ(read.frames[k][i].y, static_cast<float>(expected[c][k][i].y));
                EXPECT_EQ(read.frames[k][i].z, static_cast<float>(expected[c][k][i].z));
            }
        // The rest mesh beside it: an OBJ of the first frame, one `v` line a vertex in order.
        const auto obj = std::filesystem::path(files[c]).replace_extension(".obj");
        ASSERT_TRUE(std::filesystem::exists(obj));
        std::ifstream in(obj);
        std::string line;
        std::size_t vertices = 0, faces = 0;
        while (std::getline(in, line)) {
            vertices += line.rfind("v ", 0) == 0 ? 1 : 0;
            faces += line.rfind("f ", 0) == 0 ? 1 : 0;
        }
        EXPECT_EQ(vertices, read.points);
        EXPECT_EQ(faces, world->cloth(c).fabric->triangles().size());
    }
    EXPECT_THROW(CacheWriter(dir / "run.abc", *world), Error);
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace weft::cli
