// Mesh import through assimp (skipped when weft::assets is not built): OBJ, PLY and glTF load; the
// skirt's UV seam is welded shut; exported meshes read back; bad meshes are reported, not crashed on.
#include <algorithm>
#include <fstream>
#include <map>
#include <numeric>
#include <set>
#include <sstream>
#include <tuple>

#include "scene_test_util.h"
#include "weft/backend/model.h"
#include "weft/scene.h"

namespace weft {
namespace {

using test::data_file;
using test::expect_error;

#if WEFT_TEST_HAVE_ASSETS
#define REQUIRE_ASSETS() (void)0
#else
#define REQUIRE_ASSETS() GTEST_SKIP() << "weft::assets (assimp import) not built"
#endif

#if WEFT_TEST_HAVE_ASSETS
using assets::import_mesh;
using assets::ImportReport;
#endif

// segments and rings from the skirt's "# segments N rings M" comment.
std::pair<int, int> skirt_parameters(const std::filesystem::path& path) {
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream s(line);
        std::string hash, a, b;
        int n = 0, m = 0;
        if (s >> hash >> a >> n >> b >> m && hash == "#" && a == "segments" && b == "rings") return {n, m};
    }
    return {0, 0};
}

std::filesystem::path skirt_path() { return test::source_dir() / "assets" / "meshes" / "skirt.obj"; }

TEST(MeshImport, SkirtSeamIsWelded) {
    REQUIRE_ASSETS();
#if WEFT_TEST_HAVE_ASSETS
    const auto [n, m] = skirt_parameters(skirt_path());
    ASSERT_GT(n, 2);
    ASSERT_GT(m, 0);
    ImportReport report;
    const MeshData mesh = import_mesh(skirt_path(), &report);
    // Assimp splits the seam: (n + 1) columns; the weld closes it to n columns.
    EXPECT_EQ(report.imported_vertices, static_cast<std::size_t>((n + 1) * (m + 1)));
    EXPECT_EQ(report.welded_vertices, static_cast<std::size_t>(m + 1));
    EXPECT_EQ(mesh.welded_vertices, report.welded_vertices);
    EXPECT_EQ(mesh.positions.size(), static_cast<std::size_t>(n * (m + 1)));
    EXPECT_EQ(mesh.triangles.size(), static_cast<std::size_t>(2 * n * m));
    EXPECT_FALSE(report.warnings.empty());

    // It does not fall apart: every edge has at most two triangles, only the waist and hem are
    // boundary, and the mesh is one connected piece.
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
    std::vector<std::uint32_t> parent(mesh.positions.size());
    std::iota(parent.begin(), parent.end(), 0U);
    const auto find = [&](std::uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    for (const Triangle& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = t.v[k], b = t.v[(k + 1) % 3];
            ++edges[{std::min(a, b), std::max(a, b)}];
            parent[find(a)] = find(b);
        }
    std::size_t boundary = 0;
    for (const auto& [e, count] : edges) {
        EXPECT_LE(count, 2);
        if (count == 1) ++boundary;
    }
    EXPECT_EQ(boundary, static_cast<std::size_t>(2 * n));
    std::set<std::uint32_t> roots;
    for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) roots.insert(find(v));
    EXPECT_EQ(roots.size(), 1U);

    // The cooked fabric sees a manifold mesh with nothing dropped.
    const auto fabric = Fabric::cook(mesh);
    EXPECT_EQ(fabric->report().non_manifold_edges, 0U);
    EXPECT_EQ(fabric->report().degenerate_triangles, 0U);
    EXPECT_EQ(fabric->vertex_count(), mesh.positions.size());
#endif
}

TEST(MeshImport, LoadMeshFileGoesThroughTheInstalledLoader) {
    REQUIRE_ASSETS();
    ASSERT_TRUE(test::install_loader());
    const MeshData mesh = load_mesh_file(skirt_path());
    const auto [n, m] = skirt_parameters(skirt_path());
    EXPECT_EQ(mesh.positions.size(), static_cast<std::size_t>(n * (m + 1)));
    EXPECT_GT(mesh.welded_vertices, 0U);
    EXPECT_EQ(mesh.source, skirt_path().string());
}

TEST(MeshImport, Ply) {
    REQUIRE_ASSETS();
    ASSERT_TRUE(test::install_loader());
    const MeshData mesh = load_mesh_file(data_file("quad.ply"));
    EXPECT_EQ(mesh.positions.size(), 4U);
    EXPECT_EQ(mesh.triangles.size(), 2U);
}

TEST(MeshImport, GltfWithEmbeddedBufferAndNodeTransform) {
    REQUIRE_ASSETS();
    ASSERT_TRUE(test::install_loader());
    const MeshData mesh = load_mesh_file(data_file("quad.gltf"));
    ASSERT_EQ(mesh.positions.size(), 4U);
    EXPECT_EQ(mesh.triangles.size(), 2U);
    for (const Vec3d& p : mesh.positions) EXPECT_NEAR(p.y, 1.0, 1e-6);  // the node's translation applied
}

TEST(MeshImport, WriteMeshRoundTrips) {
    REQUIRE_ASSETS();
    ASSERT_TRUE(test::install_loader());
    const MeshData original = load_mesh_file(skirt_path());
    for (const char* ext : {".ply", ".obj"}) {
        SCOPED_TRACE(ext);
        const auto path = std::filesystem::temp_directory_path() / (std::string("weft_test_round_trip") + ext);
        write_mesh(path, original.positions, original.triangles);
        const MeshData back = load_mesh_file(path);
        ASSERT_EQ(back.positions.size(), original.positions.size());
        ASSERT_EQ(back.triangles.size(), original.triangles.size());
        // Importers may reorder vertices; compare each triangle's corner positions as read back.
        // Every position must be found in the original (within float precision), and vice versa by count.
        std::vector<Vec3d> a = original.positions, b = back.positions;
        const auto less = [](const Vec3d& p, const Vec3d& q) {
            return std::tie(p.x, p.y, p.z) < std::tie(q.x, q.y, q.z);
        };
        for (Vec3d& p : a) p = p.cast<float>().cast<double>();  // the PLY stores float32
        std::sort(a.begin(), a.end(), less);
        std::sort(b.begin(), b.end(), less);
        for (std::size_t i = 0; i < a.size(); ++i)
            ASSERT_LT(math::length(a[i] - b[i]), 1e-6) << "vertex " << i;
        std::filesystem::remove(path);
    }
}

TEST(MeshImport, DegenerateTrianglesAreReported) {
    REQUIRE_ASSETS();
    ASSERT_TRUE(test::install_loader());
    const MeshData mesh = load_mesh_file(data_file("degenerate.obj"));
    const auto fabric = Fabric::cook(mesh);
    EXPECT_GE(fabric->report().degenerate_triangles, 1U);
    EXPECT_EQ(fabric->triangle_count(), 4U);
    EXPECT_FALSE(fabric->report().warnings.empty());
}

TEST(MeshImport, NonManifoldEdgesAreReported) {
    REQUIRE_ASSETS();
    ASSERT_TRUE(test::install_loader());
    const MeshData mesh = load_mesh_file(data_file("nonmanifold.obj"));
    EXPECT_EQ(mesh.triangles.size(), 3U);
    const auto fabric = Fabric::cook(mesh);
    EXPECT_EQ(fabric->report().non_manifold_edges, 1U);
    EXPECT_TRUE(fabric->hinges().empty());
    EXPECT_FALSE(fabric->report().warnings.empty());
}

TEST(MeshImport, ErrorsNameTheFile) {
    REQUIRE_ASSETS();
    ASSERT_TRUE(test::install_loader());
    expect_error([] { (void)load_mesh_file(data_file("missing.obj")); }, {"missing.obj", "not found"});
    // A file assimp cannot read: assimp's message comes through, with the file name.
    expect_error([] { (void)load_mesh_file(data_file("bad_syntax.toml")); }, {"bad_syntax.toml", "cannot import mesh"});
}

// Files cut short (a copy interrupted): a binary PLY whose faces index vertices never read was a
// crash inside assimp's post-processing, an OBJ cut in its faces loaded as a smaller cloth. Each is
// now an error naming the file; the whole files still load.
TEST(MeshImport, TruncatedFilesAreErrorsNotCrashesOrSmallerCloth) {
    REQUIRE_ASSETS();
    ASSERT_TRUE(test::install_loader());
    const MeshData skirt = load_mesh_file(skirt_path());
    const auto dir = std::filesystem::temp_directory_path();
    const auto cut = [&](const std::filesystem::path& whole, double keep, const std::string& name) {
        std::ifstream in(whole, std::ios::binary);
        std::ostringstream all;
        all << in.rdbuf();
        const std::string bytes = all.str();
        const auto path = dir / name;
        std::ofstream(path, std::ios::binary) << bytes.substr(0, static_cast<std::size_t>(keep * static_cast<double>(bytes.size())));
        return path;
    };
    for (const char* ext : {".ply", ".obj"}) {
        SCOPED_TRACE(ext);
        const auto whole = dir / (std::string("weft_test_whole") + ext);
        write_mesh(whole, skirt.positions, skirt.triangles);
        EXPECT_EQ(load_mesh_file(whole).triangles.size(), skirt.triangles.size());
        for (const double keep : {0.5, 0.75, 0.9}) {
            const auto path = cut(whole, keep, std::string("weft_test_cut") + ext);
            expect_error([&] { (void)load_mesh_file(path); }, {path.filename().string()});
            std::filesystem::remove(path);
        }
        std::filesystem::remove(whole);
    }
    // The OBJ forms: cut inside the last face line; cut at a line end (its last vertices in no face);
    // a face naming a vertex the file does not have. A whole file without a final newline loads.
    const auto write = [&](const std::string& name, const std::string& text) {
        const auto path = dir / name;
        std::ofstream(path, std::ios::binary) << text;
        return path;
    };
    const std::string quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4";
    expect_error([&] { (void)load_mesh_file(write("weft_test_midline.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3")); },
                 {"weft_test_midline.obj", "middle of a vertex or face line"});
    expect_error([&] { (void)load_mesh_file(write("weft_test_unused.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\n")); },
                 {"weft_test_unused.obj", "1 of its 4 vertices are in no face"});
    expect_error([&] { (void)load_mesh_file(write("weft_test_range.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 7\n")); },
                 {"weft_test_range.obj:4", "face index 7 of 3 vertices"});
    EXPECT_EQ(load_mesh_file(write("weft_test_no_newline.obj", quad)).triangles.size(), 2U);
    // A face line of 0xFF bytes overran assimp's buffer (found by fuzz_mesh_import).
    expect_error([&] { (void)load_mesh_file(write("weft_test_ff.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf\xff\xff\xff 2\t1\n")); },
                 {"weft_test_ff.obj:4", "not an OBJ statement"});
    expect_error([&] { (void)load_mesh_file(write("weft_test_ff2.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\xff\n")); },
                 {"weft_test_ff2.obj:4", "non-ASCII character in a 'f' line"});
    std::filesystem::remove(dir / "weft_test_ff.obj");
    std::filesystem::remove(dir / "weft_test_ff2.obj");
    // PLY headers: assimp loops forever on one that never ends (found by fuzz_mesh_import); an ASCII
    // file with fewer element lines than its header declares is cut short.
    const std::string ply_head = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                                 "element face 2\nproperty list uchar int vertex_indices\n";
    const std::string ply_body = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
    EXPECT_EQ(load_mesh_file(write("weft_test_whole.ply", ply_head + "end_header\n" + ply_body)).triangles.size(), 2U);
    expect_error([&] { (void)load_mesh_file(write("weft_test_endless.ply", ply_head + ply_body)); },
                 {"weft_test_endless.ply:9", "unknown header line"});
    expect_error([&] { (void)load_mesh_file(write("weft_test_no_end.ply", ply_head)); }, {"weft_test_no_end.ply", "no end_header"});
    expect_error([&] { (void)load_mesh_file(write("weft_test_short.ply", ply_head + "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n")); },
                 {"weft_test_short.ply", "declares 6 element lines", "the file has 5"});
    // A malformed face line made assimp abort in its post-processing, and an `end_header` followed by
    // a vertical tab made it loop (both found by fuzz_mesh_import); a file whose first bytes are not
    // its extension's format is refused before assimp tries its other readers on it.
    expect_error([&] { (void)load_mesh_file(write("weft_test_comma.ply", ply_head + "end_header\n" + ply_body.substr(0, 32) + ", 0 2 3\n")); },
                 {"weft_test_comma.ply:15", "',' is not a number"});
    expect_error([&] { (void)load_mesh_file(write("weft_test_index.ply", ply_head + "end_header\n" + ply_body.substr(0, 32) + "3 0 2 9\n")); },
                 {"weft_test_index.ply:15", "vertex index 9 of 4"});
    expect_error([&] { (void)load_mesh_file(write("weft_test_ply_as.glb", ply_head + ply_body)); }, {"weft_test_ply_as.glb", "not a GLB file"});
    expect_error([&] { (void)load_mesh_file(write("weft_test_vtab.ply", ply_head + "end_header\v0 0 -1\n" + ply_body)); },
                 {"weft_test_vtab.ply:9", "control or non-ASCII character"});
    // A form feed between two numbers of a vertex line made assimp's triangulation abort (found by
    // fuzz_mesh_import).
    expect_error([&] { (void)load_mesh_file(write("weft_test_formfeed.ply", ply_head + "end_header\n0 0 0\n1 0 0\n1 1 \f0\n" + ply_body.substr(18))); },
                 {"weft_test_formfeed.ply:12", "control or non-ASCII character in a vertex line"});
    std::filesystem::remove(dir / "weft_test_formfeed.ply");
    std::filesystem::remove(dir / "weft_test_vtab.ply");
    for (const char* f : {"weft_test_comma.ply", "weft_test_index.ply", "weft_test_ply_as.glb"}) std::filesystem::remove(dir / f);
    for (const char* f : {"weft_test_whole.ply", "weft_test_endless.ply", "weft_test_no_end.ply", "weft_test_short.ply"})
        std::filesystem::remove(dir / f);
    // A coordinate beyond the scene's extent, in a cloth's mesh: refused when the scene is built.
    const auto huge = write("weft_test_huge.obj", "v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n");
    SceneDesc scene = load_scene(test::scene_file("hanging"));
    scene.cloths[0].source.kind = ClothSource::Kind::File;
    scene.cloths[0].source.file = huge;
    scene.cloths[0].pins.clear();
    expect_error([&] { (void)build_world(scene, "cpu"); }, {"weft_test_huge.obj", "vertex 1 has coordinate 1e+30"});
    std::filesystem::remove(huge);
    for (const char* f : {"weft_test_midline.obj", "weft_test_unused.obj", "weft_test_range.obj", "weft_test_no_newline.obj"})
        std::filesystem::remove(dir / f);
}

TEST(MeshImport, SceneWithMeshFileBuildsWithReport) {
    REQUIRE_ASSETS();
    ASSERT_TRUE(test::install_loader());
    // degenerate.obj through the whole scene pipeline: loads, cooks with a report, no crash.
    const std::string text = "[[cloth]]\nname = \"bad\"\nmesh = { file = \"degenerate.obj\", scale = 2.0 }\n"
                             "[[cloth.pin]]\nvertices = [0]\n";
    const SceneDesc scene = parse_scene(text, data_file("inline_degenerate.toml"));
    const auto world = build_world(scene);
    const Fabric& f = *world->model().cloths[0].fabric;
    EXPECT_GE(f.report().degenerate_triangles, 1U);
    double max_x = 0.0;
    for (const Vec3d& p : f.rest_positions()) max_x = std::max(max_x, p.x);
    EXPECT_DOUBLE_EQ(max_x, 4.0);  // scale applied
}

}  // namespace
}  // namespace weft
