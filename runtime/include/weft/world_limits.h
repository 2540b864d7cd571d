#pragma once
/// @file
/// Limits a scene must keep, stated once and enforced where scenes and meshes are read.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string_view>

namespace weft {

/// The largest coordinate, m, at which a scene may place cloth, colliders or motions (each
/// component, after a mesh's scale and placement). Float keeps about 8 mm at 1e5 m, already coarse
/// for cloth a few millimetres thick: keep a scene near its origin. Beyond it a scene is refused
/// with the value named rather than simulated into garbage.
inline constexpr double kWorldExtent = 1e5;

/// The most cloth vertices one world may hold (every cloth, `repeat` copies included). The CUDA
/// backend indexes up to about 238M, but at 4–9 KB a vertex on the CPU and 1–20 KB on the GPU (the
/// memory tables of docs/results.md) 50M is already hundreds of GB: past it the scene is a typo
/// (a grid of cells × repeat), and it is refused before anything of its size is allocated.
inline constexpr std::size_t kMaxWorldVertices = 50'000'000;

/// The largest mesh file (OBJ, PLY, glTF) Weft imports: the importer holds the whole file in
/// memory, several times over while it converts it. 2 GiB is about 40M triangles of OBJ.
inline constexpr std::uintmax_t kMaxMeshFileBytes = std::uintmax_t{2} << 30;

/// The largest scene file and editor script: text of a few KB; 16 MiB cannot be one written by hand
/// or by the editor, and is refused before it is read into memory.
inline constexpr std::uintmax_t kMaxTextFileBytes = std::uintmax_t{16} << 20;

/// Throws weft::Error naming `path`, its size and `limit` when the file is larger; `what` names the
/// kind ("mesh file", "scene file", "script"). A file whose size cannot be read passes: opening it
/// reports the error.
void check_file_size(const std::filesystem::path& path, std::uintmax_t limit, std::string_view what);

}  // namespace weft
