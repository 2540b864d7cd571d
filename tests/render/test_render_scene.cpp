// The API-neutral parts of the renderer: PNG files and image comparisons (what the image tests rely
// on to fail), the scene built from a world, the collider meshes and the cloth normals.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "render_test_scenes.h"
#include "weft/backend/model.h"
#include "weft/error.h"
#include "weft/render/frame_sequence.h"
#include "weft/render/image.h"
#include "weft/render/render_scene.h"

namespace weft::render {
namespace {

std::filesystem::path temp_file(const std::string& name) {
    return std::filesystem::temp_directory_path() / ("weft_render_test_" + std::to_string(::getpid()) + "_" + name);
}

Image gradient(int w, int h) {
    Image im(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::uint8_t* p = im.pixel(x, y);
            p[0] = static_cast<std::uint8_t>(x * 255 / std::max(1, w - 1));
            p[1] = static_cast<std::uint8_t>(y * 255 / std::max(1, h - 1));
            p[2] = static_cast<std::uint8_t>((x + y) % 256);
            p[3] = 255;
        }
    return im;
}

TEST(Image, PngRoundTripKeepsEveryByte) {
    const Image a = gradient(37, 23);  // odd sizes: no row padding assumed
    const auto file = temp_file("roundtrip.png");
    write_png(file, a);
    const Image b = read_png(file);
    std::filesystem::remove(file);
    ASSERT_EQ(b.width, 37);
    ASSERT_EQ(b.height, 23);
    EXPECT_EQ(a.rgba, b.rgba);
}

TEST(Image, BadFilesAreErrorsNamingTheFile) {
    const auto missing = temp_file("missing.png");
    try {
        (void)read_png(missing);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
    }
    const auto text = temp_file("not_a_png.png");
    std::ofstream(text) << "this is not a picture";
    try {
        (void)read_png(text);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("not a PNG"), std::string::npos) << e.what();
    }
    std::filesystem::remove(text);
    EXPECT_THROW(write_png("/nonexistent-dir/x.png", gradient(4, 4)), Error);
    EXPECT_THROW(write_png(temp_file("empty.png"), Image{}), Error);
}

TEST(Image, ComparisonSeesWhatDiffers) {
    const Image a = gradient(64, 32);
    Image b = a;
    const ImageDifference same = compare(a, b);
    EXPECT_EQ(same.max, 0);
    EXPECT_EQ(same.mean, 0.0);
    b.pixel(10, 10)[1] = static_cast<std::uint8_t>(b.pixel(10, 10)[1] ^ 0x80);  // one channel by 128
    const ImageDifference one = compare(a, b, 16);
    EXPECT_EQ(one.max, 128);
    EXPECT_DOUBLE_EQ(one.fraction_over, 1.0 / (64.0 * 32.0));
    EXPECT_NEAR(one.mean, 128.0 / (3.0 * 64.0 * 32.0), 1e-12);
    EXPECT_THROW((void)compare(a, gradient(32, 64)), Error);
}

TEST(Image, BlankFramesHaveNoLuminanceSpread) {
    Image black(50, 40);
    EXPECT_EQ(luminance_spread(black), 0.0);
    Image grey(50, 40);
    std::fill(grey.rgba.begin(), grey.rgba.end(), 128);
    EXPECT_NEAR(luminance_spread(grey), 0.0, 1e-9);
    EXPECT_GT(luminance_spread(gradient(50, 40)), 30.0);
}

TEST(Image, ContactSheetTilesAndShrinks) {
    std::vector<Image> frames;
    for (int k = 0; k < 5; ++k) {
        Image im(40, 20);
        std::fill(im.rgba.begin(), im.rgba.end(), static_cast<std::uint8_t>(40 * k));
        frames.push_back(im);
    }
    const Image sheet = contact_sheet(frames, 3, 2);
    ASSERT_EQ(sheet.width, 3 * 20);
    ASSERT_EQ(sheet.height, 2 * 10);
    EXPECT_EQ(sheet.pixel(0, 0)[0], 0);         // frame 0, top left
    EXPECT_EQ(sheet.pixel(45, 5)[0], 80);       // frame 2, top right
    EXPECT_EQ(sheet.pixel(25, 15)[0], 160);     // frame 4, second row, middle
    frames.push_back(Image(10, 10));
    EXPECT_THROW((void)contact_sheet(frames, 3, 2), Error);
}

TEST(RenderScene, ClothsShareOneBufferAndCollidersBecomeMeshes) {
    const test::TestScene t = test::sheet_over_ball();
    const RenderScene& s = t.scene;
    ASSERT_EQ(s.cloths.size(), 1U);
    EXPECT_EQ(s.cloth_vertices, 17U * 17U);
    EXPECT_EQ(s.cloths[0].index_count, 16U * 16U * 2U * 3U);
    for (const std::uint32_t i : s.cloth_indices) ASSERT_LT(i, s.cloth_vertices);
    // The ball and the floor: the floor is the ground grid, so no second ground is added.
    ASSERT_EQ(s.colliders.size(), 2U);
    EXPECT_EQ(s.colliders[0].grid_spacing, 0.0F);
    EXPECT_GT(s.colliders[1].grid_spacing, 0.0F);
    // The shadow box holds the cloth and the ball and reaches the ground.
    for (const RenderVertex& v : t.vertices)
        for (int c = 0; c < 3; ++c) {
            EXPECT_GE(v.position[c], s.bounds_min[c]);
            EXPECT_LE(v.position[c], s.bounds_max[c]);
        }
    EXPECT_LE(s.bounds_min.y, 0.0F);
    EXPECT_EQ(t.frame.collider_models.size(), s.colliders.size());
    EXPECT_FLOAT_EQ(t.frame.collider_models[0][3][0], 0.3F);  // the ball's translation
}

TEST(RenderScene, EdgeIndicesListEachEdgeOnceWhereItFirstAppears) {
    // Two triangles sharing the edge 1–2: five edges, smaller index first, in order of appearance.
    const std::vector<std::uint32_t> triangles{0, 1, 2, 2, 1, 3};
    EXPECT_EQ(edge_indices(triangles), (std::vector<std::uint32_t>{0, 1, 1, 2, 0, 2, 1, 3, 2, 3}));
    EXPECT_TRUE(edge_indices({}).empty());
    EXPECT_THROW((void)edge_indices(std::vector<std::uint32_t>{0, 1, 2, 3}), Error);
}

TEST(RenderScene, WorldWithoutAPlaneGetsAGroundGrid) {
    World world;
    world.add_cloth(ClothDesc{.name = "a", .fabric = Fabric::cook(make_grid(1.0, 1.0, 4, 4), {})});
    world.add_cloth(ClothDesc{.name = "b", .fabric = Fabric::cook(make_grid(1.0, 1.0, 2, 2), {})});
    const RenderScene s = make_render_scene(world, CameraDesc{});
    ASSERT_EQ(s.cloths.size(), 2U);
    EXPECT_EQ(s.cloths[1].first_vertex, 25U);
    EXPECT_EQ(s.cloth_vertices, 25U + 9U);
    EXPECT_NE(s.cloths[0].front_colour, s.cloths[1].front_colour);
    ASSERT_EQ(s.colliders.size(), 1U);
    EXPECT_EQ(s.colliders[0].name, "ground");
    EXPECT_GT(s.colliders[0].grid_spacing, 0.0F);
}

TEST(RenderScene, ClothNormalsAreUnitAndFaceTheWindingSide) {
    const test::TestScene t = test::sheet_over_ball();
    // The sheet is the XZ grid tilted 30° about X: every normal is the rotated ±Y.
    const glm::vec3 expected = glm::vec3(0.0F, std::cos(0.5235988F), std::sin(0.5235988F));
    float first_sign = 0.0F;
    for (const RenderVertex& v : t.vertices) {
        const glm::vec3 n(v.normal[0], v.normal[1], v.normal[2]);
        EXPECT_NEAR(glm::length(n), 1.0F, 1e-5F);
        const float d = glm::dot(n, expected);
        EXPECT_NEAR(std::abs(d), 1.0F, 1e-4F);
        if (first_sign == 0.0F) first_sign = d;
        EXPECT_GT(d * first_sign, 0.0F) << "normals of one flat sheet point the same way";
    }
}

// Analytic collider meshes: normals point out of the shape and triangles wind counter-clockwise
// seen from outside (the front face the shader lights).
void expect_outward(const RenderMesh& m, glm::vec3 half_axis_extent) {
    ASSERT_FALSE(m.indices.empty());
    for (const RenderVertex& v : m.vertices) {
        const glm::vec3 p(v.position[0], v.position[1], v.position[2]);
        const glm::vec3 n(v.normal[0], v.normal[1], v.normal[2]);
        // Outward from the nearest point of the shape's axis segment (capsule) or centre.
        const glm::vec3 axis_point(0.0F, std::clamp(p.y, -half_axis_extent.y, half_axis_extent.y), 0.0F);
        EXPECT_GT(glm::dot(n, p - axis_point), 0.0F);
        EXPECT_NEAR(glm::length(n), 1.0F, 1e-5F);
    }
    int outward = 0, degenerate = 0;
    for (std::size_t k = 0; k < m.indices.size(); k += 3) {
        const auto p = [&](std::size_t i) {
            const RenderVertex& v = m.vertices[m.indices[k + i]];
            return glm::vec3(v.position[0], v.position[1], v.position[2]);
        };
        const glm::vec3 area = glm::cross(p(1) - p(0), p(2) - p(0));
        if (glm::length(area) < 1e-9F) {
            ++degenerate;  // the poles' fan
            continue;
        }
        const glm::vec3 c = (p(0) + p(1) + p(2)) / 3.0F;
        const glm::vec3 axis_point(0.0F, std::clamp(c.y, -half_axis_extent.y, half_axis_extent.y), 0.0F);
        if (glm::dot(area, c - axis_point) > 0.0F) ++outward;
    }
    EXPECT_EQ(outward + degenerate, static_cast<int>(m.indices.size() / 3));
}

// A character playing a clip is a deforming collider: its mesh is drawn in world space with an
// identity model matrix, and each frame's vertices are the collision pipeline's placement of it.
TEST(RenderScene, ACharacterPlayingAClipDeformsEachFrame) {
    const test::TestScene t = test::sliding_box();
    const RenderScene& s = t.scene;
    ASSERT_EQ(s.colliders.size(), 2U);  // the box, then the floor (the ground grid)
    const std::size_t box = 0;
    ASSERT_EQ(s.colliders[box].name, "box");
    ASSERT_TRUE(s.colliders[box].deforms);
    EXPECT_FALSE(s.colliders[1].deforms);
    EXPECT_EQ(s.deforming_vertices, 8U);
    const std::vector<glm::mat4> models = collider_models(s, t.world->model(), 0.7);
    EXPECT_EQ(models[box], glm::mat4(1.0F));
    std::vector<RenderVertex> v;
    deforming_collider_vertices(s, t.world->model(), 0.7, v);
    ASSERT_EQ(v.size(), 8U);
    std::vector<Vec3d> placed(8);
    collider_mesh_positions(t.world->model().colliders[0], 0.7, placed);
    for (std::size_t i = 0; i < 8; ++i)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[i].position[c], placed[i][c], 1e-6) << "vertex " << i;
    EXPECT_NEAR(v[0].position[0], -0.2 + 0.2, 1e-6);  // x = −0.2 slid 0.7 of the way from −0.5 to +0.5
    // The pose at t = 0 is the scene's own mesh (what a renderer draws before the first frame).
    deforming_collider_vertices(s, t.world->model(), 0.0, v);
    for (std::size_t i = 0; i < 8; ++i) EXPECT_EQ(v[i].position[0], s.colliders[box].mesh.vertices[i].position[0]);
}

TEST(RenderScene, ColliderMeshesFaceOutwards) {
    expect_outward(sphere_mesh(0.5F), glm::vec3(0.0F));
    expect_outward(capsule_mesh(0.2F, 0.4F), glm::vec3(0.0F, 0.4F, 0.0F));
    expect_outward(box_mesh({0.1F, 0.2F, 0.3F}), glm::vec3(0.0F));
    const RenderMesh plane = plane_mesh(2.0F);
    ASSERT_EQ(plane.indices.size(), 6U);
    const auto& v = plane.vertices;
    const glm::vec3 a(v[0].position[0], v[0].position[1], v[0].position[2]);
    const glm::vec3 b(v[1].position[0], v[1].position[1], v[1].position[2]);
    const glm::vec3 c(v[2].position[0], v[2].position[1], v[2].position[2]);
    EXPECT_GT(glm::cross(b - a, c - a).y, 0.0F) << "the ground faces up";
}

// Numbered frames, and the MP4 made from them where ffmpeg is installed (skipped, saying so,
// where it is not): ffprobe finds as many frames as were written, at the frame rate asked for,
// padded to even sizes for yuv420p.
TEST(FrameSequence, WritesNumberedFramesAndTheirVideo) {
    const std::filesystem::path folder = temp_file("sequence");
    std::filesystem::remove_all(folder);
    FrameSequence frames(folder);
    EXPECT_EQ(frames.pattern(), (folder / "frame_%04d.png").string());
    frames.write(0, gradient(33, 17));
    EXPECT_EQ(frames.encode_mp4(30).note, "fewer than 2 frames");
    for (int k = 1; k < 12; ++k) frames.write(k, gradient(33, 17));
    EXPECT_EQ(frames.frames_written(), 12);
    EXPECT_TRUE(std::filesystem::exists(folder / "frame_0011.png"));
    EXPECT_EQ(read_png(folder / "frame_0007.png").rgba, gradient(33, 17).rgba);

    if (std::system("command -v ffmpeg > /dev/null 2>&1 && command -v ffprobe > /dev/null 2>&1") != 0) {
        EXPECT_EQ(frames.encode_mp4(30).note, "ffmpeg not installed");
        std::filesystem::remove_all(folder);
        GTEST_SKIP() << "ffmpeg/ffprobe not installed: the MP4 is not made here";
    }
    const FrameSequence::Video video = frames.encode_mp4(24);
    ASSERT_FALSE(video.file.empty()) << video.note;
    EXPECT_EQ(video.file, folder / "capture.mp4");
    const std::string probe = "ffprobe -v error -select_streams v:0 -count_frames -show_entries "
                              "stream=nb_read_frames,width,height,r_frame_rate -of csv=p=0 '" +
                              video.file.string() + "'";
    FILE* pipe = ::popen(probe.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    char line[256] = {};
    const bool read = std::fgets(line, sizeof line, pipe) != nullptr;
    ::pclose(pipe);
    ASSERT_TRUE(read) << probe;
    // width,height,r_frame_rate,nb_read_frames
    EXPECT_EQ(std::string(line).substr(0, std::string(line).find_last_not_of("\r\n") + 1), "34,18,24/1,12") << probe;
    std::filesystem::remove_all(folder);
}

}  // namespace
}  // namespace weft::render
