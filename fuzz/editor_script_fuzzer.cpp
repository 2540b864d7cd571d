// libFuzzer target: the editor's script parser (`weft edit --script FILE`) and its check against a
// scene's parameters must answer every text with a script or a weft::Error, never a crash (issue 24).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>

#include "weft/editor/parameters.h"
#include "weft/editor/script.h"
#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace {

/// A small world whose parameters the scripts' `set` and `expect` lines are checked against.
const weft::editor::ParameterTable& table() {
    static const auto world = [] {
        auto w = std::make_unique<weft::World>(weft::WorldDesc{}, "cpu");
        w->add_cloth({.name = "flag", .fabric = weft::Fabric::cook(weft::make_grid(1.0, 1.0, 4, 4))});
        return w;
    }();
    static const weft::editor::ParameterTable t(*world);
    return t;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        weft::editor::Script script = weft::editor::parse_script(text, "fuzz.txt");
        weft::editor::check_script(script, table());
    } catch (const weft::Error&) {
        // A clear error ("NAME:LINE: WHAT") is the right answer to a bad script.
    }
    return 0;
}
