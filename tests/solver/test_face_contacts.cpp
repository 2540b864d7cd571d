// Collider contacts at the cloth triangles' centroids (SolverSettings::face_contacts,
// weft/physics/implicit_terms.h: face_collider_terms): a coarse sheet draped over a ball rests on
// its vertices alone, and the ball shows through the middle of its triangles (the control, which
// proves the scene tests something); with face contacts every triangle's centroid stays outside the
// ball too, with no energy gained and the same vertex-contact behaviour elsewhere.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "face_contacts_drape.h"

namespace weft {
namespace {

using test::drape_coarse_sheet;

TEST(FaceContacts, ACoarseSheetOverABallKeepsItsTrianglesOffTheBall) {
    const test::Draped vertices_only = drape_coarse_sheet("cpu", false), with_faces = drape_coarse_sheet("cpu", true);
    std::printf("vertex contacts only: centroid gap %.4f m, vertex gap %.4f m; with face contacts: %.4f m, %.4f m "
                "(%d contacts)\n",
                vertices_only.centroid_gap, vertices_only.vertex_gap, with_faces.centroid_gap, with_faces.vertex_gap,
                with_faces.collider_contacts);
    // The control: vertices held off the ball (the middle cell's tension presses its corners through
    // the contact thickness onto the surface), a centroid well inside it.
    EXPECT_GT(vertices_only.vertex_gap, -0.001);
    EXPECT_LT(vertices_only.centroid_gap, -0.01) << "the scene no longer shows the sag it tests";
    // Face contacts: the centroids outside too (within a tenth of the 5 mm contact thickness).
    EXPECT_GT(with_faces.centroid_gap, -0.0005);
    EXPECT_GT(with_faces.vertex_gap, -0.0005);
    EXPECT_GT(with_faces.collider_contacts, vertices_only.collider_contacts) << "centroid contacts are counted";
    // Energy: the control, with the ball through the sheet's middle cell and its corners sliding over
    // the ball, gains in tens of substeps (23 of 180 when measured); held off the ball, the sheet
    // gains in no more than a few (2: the first contacts of the falling sheet).
    EXPECT_TRUE(vertices_only.finite);
    EXPECT_TRUE(with_faces.finite);
    EXPECT_LE(with_faces.gained, 3);
    EXPECT_LT(with_faces.gained, vertices_only.gained);
    // What the backend reports (the editor's contact marks): the solver's own active contacts. Vertex
    // contacts only: one per vertex in a contact, so as many as the stats count. With face contacts
    // also the corners of the triangles whose centroids touch: more vertices.
    for (const test::Draped* d : {&vertices_only, &with_faces}) {
        ASSERT_TRUE(d->reported);
        EXPECT_TRUE(std::is_sorted(d->touching.begin(), d->touching.end()));
        EXPECT_TRUE(std::adjacent_find(d->touching.begin(), d->touching.end()) == d->touching.end());
        for (const std::uint32_t v : d->touching) EXPECT_LT(v, 16U) << "cloth-local ids of the 4×4 vertices";
    }
    std::printf("vertices reported in a collider contact: %zu without face contacts, %zu with\n", vertices_only.touching.size(),
                with_faces.touching.size());
    EXPECT_EQ(vertices_only.touching.size(), static_cast<std::size_t>(vertices_only.collider_contacts));
    EXPECT_FALSE(vertices_only.touching.empty());
    for (const std::uint32_t corner : {5U, 6U, 9U, 10U})  // the middle cell, whose centroids rest on the ball
        EXPECT_TRUE(std::binary_search(with_faces.touching.begin(), with_faces.touching.end(), corner)) << corner;
    const test::Draped in_float = drape_coarse_sheet("cpu", true, Precision::Float);
    std::printf("with face contacts in float: centroid gap %.4f m, %d substeps gained\n", in_float.centroid_gap, in_float.gained);
}

}  // namespace
}  // namespace weft
