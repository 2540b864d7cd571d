// Finding scenes by path or bare name, and the messages when they are not found.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "weft/error.h"

#include "scene_lookup.h"

namespace weft::cli {
namespace {

namespace fs = std::filesystem;

class SceneLookup : public ::testing::Test {
protected:
    void SetUp() override {
        root_ = fs::temp_directory_path() / ("weft_scene_lookup_" + std::to_string(::getpid()));
        fs::remove_all(root_);
        fs::create_directories(root_ / "a");
        fs::create_directories(root_ / "b");
        std::ofstream(root_ / "a" / "flag.toml") << "";
        std::ofstream(root_ / "b" / "flag.toml") << "";
        std::ofstream(root_ / "b" / "drape.toml") << "";
    }
    void TearDown() override { fs::remove_all(root_); }
    fs::path root_;
};

TEST_F(SceneLookup, BareNameFirstFolderWins) {
    EXPECT_EQ(find_scene("flag", {root_ / "a", root_ / "b"}), root_ / "a" / "flag.toml");
    EXPECT_EQ(find_scene("drape", {root_ / "a", root_ / "b"}), root_ / "b" / "drape.toml");
    EXPECT_EQ(find_scene("drape.toml", {root_ / "missing", root_ / "b"}), root_ / "b" / "drape.toml");
}

TEST_F(SceneLookup, PathsAreTakenAsGiven) {
    const fs::path file = root_ / "b" / "drape.toml";
    EXPECT_EQ(find_scene(file.string(), {}), file);
    EXPECT_EQ(find_scene((root_ / "b" / "drape").string(), {}), file);  // .toml appended
}

TEST_F(SceneLookup, NotFoundNamesSceneAndListsAvailable) {
    try {
        (void)find_scene("flgg", {root_ / "b"});
        FAIL() << "expected weft::Error";
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("'flgg'"), std::string::npos) << msg;
        EXPECT_NE(msg.find((root_ / "b" / "flgg.toml").string()), std::string::npos) << msg;
        EXPECT_NE(msg.find("available scenes: drape flag"), std::string::npos) << msg;
    }
    try {
        (void)find_scene((root_ / "nowhere" / "x.toml").string(), {root_ / "b"});
        FAIL() << "expected weft::Error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("x.toml"), std::string::npos) << e.what();
    }
}

TEST_F(SceneLookup, SceneNames) {
    EXPECT_EQ(scene_names(root_ / "b"), (std::vector<std::string>{"drape", "flag"}));
    EXPECT_TRUE(scene_names(root_ / "missing").empty());
}

}  // namespace
}  // namespace weft::cli
