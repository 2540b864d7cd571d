#pragma once
/// @file
/// Skinned meshes through assimp (issue 23, item 2): a character's bind-pose mesh, its skeleton, skin
/// weights and animation clips from glTF 2.0 (.gltf, .glb) or FBX, into weft::SkinnedMesh
/// (weft/skinning.h). `tools/make_character.py` writes the shipped `assets/characters/runner.gltf`.

#include <filesystem>

#include "weft/skinning.h"

namespace weft::assets {

/// Imports every skinned triangle mesh of `path` into one SkinnedMesh: positions in the bind pose,
/// the joints (every node from the scene's root to each bone, parents first; the bones' offset
/// matrices as inverse bind transforms), up to four weights a vertex (the largest, normalised), and
/// every animation clip (times in seconds). Vertices are not welded: each keeps its own weights.
/// Throws weft::Error naming the file for a file assimp cannot read, one without a skinned mesh,
/// or one whose skin fails weft::validate. Thread-safe.
[[nodiscard]] SkinnedMesh import_skinned_mesh(const std::filesystem::path& path);

}  // namespace weft::assets
