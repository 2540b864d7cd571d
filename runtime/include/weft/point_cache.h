#pragma once
/// @file
/// Point caches in the PC2 format, the cloth's animation as DCC tools read it (Blender's Mesh Cache
/// modifier, 3ds Max's Point Cache, Maya through its importers): every frame's vertex positions in
/// the mesh's own vertex order, beside a rest mesh (OBJ) with that order.
///
/// The file, little-endian: the 12 bytes "POINTCACHE2\0", int32 version (1), int32 point count,
/// float32 start frame, float32 sample rate (frames between samples), int32 sample count, then
/// sample count × point count × 3 float32 positions (m).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <span>
#include <vector>

#include "weft/types.h"

namespace weft {

/// Appends frames to a PC2 file as they are simulated. The header's sample count is rewritten after
/// every frame, so that a bake stopped part way leaves a valid cache of the frames so far.
class PointCacheWriter {
public:
    /// Creates (or replaces) `file` for `points` vertices a frame; the first frame is numbered
    /// `start_frame`, one every `sample_rate` frames. Throws weft::Error naming the file when it
    /// cannot be written, or naming the value when `points` is 0 or a number is not positive and finite.
    PointCacheWriter(std::filesystem::path file, std::size_t points, double start_frame = 0.0, double sample_rate = 1.0);

    /// Appends one frame (positions in m, converted to float32). Throws weft::Error naming the file
    /// when the count is not the cache's or the write fails.
    void append(std::span<const Vec3d> positions);

    [[nodiscard]] std::size_t frames() const { return frames_; }
    [[nodiscard]] const std::filesystem::path& file() const { return file_; }

private:
    std::filesystem::path file_;
    std::ofstream out_;
    std::size_t points_ = 0;
    std::size_t frames_ = 0;
    std::vector<float> buffer_;
};

/// A PC2 file read back.
struct PointCache {
    std::size_t points = 0;
    float start_frame = 0.0F;
    float sample_rate = 1.0F;
    std::vector<std::vector<Vec3f>> frames;  ///< per frame: `points` positions, m
};

/// Reads a PC2 file. Throws weft::Error naming the file and what is wrong (the signature, the
/// version, a count, or data shorter than the header says).
[[nodiscard]] PointCache read_point_cache(const std::filesystem::path& file);

}  // namespace weft
