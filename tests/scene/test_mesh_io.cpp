// Mesh export (PLY binary, OBJ text) and the loader hook.
#include <bit>
#include <cstring>
#include <fstream>
#include <sstream>

#include "file_bytes.h"
#include "scene_test_util.h"

namespace weft {
namespace {

using test::expect_error;

const std::vector<Vec3d> kPositions{{0, 0, 0}, {1.5, 0, 0}, {1.5, 2.25, -0.125}, {0, 2.25, 1e-3}};
const std::vector<Triangle> kTriangles{{{0, 1, 2}}, {{0, 2, 3}}};

std::filesystem::path temp_path(const std::string& name) {
    return std::filesystem::temp_directory_path() / ("weft_test_mesh_io_" + name);
}


TEST(MeshIo, WritesObj) {
    const auto path = temp_path("a.obj");
    write_mesh(path, kPositions, kTriangles);
    std::istringstream in(test::file_bytes(path));
    std::vector<Vec3d> v;
    std::vector<Triangle> f;
    std::string tag;
    while (in >> tag) {
        if (tag == "v") {
            Vec3d p;
            in >> p.x >> p.y >> p.z;
            v.push_back(p);
        } else if (tag == "f") {
            Triangle t;
            for (auto& i : t.v) {
                in >> i;
                --i;
            }
            f.push_back(t);
        } else {
            std::getline(in, tag);
        }
    }
    EXPECT_EQ(v, kPositions);
    ASSERT_EQ(f.size(), 2U);
    EXPECT_EQ(f[1].v[2], 3U);
    std::filesystem::remove(path);
}

TEST(MeshIo, WritesBinaryLittleEndianPly) {
    const auto path = temp_path("a.PLY");  // the extension is case-insensitive
    write_mesh(path, kPositions, kTriangles);
    const std::string bytes = test::file_bytes(path);
    const std::string end = "end_header\n";
    const auto body = bytes.find(end);
    ASSERT_NE(body, std::string::npos);
    const std::string header = bytes.substr(0, body);
    EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
    EXPECT_NE(header.find("element vertex 4"), std::string::npos);
    EXPECT_NE(header.find("element face 2"), std::string::npos);
    const auto* data = reinterpret_cast<const unsigned char*>(bytes.data() + body + end.size());
    const auto u32 = [](const unsigned char* p) {
        return std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) | (std::uint32_t{p[3]} << 24);
    };
    ASSERT_EQ(bytes.size() - body - end.size(), 4U * 12U + 2U * 13U);
    for (std::size_t i = 0; i < kPositions.size(); ++i)
        for (int k = 0; k < 3; ++k)
            EXPECT_EQ(std::bit_cast<float>(u32(data + i * 12 + static_cast<std::size_t>(k) * 4)),
                      static_cast<float>(kPositions[i][k]));
    const unsigned char* faces = data + 48;
    EXPECT_EQ(faces[13], 3);
    EXPECT_EQ(u32(faces + 14), 0U);
    EXPECT_EQ(u32(faces + 22), 3U);
    std::filesystem::remove(path);
}

TEST(MeshIo, UnknownExtension) {
    expect_error([] { write_mesh(temp_path("a.stl"), kPositions, kTriangles); }, {"a.stl", "'.stl'", ".ply or .obj"});
}

TEST(MeshIo, UnwritablePath) {
    expect_error([] { write_mesh("/nonexistent_dir/x.obj", kPositions, kTriangles); }, {"/nonexistent_dir/x.obj"});
}

TEST(MeshIo, LoaderHook) {
    const auto file = test::data_file("quad.ply");
    set_mesh_file_loader({});
    EXPECT_FALSE(has_mesh_file_loader());
    expect_error([&] { (void)load_mesh_file(file); }, {"quad.ply", "mesh import not built (configure with -DWEFT_ASSETS=ON)"});

    // A fake loader that returns a seam-split square: load_mesh_file welds it.
    set_mesh_file_loader([](const std::filesystem::path&) {
        MeshData m;
        m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}};
        m.triangles = {{{0, 1, 2}}, {{3, 4, 5}}};
        return m;
    });
    EXPECT_TRUE(has_mesh_file_loader());
    const MeshData m = load_mesh_file(file);
    EXPECT_EQ(m.positions.size(), 4U);
    EXPECT_EQ(m.welded_vertices, 2U);
    EXPECT_EQ(m.source, file.string());
    expect_error([] { (void)load_mesh_file(test::data_file("nope.obj")); }, {"nope.obj", "not found"});
    set_mesh_file_loader({});
    test::install_loader();
}

}  // namespace
}  // namespace weft
