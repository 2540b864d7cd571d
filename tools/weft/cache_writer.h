#pragma once
/// @file
/// `weft run --cache FILE`: the run's animation in a form DCC tools read, chosen by the extension.
/// FILE.pc2: PC2 point caches (weft/point_cache.h), one per cloth, each with its rest mesh as OBJ
/// beside it (the first frame's positions, the same vertex order): FILE.pc2 and FILE.obj for a scene
/// of one cloth, FILE_<cloth>.pc2 and FILE_<cloth>.obj for each cloth of several. FILE.glb: one glTF
/// binary with every cloth, its frames as morph targets (gltf_cache_writer.h). Frame 0 is the
/// initial state.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <memory>

#include "gltf_cache_writer.h"
#include "weft/point_cache.h"

namespace weft {
class World;
}

namespace weft::cli {

class CacheWriter {
public:
    /// Checks the extension (.pc2 or .glb), creates the folder and, for PC2, writes every cloth's
    /// rest OBJ and opens its cache. Frames are `frame_seconds` apart (s). Throws weft::Error naming
    /// the file.
    CacheWriter(const std::filesystem::path& file, const World& world, double frame_seconds);
    /// Appends the world's current positions as the next frame of every cloth.
    void append(const World& world);
    /// Ends the cache (the glTF file is written here; PC2 files are complete after every frame).
    void finish(const World& world);

    [[nodiscard]] std::size_t frames() const;
    /// The files written, in cloth order (one for glTF).
    [[nodiscard]] std::vector<std::filesystem::path> files() const;
    [[nodiscard]] const char* format() const { return gltf_ ? "glTF" : "PC2"; }

private:
    std::vector<PointCacheWriter> caches_;
    std::unique_ptr<GltfCacheWriter> gltf_;
};

}  // namespace weft::cli
