#pragma once
/// @file
/// Writes one mesh per cloth per frame for `weft run --out DIR`: DIR/frame_0000_<cloth>.ply, where
/// frame 0 is the initial state and frame N the state after N steps.

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "cli_args.h"

namespace weft {
class World;
}

namespace weft::cli {

/// `name` made safe as part of a file name: letters, digits, '-', '_' and '.' kept, the rest '_'.
[[nodiscard]] std::string file_name_part(std::string_view name);

class FrameWriter {
public:
    /// Creates `dir` (and parents). `cloth_names` come from the world in cloth order; empty or
    /// repeated names get the cloth index so that every cloth has its own file.
    FrameWriter(std::filesystem::path dir, MeshFormat format, const std::vector<std::string>& cloth_names,
                int last_frame);

    [[nodiscard]] std::filesystem::path path(int frame, std::size_t cloth) const;
    /// Writes every cloth of `world` as frame `frame`. Throws `weft::Error` if a file cannot be written.
    void write(int frame, const World& world);

    [[nodiscard]] const std::filesystem::path& dir() const { return dir_; }
    [[nodiscard]] std::size_t files_written() const { return files_written_; }
    /// A glob-like pattern for messages, e.g. "out/demo/frame_*_flag.ply".
    [[nodiscard]] std::string pattern() const;

private:
    std::filesystem::path dir_;
    MeshFormat format_;
    std::vector<std::string> stems_;
    int digits_ = 4;
    std::size_t files_written_ = 0;
};

}  // namespace weft::cli
