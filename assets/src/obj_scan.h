#pragma once
// What an OBJ file says about itself, read before assimp imports it: assimp keeps only the vertices
// that faces use and stops quietly where a file ends, so a file cut short (a copy interrupted, a
// download truncated) would load as a smaller cloth. The marks such a file leaves: a last line
// without its newline that is not a whole vertex or face, or vertices that no face uses.

#include <cstddef>
#include <filesystem>

namespace weft::assets {

struct ObjScan {
    std::size_t vertices = 0;             ///< `v` lines
    std::size_t faces = 0;                ///< `f` lines
    std::size_t unreferenced = 0;         ///< vertices no face refers to
    bool ends_mid_line = false;  ///< the last line has no newline and is not a whole vertex (3 numbers) or face (3 corners)
};

/// Scans an OBJ file's `v` and `f` lines (positive and negative indices, `v/vt/vn` forms). Throws
/// weft::Error naming the file and line for a face index out of range or not a number.
[[nodiscard]] ObjScan scan_obj(const std::filesystem::path& path);

}  // namespace weft::assets
