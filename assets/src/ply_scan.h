#pragma once
// What a PLY file's header declares, read and checked before assimp imports it. assimp 5.2 loops
// forever on a header without its `end_header` line (found by fuzz_mesh_import) and reads past the
// data of a file cut short; a header checked here, and data at least as long as the header says,
// keep both away from it.

#include <cstdint>
#include <filesystem>

namespace weft::assets {

struct PlyScan {
    bool binary = false;
    std::uint64_t vertices = 0;  ///< `element vertex N`
    std::uint64_t faces = 0;     ///< `element face N`
    std::uint64_t header_bytes = 0;
};

/// Reads and checks the header: the `ply` magic, a known format, `element` and `property` lines
/// of known types, `end_header` within the first 64 KiB. Then checks that the data can hold what the
/// header declares: for a binary file at least the bytes of the fixed-size elements (a list counts
/// its count field), for an ASCII file at least one line per element. Throws weft::Error naming the
/// file and what is wrong.
PlyScan scan_ply(const std::filesystem::path& path);

}  // namespace weft::assets
