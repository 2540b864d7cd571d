// Checkpoints (World::save_state / load_state; docs/design.md, "Checkpoints"): on the CPU backend a
// world resumed from a checkpoint steps on to the bits the saved world gives, in float and double,
// with wind, self-contact and a pin added at run time; corrupt, cut, foreign and mismatched files
// are refused with the reason, and the world they were offered to is left as it was.
#include <gtest/gtest.h>

#include "file_bytes.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "weft/error.h"
#include "world_snapshot.h"
#include "weft/scene.h"
#include "weft/world.h"

namespace weft {
namespace {

std::filesystem::path scene_file(const std::string& name) {
    return std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / (name + ".toml");
}

std::unique_ptr<World> make(const std::string& scene, std::vector<std::string> overrides) {
    return build_world(load_scene(scene_file(scene), overrides), "cpu");
}

using test::snapshot;

// One file per test (test::test_state_file).
std::filesystem::path state_file() { return test::test_state_file("weft_test_checkpoint_"); }

TEST(Checkpoint, AResumedWorldStepsOnToTheSameBits) {
    const std::filesystem::path kFile = state_file();
    struct Case {
        const char* scene;
        std::vector<std::string> overrides;
    };
    const Case cases[] = {
        {"flag", {"cloth.flag.mesh.grid.cells=[24,14]"}},                               // wind, pins, double
        {"flag", {"cloth.flag.mesh.grid.cells=[24,14]", "solver.precision=\"float\""}},  // float
        {"layers", {}},                                                                  // self-contact, CCD
        {"drape", {"solver.preconditioner=\"mas\""}},                                    // a ball, the Schwarz preconditioner
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(std::string(c.scene) + (c.overrides.empty() ? "" : " " + c.overrides.back()));
        auto saved = make(c.scene, c.overrides);
        for (int f = 0; f < 5; ++f) (void)saved->step();
        (void)saved->pin(0, 3);  // a pin added at run time travels with the checkpoint
        (void)saved->step();
        saved->save_state(kFile);
        for (int f = 0; f < 6; ++f) (void)saved->step();

        auto resumed = make(c.scene, c.overrides);
        resumed->load_state(kFile);
        EXPECT_EQ(resumed->steps(), 6U);
        EXPECT_TRUE(resumed->is_pinned(0, 3));
        for (int f = 0; f < 6; ++f) (void)resumed->step();
        EXPECT_TRUE(snapshot(*resumed) == snapshot(*saved)) << "the continuation differs";
        // Without the warm start the same steps land elsewhere: the checkpoint carries it.
        auto cold = make(c.scene, c.overrides);
        cold->load_state(kFile);
        for (std::size_t k = 0; k < cold->cloth_count(); ++k) cold->set_state(k, cold->positions(k), cold->velocities(k));
        for (int f = 0; f < 6; ++f) (void)cold->step();
        if (std::string(c.scene) != "layers") {
            EXPECT_FALSE(snapshot(*cold) == snapshot(*saved)) << "the warm start made no difference";
        }
    }
    std::filesystem::remove(kFile);
}

TEST(Checkpoint, BadCheckpointsAreRefusedAndChangeNothing) {
    const std::filesystem::path kFile = state_file();
    auto world = make("flag", {"cloth.flag.mesh.grid.cells=[24,14]"});
    for (int f = 0; f < 3; ++f) (void)world->step();
    world->save_state(kFile);
    const std::string good = test::file_bytes(kFile);
    auto target = make("flag", {"cloth.flag.mesh.grid.cells=[24,14]"});
    (void)target->step();
    const test::WorldSnapshot before = snapshot(*target);
    const auto refused = [&](const std::string& bytes, const std::string& says) {
        std::ofstream(kFile, std::ios::binary | std::ios::trunc) << bytes;
        try {
            target->load_state(kFile);
            ADD_FAILURE() << "accepted; expected an error saying " << says;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(kFile.filename().string()), std::string::npos) << e.what();
        }
        EXPECT_TRUE(snapshot(*target) == before) << "a refused checkpoint changed the world (" << says << ")";
    };
    std::string flipped = good;
    flipped[flipped.size() / 2] = static_cast<char>(flipped[flipped.size() / 2] ^ 0x10);
    refused(flipped, "checksum");
    refused(good.substr(0, good.size() - 7), "cut short");
    refused("not a checkpoint at all, just text", "not a Weft checkpoint");
    // Another scene (other vertex counts), another precision.
    auto other = make("flag", {"cloth.flag.mesh.grid.cells=[20,12]"});
    other->save_state(kFile);
    refused(test::file_bytes(kFile), "vertices in the checkpoint");
    auto single = make("flag", {"cloth.flag.mesh.grid.cells=[24,14]", "solver.precision=\"float\""});
    single->save_state(kFile);
    refused(test::file_bytes(kFile), "made in float");
    std::filesystem::remove(kFile);
}

}  // namespace
}  // namespace weft
