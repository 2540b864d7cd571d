// Text formatting for summaries and output file names.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "frame_writer.h"
#include "text_table.h"

namespace weft::cli {
namespace {

TEST(TextTable, AlignsColumns) {
    TextTable table({{"stage", TextTable::Align::Left}, {"ms"}});
    table.add_row({"solve", "12.500"});
    table.add_row({"kinematics", "0.1"});
    std::ostringstream out;
    table.print(out, "");
    EXPECT_EQ(out.str(),
              "stage           ms\n"
              "------------------\n"
              "solve       12.500\n"
              "kinematics     0.1\n");
    EXPECT_THROW(table.add_row({"a", "b", "c"}), std::invalid_argument);
}

TEST(TextTable, Formatting) {
    EXPECT_EQ(format_fixed(1.23456, 2), "1.23");
    EXPECT_EQ(format_fixed(std::numeric_limits<double>::quiet_NaN(), 2), "-");
    EXPECT_EQ(format_bytes(512), "512 B");
    EXPECT_EQ(format_bytes(1536), "1.50 KiB");
    EXPECT_EQ(format_bytes(200.0 * 1024 * 1024), "200 MiB");
    EXPECT_EQ(format_duration(65), "1:05");
    EXPECT_EQ(format_duration(3725), "1:02:05");
    EXPECT_EQ(display_width("×é"), 2u);
}

TEST(FrameWriter, FileNamePart) {
    EXPECT_EQ(file_name_part("flag"), "flag");
    EXPECT_EQ(file_name_part("my cape/1"), "my_cape_1");
    EXPECT_EQ(file_name_part("a.b-c_d"), "a.b-c_d");
}

TEST(FrameWriter, PathsAreUniquePerCloth) {
    const auto dir = std::filesystem::temp_directory_path() / ("weft_frame_writer_" + std::to_string(::getpid()));
    {
        const FrameWriter writer(dir / "out", MeshFormat::Ply, {"flag", "flag", ""}, 3);
        EXPECT_TRUE(std::filesystem::is_directory(dir / "out"));
        EXPECT_EQ(writer.path(1, 0), dir / "out" / "frame_0001_flag.ply");
        EXPECT_EQ(writer.path(1, 1), dir / "out" / "frame_0001_flag_1.ply");
        EXPECT_EQ(writer.path(0, 2), dir / "out" / "frame_0000_cloth2.ply");
        const FrameWriter wide(dir / "obj", MeshFormat::Obj, {"sheet"}, 12345);
        EXPECT_EQ(wide.path(7, 0), dir / "obj" / "frame_00007_sheet.obj");
        EXPECT_EQ(wide.pattern(), (dir / "obj" / "frame_*").string() + "_sheet.obj");
    }
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace weft::cli
