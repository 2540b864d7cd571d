// libFuzzer target: the scene loader (TOML text and `--set` overrides) must answer every input with
// a scene or a weft::Error, never a crash, a hang or an unbounded allocation (issue 24, fuzzing).
//
// Input: the TOML text, then optionally a line "#--set" followed by one override a line.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "weft/error.h"
#include "weft/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view input(reinterpret_cast<const char*>(data), size);
    std::string_view toml = input;
    std::vector<std::string> overrides;
    if (const std::size_t split = input.find("\n#--set\n"); split != std::string_view::npos) {
        toml = input.substr(0, split);
        std::string_view rest = input.substr(split + 8);
        while (!rest.empty()) {
            const std::size_t end = rest.find('\n');
            overrides.emplace_back(rest.substr(0, end));
            rest = end == std::string_view::npos ? std::string_view() : rest.substr(end + 1);
        }
    }
    try {
        // Mesh files named by the input are looked up but none is loaded: parse_scene validates,
        // build_world (not called here) loads meshes. The mesh fuzzer covers those.
        (void)weft::parse_scene(toml, "fuzz.toml", overrides);
    } catch (const weft::Error&) {
        // A clear error is the right answer to bad input.
    }
    return 0;
}
