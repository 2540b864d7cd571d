// `weft run --cache` (tools/weft/cache_writer.h): every cloth of a world gets a PC2 cache whose
// frames are the world's positions after each step and a rest OBJ with the same vertices in the
// same order; the glTF binary holds every cloth with its frames as morph targets and an animation
// that shows frame k at k·dt (read back with TinyGLTF); a file name of another kind is refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
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

#ifdef WEFT_TEST_HAVE_GLTF
#include <tiny_gltf.h>
#endif

namespace weft::cli {
namespace {

TEST(CacheWriter, EveryClothsFramesAreTheWorldsPositions) {
    const auto dir = std::filesystem::temp_directory_path() / "weft_cache_writer";
    std::filesystem::remove_all(dir);
    const std::filesystem::path scene = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / "layers.toml";
    const std::vector<std::string> overrides{"solver.substeps=1"};
    auto world = build_world(load_scene(scene, overrides), "cpu");
    ASSERT_GT(world->cloth_count(), 1U);
    CacheWriter cache(dir / "run.pc2", *world, 1.0 / 60.0);
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
    EXPECT_THROW(CacheWriter(dir / "run.abc", *world, 1.0 / 60.0), Error);
    std::filesystem::remove_all(dir);
}

#ifdef WEFT_TEST_HAVE_GLTF
/// The floats of accessor `index` (tightly packed, as the writer makes them).
std::vector<float> floats_of(const tinygltf::Model& m, int index) {
    const tinygltf::Accessor& a = m.accessors.at(static_cast<std::size_t>(index));
    const tinygltf::BufferView& v = m.bufferViews.at(static_cast<std::size_t>(a.bufferView));
    const std::size_t per = a.type == TINYGLTF_TYPE_VEC3 ? 3 : 1;
    std::vector<float> out(a.count * per);
    std::memcpy(out.data(), m.buffers.at(0).data.data() + v.byteOffset + a.byteOffset, out.size() * sizeof(float));
    return out;
}

TEST(CacheWriter, TheGltfCacheHoldsEveryFrameAsAMorphTarget) {
    const auto file = std::filesystem::temp_directory_path() / "weft_cache_writer_glb" / "run.glb";
    std::filesystem::remove_all(file.parent_path());
    const std::filesystem::path scene = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / "layers.toml";
    const std::vector<std::string> overrides{"solver.substeps=1"};
    auto world = build_world(load_scene(scene, overrides), "cpu");
    const double dt = world->settings().solver.dt;
    CacheWriter cache(file, *world, dt);
    std::vector<std::vector<std::vector<Vec3d>>> expected(world->cloth_count());
    for (int f = 0; f < 5; ++f) {
        if (f > 0) (void)world->step();
        cache.append(*world);
        for (std::size_t c = 0; c < world->cloth_count(); ++c) expected[c].push_back(world->positions(c));
    }
    cache.finish(*world);
    ASSERT_EQ(cache.files().size(), 1U);

    tinygltf::Model m;
    tinygltf::TinyGLTF loader;
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, file.string())) << err;
    ASSERT_EQ(m.meshes.size(), world->cloth_count());
    ASSERT_EQ(m.animations.size(), 1U);
    const tinygltf::Animation& anim = m.animations[0];
    ASSERT_EQ(anim.channels.size(), world->cloth_count());
    const std::vector<float> times = floats_of(m, anim.samplers.at(0).input);
    ASSERT_EQ(times.size(), 5U);
    for (std::size_t k = 0; k < 5; ++k) EXPECT_FLOAT_EQ(times[k], static_cast<float>(static_cast<double>(k) * dt));
    for (std::size_t c = 0; c < m.meshes.size(); ++c) {
        SCOPED_TRACE(m.meshes[c].name);
        EXPECT_EQ(m.meshes[c].name, world->cloth(c).name);
        const tinygltf::Primitive& p = m.meshes[c].primitives.at(0);
        const std::vector<float> base = floats_of(m, p.attributes.at("POSITION"));
        ASSERT_EQ(base.size(), 3 * expected[c][0].size());
        ASSERT_EQ(p.targets.size(), 4U);
        EXPECT_EQ(m.accessors.at(static_cast<std::size_t>(p.indices)).count, 3 * world->cloth(c).fabric->triangles().size());
        for (std::size_t k = 0; k < 5; ++k) {
            const std::vector<float> d = k == 0 ? std::vector<float>(base.size(), 0.0F) : floats_of(m, p.targets[k - 1].at("POSITION"));
            double worst = 0.0;
            for (std::size_t i = 0; i < expected[c][k].size(); ++i) {
                const Vec3d& x = expected[c][k][i];
                const double e[3] = {x.x, x.y, x.z};
                for (int a = 0; a < 3; ++a)
                    worst = std::max(worst, std::abs(static_cast<double>(base[3 * i + a] + d[3 * i + a]) - e[a]));
            }
            EXPECT_LT(worst, 1e-6) << "frame " << k;  // float rounding of a position of a few metres
        }
        // The channel's weights at key k: one-hot at target k − 1.
        const tinygltf::AnimationChannel& ch = anim.channels[c];
        EXPECT_EQ(ch.target_path, "weights");
        EXPECT_EQ(m.nodes.at(static_cast<std::size_t>(ch.target_node)).mesh, static_cast<int>(c));
        const std::vector<float> w = floats_of(m, anim.samplers.at(static_cast<std::size_t>(ch.sampler)).output);
        ASSERT_EQ(w.size(), 5U * 4U);
        for (std::size_t k = 0; k < 5; ++k)
            for (std::size_t t = 0; t < 4; ++t) EXPECT_EQ(w[k * 4 + t], k > 0 && t == k - 1 ? 1.0F : 0.0F) << k << ", " << t;
    }
    std::filesystem::remove_all(file.parent_path());
}
#endif

}  // namespace
}  // namespace weft::cli
