#pragma once
// Shared helpers of the scene tests: paths into the source tree, error-message matching and the
// optional assimp loader.

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <initializer_list>
#include <string>
#include <string_view>

#include "weft/error.h"
#include "weft/mesh.h"

#if WEFT_TEST_HAVE_ASSETS
#include "weft/assets/assimp_loader.h"
#endif

namespace weft::test {

inline std::filesystem::path source_dir() { return WEFT_SOURCE_DIR; }
inline std::filesystem::path scene_file(std::string_view name) {
    return source_dir() / "assets" / "scenes" / (std::string(name) + ".toml");
}
inline std::filesystem::path data_file(std::string_view name) { return source_dir() / "tests" / "scene" / "data" / name; }

/// The smallest valid cloth table: scenes in the tests append what they exercise to it.
inline const std::string kSheet = R"(
[[cloth]]
name = "sheet"
mesh = { grid = { width = 1.0, height = 1.0, cells = [4, 4] } }
)";

/// Installs the assimp loader when the assets library is built; false when it is not.
inline bool install_loader() {
#if WEFT_TEST_HAVE_ASSETS
    weft::assets::install_mesh_loader();
    return true;
#else
    return false;
#endif
}

/// Runs `f`, expecting a weft::Error whose message contains every one of `parts`; returns the message.
inline std::string expect_error(const std::function<void()>& f, std::initializer_list<std::string_view> parts) {
    try {
        f();
    } catch (const weft::Error& e) {
        const std::string message = e.what();
        for (std::string_view p : parts)
            EXPECT_NE(message.find(p), std::string::npos) << "message lacks \"" << p << "\":\n  " << message;
        return message;
    } catch (const std::exception& e) {
        ADD_FAILURE() << "expected weft::Error, got another exception: " << e.what();
        return {};
    }
    ADD_FAILURE() << "expected weft::Error, nothing was thrown";
    return {};
}

}  // namespace weft::test
