#pragma once
/// @file
/// `weft run --cache FILE.pc2`: the run's animation as PC2 point caches that DCC tools read
/// (weft/point_cache.h), one per cloth, each with its rest mesh as OBJ beside it (the first frame's
/// positions, the same vertex order): FILE.pc2 and FILE.obj for a scene of one cloth,
/// FILE_<cloth>.pc2 and FILE_<cloth>.obj for each cloth of several. Frame 0 is the initial state.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "weft/point_cache.h"

namespace weft {
class World;
}

namespace weft::cli {

class CacheWriter {
public:
    /// Checks the extension (.pc2), creates the folder, writes every cloth's rest OBJ and opens its
    /// cache. Throws weft::Error naming the file.
    CacheWriter(const std::filesystem::path& file, const World& world);
    /// Appends the world's current positions as the next frame of every cloth's cache.
    void append(const World& world);

    [[nodiscard]] std::size_t frames() const { return caches_.empty() ? 0 : caches_.front().frames(); }
    /// The caches' paths, in cloth order.
    [[nodiscard]] std::vector<std::filesystem::path> files() const;

private:
    std::vector<PointCacheWriter> caches_;
};

}  // namespace weft::cli
