// PC2 point caches (weft/point_cache.h): what is written reads back to the float, the header says
// what the frames hold after every frame (a bake stopped part way is a valid cache), and bad files
// and bad calls are errors naming the file.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "weft/error.h"
#include "weft/point_cache.h"

namespace weft {
namespace {

std::filesystem::path temp(const std::string& name) { return std::filesystem::temp_directory_path() / ("weft_pc2_" + name); }

std::vector<Vec3d> frame_at(int k, std::size_t n) {
    std::vector<Vec3d> x(n);
    for (std::size_t i = 0; i < n; ++i) x[i] = {0.1 * static_cast<double>(i), -0.01 * k, 1.0 / 3.0 + k};
    return x;
}

TEST(PointCache, FramesReadBackToTheFloat) {
    const auto file = temp("roundtrip.pc2");
    {
        PointCacheWriter w(file, 7, 1.0, 2.0);
        for (int k = 0; k < 4; ++k) {
            w.append(frame_at(k, 7));
            EXPECT_EQ(read_point_cache(file).frames.size(), static_cast<std::size_t>(k + 1)) << "after frame " << k;
        }
    }
    const PointCache c = read_point_cache(file);
    EXPECT_EQ(c.points, 7U);
    EXPECT_EQ(c.start_frame, 1.0F);
    EXPECT_EQ(c.sample_rate, 2.0F);
    ASSERT_EQ(c.frames.size(), 4U);
    for (int k = 0; k < 4; ++k) {
        const std::vector<Vec3d> x = frame_at(k, 7);
        for (std::size_t i = 0; i < 7; ++i) {
            EXPECT_EQ(c.frames[k][i].x, static_cast<float>(x[i].x));
            EXPECT_EQ(c.frames[k][i].y, static_cast<float>(x[i].y));
            EXPECT_EQ(c.frames[k][i].z, static_cast<float>(x[i].z));
        }
    }
    // The file is exactly the format's size: 32 header bytes and 12 a point a frame.
    EXPECT_EQ(std::filesystem::file_size(file), 32U + 4U * 7U * 12U);
    std::filesystem::remove(file);
}

TEST(PointCache, BadFilesAndCallsAreErrorsNamingTheFile) {
    const auto file = temp("bad.pc2");
    const auto expect_error = [&](auto&& call, const std::string& says) {
        try {
            call();
            ADD_FAILURE() << "no error; expected one saying " << says;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(file.filename().string()), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
        }
    };
    expect_error([&] { PointCacheWriter(file, 0); }, "0 points");
    expect_error([&] { PointCacheWriter(file, 3, 0.0, 0.0); }, "sample rate");
    {
        PointCacheWriter w(file, 3);
        expect_error([&] { w.append(frame_at(0, 4)); }, "a frame of 4 points");
        w.append(frame_at(0, 3));
        w.append(frame_at(1, 3));
    }
    // Cut the last frame short: the header promises two.
    std::filesystem::resize_file(file, std::filesystem::file_size(file) - 5);
    expect_error([&] { (void)read_point_cache(file); }, "need");
    {
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        out << "NOTACACHE!!!and more bytes than a header";
    }
    expect_error([&] { (void)read_point_cache(file); }, "signature");
    std::filesystem::remove(file);
    expect_error([&] { (void)read_point_cache(file); }, "cannot read");
}

}  // namespace
}  // namespace weft
