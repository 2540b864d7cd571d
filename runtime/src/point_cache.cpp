// PC2 point caches (weft/point_cache.h).
#include "weft/point_cache.h"

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "weft/error.h"

namespace weft {
namespace {

static_assert(std::endian::native == std::endian::little, "PC2 is little-endian; this writer stores native floats");

constexpr std::array<char, 12> kSignature = {'P', 'O', 'I', 'N', 'T', 'C', 'A', 'C', 'H', 'E', '2', '\0'};
constexpr std::int32_t kVersion = 1;
/// Byte offset of the sample count in the header: signature, version, points, start, rate.
constexpr std::streamoff kSampleCountAt = 12 + 4 + 4 + 4 + 4;
constexpr std::streamoff kHeaderBytes = kSampleCountAt + 4;

template <typename T>
void put(std::ofstream& out, T value) {
    out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
bool get(std::ifstream& in, T& value) {
    return static_cast<bool>(in.read(reinterpret_cast<char*>(&value), sizeof(T)));
}

}  // namespace

PointCacheWriter::PointCacheWriter(std::filesystem::path file, std::size_t points, double start_frame, double sample_rate)
    : file_(std::move(file)), points_(points) {
    if (points == 0 || points > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
        throw Error(file_.string() + ": a point cache of " + std::to_string(points) + " points");
    if (!std::isfinite(start_frame)) throw Error(file_.string() + ": start frame " + std::to_string(start_frame));
    if (!(sample_rate > 0.0) || !std::isfinite(sample_rate))
        throw Error(file_.string() + ": sample rate " + std::to_string(sample_rate) + " (frames between samples, > 0)");
    out_.open(file_, std::ios::binary | std::ios::trunc);
    if (!out_) throw Error("cannot write the point cache " + file_.string());
    out_.write(kSignature.data(), kSignature.size());
    put(out_, kVersion);
    put(out_, static_cast<std::int32_t>(points));
    put(out_, static_cast<float>(start_frame));
    put(out_, static_cast<float>(sample_rate));
    put(out_, std::int32_t{0});
    out_.flush();
    if (!out_) throw Error("cannot write the point cache " + file_.string());
    buffer_.resize(3 * points);
}

void PointCacheWriter::append(std::span<const Vec3d> positions) {
    if (positions.size() != points_)
        throw Error(file_.string() + ": a frame of " + std::to_string(positions.size()) + " points for a cache of " +
                    std::to_string(points_));
    if (frames_ >= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
        throw Error(file_.string() + ": the PC2 sample count is full");
    for (std::size_t i = 0; i < points_; ++i) {
        buffer_[3 * i + 0] = static_cast<float>(positions[i].x);
        buffer_[3 * i + 1] = static_cast<float>(positions[i].y);
        buffer_[3 * i + 2] = static_cast<float>(positions[i].z);
    }
    out_.seekp(0, std::ios::end);
    out_.write(reinterpret_cast<const char*>(buffer_.data()), static_cast<std::streamsize>(buffer_.size() * sizeof(float)));
    ++frames_;
    // The count last: a reader never sees a count beyond the data written.
    out_.seekp(kSampleCountAt);
    put(out_, static_cast<std::int32_t>(frames_));
    out_.flush();
    if (!out_) throw Error("cannot write the point cache " + file_.string());
}

PointCache read_point_cache(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw Error("cannot read the point cache " + file.string());
    std::array<char, 12> signature{};
    std::int32_t version = 0, points = 0, samples = 0;
    PointCache cache;
    if (!in.read(signature.data(), signature.size()) || signature != kSignature)
        throw Error(file.string() + ": not a PC2 point cache (no POINTCACHE2 signature)");
    if (!get(in, version) || !get(in, points) || !get(in, cache.start_frame) || !get(in, cache.sample_rate) || !get(in, samples))
        throw Error(file.string() + ": the PC2 header is cut short");
    if (version != kVersion) throw Error(file.string() + ": PC2 version " + std::to_string(version) + " (1 is read)");
    if (points <= 0 || samples < 0)
        throw Error(file.string() + ": " + std::to_string(points) + " points, " + std::to_string(samples) + " samples");
    cache.points = static_cast<std::size_t>(points);
    std::error_code ec;
    const auto size = std::filesystem::file_size(file, ec);
    const auto wanted = static_cast<std::uintmax_t>(kHeaderBytes) +
                        static_cast<std::uintmax_t>(samples) * cache.points * 3 * sizeof(float);
    if (ec || size < wanted)
        throw Error(file.string() + ": " + std::to_string(samples) + " samples of " + std::to_string(points) +
                    " points need " + std::to_string(wanted) + " bytes; the file has " + (ec ? std::string("?") : std::to_string(size)));
    std::vector<float> raw(3 * cache.points);
    cache.frames.reserve(static_cast<std::size_t>(samples));
    for (std::int32_t s = 0; s < samples; ++s) {
        if (!in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(raw.size() * sizeof(float))))
            throw Error(file.string() + ": sample " + std::to_string(s) + " is cut short");
        std::vector<Vec3f> frame(cache.points);
        for (std::size_t i = 0; i < cache.points; ++i) frame[i] = Vec3f{raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]};
        cache.frames.push_back(std::move(frame));
    }
    return cache;
}

}  // namespace weft
