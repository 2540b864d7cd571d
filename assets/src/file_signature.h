#pragma once
// The first bytes of a mesh file against its extension, before assimp sees it (its readers overflow
// their buffers on some garbage: found by fuzz_mesh_import).

#include <filesystem>
#include <fstream>
#include <string>

#include "weft/error.h"

namespace weft::assets {

/// Throws when the first bytes of `path` cannot start a file of extension `ext` (lower case):
/// glTF JSON opens with '{', a GLB with "glTF", a PLY with "ply", an OBJ is text (no NUL byte in
/// its first 4 KiB). Other extensions are left to assimp. Returns whether the file starts with the
/// PLY magic line, whatever its extension.
inline bool check_signature(const std::filesystem::path& path, const std::string& ext) {
    std::ifstream in(path, std::ios::binary);
    std::string head(4096, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
    const std::string file = path.string();
    const auto first = head.find_first_not_of(" \t\r\n\xEF\xBB\xBF");  // a UTF-8 byte-order mark too
    if (ext == ".gltf" && (first == std::string::npos || head[first] != '{'))
        throw Error(file + ": not a glTF file (its JSON does not start with '{')");
    if (ext == ".glb" && head.rfind("glTF", 0) != 0) throw Error(file + ": not a GLB file (no 'glTF' magic)");
    if (ext == ".ply" && head.rfind("ply", 0) != 0) throw Error(file + ": not a PLY file (no 'ply' on the first line)");
    if (ext == ".obj" && head.find('\0') != std::string::npos) throw Error(file + ": not an OBJ file (it holds binary data)");
    return head.size() >= 4 && head.rfind("ply", 0) == 0 && (head[3] == '\n' || head[3] == '\r');
}

}  // namespace weft::assets
