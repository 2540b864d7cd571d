// The stated input limits (weft/world_limits.h) are enforced with a message naming the file or the
// cloth, the size and the limit, before anything of that size is read or allocated: a world of more
// than kMaxWorldVertices cloth vertices (a grid and a repeat count), a scene file or script above
// kMaxTextFileBytes, a mesh file above kMaxMeshFileBytes (a sparse file: nothing is written).
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "scene_test_util.h"
#include "weft/scene.h"
#include "weft/world.h"
#include "weft/world_limits.h"

#if WEFT_TEST_HAVE_ASSETS
#include "weft/assets/assimp_loader.h"
#endif

namespace weft {
namespace {

using test::expect_error;
using test::scene_file;

std::filesystem::path temp_file(const std::string& name) { return std::filesystem::temp_directory_path() / name; }

TEST(InputLimits, AWorldOfTooManyClothVerticesIsRefusedBeforeItsCopiesAreMade) {
    // 501² = 251,001 vertices a sheet: 199 sheets fit under 50M, 200 do not.
    const std::vector<std::string> fits = {"cloth.sheets.mesh.grid.cells=[500,500]", "cloth.sheets.repeat.count=199"};
    EXPECT_EQ(build_world(load_scene(scene_file("layers"), fits))->cloth_count(), 199U);
    const std::vector<std::string> too_many = {"cloth.sheets.mesh.grid.cells=[500,500]", "cloth.sheets.repeat.count=200"};
    const SceneDesc scene = load_scene(scene_file("layers"), too_many);
    expect_error([&] { (void)build_world(scene); },
                 {"layers.toml", "'sheets0'", "200 copies of 251001 vertices", "50200200", "more than the 50000000"});
}

TEST(InputLimits, FilesLargerThanTheLimitAreRefusedBeforeTheyAreRead) {
    const std::filesystem::path small = temp_file("weft_test_limits_small.txt");
    std::ofstream(small) << std::string(100, 'x');
    expect_error([&] { check_file_size(small, 10, "thing"); }, {"weft_test_limits_small.txt", "the thing is 100 B", "more than the 10 B"});
    EXPECT_NO_THROW(check_file_size(small, 100, "thing"));
    std::filesystem::remove(small);

    // A scene file of 17 MiB (sparse: resize_file writes no data).
    const std::filesystem::path scene = temp_file("weft_test_limits_big.toml");
    std::ofstream(scene) << "# big\n";
    std::filesystem::resize_file(scene, kMaxTextFileBytes + 1);
    expect_error([&] { (void)load_scene(scene); }, {"weft_test_limits_big.toml", "scene file", "more than the 16.0 MiB"});
    std::filesystem::remove(scene);
#if WEFT_TEST_HAVE_ASSETS
    const std::filesystem::path mesh = temp_file("weft_test_limits_big.obj");
    std::ofstream(mesh) << "v 0 0 0\n";
    std::filesystem::resize_file(mesh, kMaxMeshFileBytes + 1);
    expect_error([&] { (void)assets::import_mesh(mesh); }, {"weft_test_limits_big.obj", "mesh file", "more than the 2.00 GiB"});
    std::filesystem::remove(mesh);
#endif
}

}  // namespace
}  // namespace weft
