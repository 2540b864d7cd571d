#pragma once
/// @file
/// `weft run --cache FILE.glb`: the run's animation as one glTF 2.0 binary (TinyGLTF, Debian's
/// libtinygltf-dev): a node and a mesh per cloth, the mesh's positions the first frame, one morph
/// target a later frame (its displacement from the first), and an animation of the morph weights
/// that shows frame k at time k·dt (linear between frames, so a player interpolates the positions).
/// Blender imports it as shape keys driven by the animation. Written when the run ends: the frames
/// are held in memory until then (12 bytes a vertex a frame).

#include <cstddef>
#include <filesystem>
#include <vector>

#include "weft/types.h"

namespace weft {
class World;
}

namespace weft::cli {

/// Whether this build writes .glb caches (TinyGLTF found at configure time).
[[nodiscard]] bool gltf_caches_available();

class GltfCacheWriter {
public:
    /// Frames `frame_seconds` apart (s). Throws weft::Error naming the file when glTF is not built
    /// or the folder cannot be made.
    GltfCacheWriter(std::filesystem::path file, const World& world, double frame_seconds);
    /// Keeps the world's current positions as the next frame.
    void append(const World& world);
    /// Writes the file. Throws weft::Error naming it on failure.
    void finish(const World& world);

    [[nodiscard]] std::size_t frames() const { return frames_.empty() ? 0 : frames_.front().size(); }
    [[nodiscard]] const std::filesystem::path& file() const { return file_; }

private:
    std::filesystem::path file_;
    double frame_seconds_ = 0.0;
    std::vector<std::vector<std::vector<Vec3f>>> frames_;  ///< per cloth, per frame, per vertex
};

}  // namespace weft::cli
