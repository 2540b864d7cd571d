#pragma once
// What the checkpoint tests compare: every cloth's positions and velocities, the time and the step
// count of a World, bit for bit; and a checkpoint file of the running test's own.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "weft/world.h"

namespace weft::test {

struct WorldSnapshot {
    std::vector<std::vector<Vec3d>> x, v;
    double time = 0.0;
    std::size_t steps = 0;
    bool operator==(const WorldSnapshot&) const = default;
};

inline WorldSnapshot snapshot(const World& w) {
    WorldSnapshot s;
    for (std::size_t c = 0; c < w.cloth_count(); ++c) {
        s.x.push_back(w.positions(c));
        s.v.push_back(w.velocities(c));
    }
    s.time = w.time();
    s.steps = w.steps();
    return s;
}

/// A checkpoint file in the temporary folder named after `prefix` and the running test: one per
/// test, since ctest runs the tests of one binary as processes side by side.
inline std::filesystem::path test_state_file(const std::string& prefix) {
    return std::filesystem::temp_directory_path() /
           (prefix + ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".state");
}

}  // namespace weft::test
