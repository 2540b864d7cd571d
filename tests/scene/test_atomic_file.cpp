// Files written whole or not at all (weft/atomic_file.h): the target keeps its old bytes until the
// commit, an abandoned write leaves it as it was and no temporary behind, and failures name the file.
#include <gtest/gtest.h>

#include "file_bytes.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "weft/atomic_file.h"
#include "weft/error.h"
#include "weft/mesh.h"

namespace weft {
namespace {


TEST(AtomicFile, TheTargetChangesOnlyAtTheCommit) {
    const auto dir = std::filesystem::temp_directory_path() / "weft_atomic_file";
    std::filesystem::remove_all(dir);
    const auto target = dir / "sub" / "stats.json";
    EXPECT_THROW(write_file_atomically(target, "old"), Error) << "no folder, and none made unasked";
    { AtomicFile made(target, true); made.stream() << "old"; made.commit(); }
    EXPECT_EQ(test::file_bytes(target), "old");
    {
        AtomicFile f(target);
        f.stream() << "new, and longer";
        f.stream().flush();
        EXPECT_EQ(test::file_bytes(target), "old") << "before the commit";
        EXPECT_TRUE(std::filesystem::exists(f.temporary()));
        f.commit();
        EXPECT_FALSE(std::filesystem::exists(f.temporary()));
    }
    EXPECT_EQ(test::file_bytes(target), "new, and longer");
    {
        AtomicFile abandoned(target);
        abandoned.stream() << "half";
    }  // an exception, a return: never committed
    EXPECT_EQ(test::file_bytes(target), "new, and longer");
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir / "sub"), std::filesystem::directory_iterator{}), 1)
        << "no temporary left behind";
    // Meshes go the same way.
    const std::vector<Vec3d> x{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const std::vector<Triangle> t{Triangle{{0, 1, 2}}};
    write_mesh(dir / "m.obj", x, t);
    EXPECT_NE(test::file_bytes(dir / "m.obj").find("f 1 2 3"), std::string::npos);
    std::filesystem::remove_all(dir);
}

TEST(AtomicFile, AFolderThatCannotBeMadeIsAnErrorNamingTheFile) {
    const auto blocker = std::filesystem::temp_directory_path() / "weft_atomic_blocker";
    std::filesystem::remove_all(blocker);
    std::ofstream(blocker) << "a file where a folder is wanted";
    try {
        AtomicFile f(blocker / "out.json", true);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("out.json"), std::string::npos) << e.what();
    }
    std::filesystem::remove(blocker);
}

}  // namespace
}  // namespace weft
