// The narrow phase's contacts (collision/proximity_contacts.h): a candidate whose gap lies on pinned
// or kinematic vertices is no contact. The stiffness rule makes each movable vertex see 100·m/h², so
// a gap that the free vertices carry only a rounding-size weight of asks them to move by the gap over
// that weight: the cape_runner's runaway solve (1e15 m/s) came from such a pair.
#include <gtest/gtest.h>

#include <vector>

#include "collision/proximity_contacts.h"

namespace weft::collision {
namespace {

/// A cloth triangle (0: (0, 0, 1); 1: (−1, 0, 0); 2: (1, 0, 0)) with corners 1 and 2 pinned unless
/// `free_edge`, and a kinematic vertex 3 1 mm above the point (0, 0, z) of its plane; the contacts of
/// the one vertex–face candidate.
std::vector<ProximityContact> contacts_near_the_edge(double z, bool free_edge) {
    const std::vector<Vec3d> x{{0.0, 0.0, 1.0}, {-1.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 0.001, z}};
    const std::vector<double> inverse_mass{1.0 / 1.4e-4, free_edge ? 1.0 / 1.4e-4 : 0.0, free_edge ? 1.0 / 1.4e-4 : 0.0, 0.0};
    const std::vector<double> thickness{0.005, 0.005, 0.005, 0.0}, friction{0.3, 0.3, 0.3, 0.5};
    const std::vector<Triangle> triangles{Triangle{{0, 1, 2}}};
    const std::vector<VertexFacePair> vf{{3, 0}};
    ProximityInput in;
    in.x0 = x;
    in.x1 = x;
    in.inverse_mass = inverse_mass;
    in.thickness = thickness;
    in.friction = friction;
    in.triangles = triangles;
    in.vf = vf;
    in.h = 1.0 / 60.0;
    std::vector<ProximityContact> out;
    find_proximity_contacts(in, out);
    return out;
}

TEST(ProximityContacts, AGapOnPinnedVerticesIsNoContact) {
    // The control: over the triangle's inside the free corner carries a fifth of the weight.
    const std::vector<ProximityContact> inside = contacts_near_the_edge(0.2, false);
    ASSERT_EQ(inside.size(), 1U);
    EXPECT_NEAR(inside[0].weight[1], -0.2, 1e-12);
    EXPECT_LT(inside[0].stiffness, 1e6) << "100·m/h² over the free corner's weight²";
    // Over the pinned edge, the free corner's weight a rounding error: no contact (the old rule gave
    // it a stiffness of about 1e33 N/m).
    EXPECT_TRUE(contacts_near_the_edge(1e-15, false).empty());
    // The same point with the edge's corners free is a contact.
    EXPECT_EQ(contacts_near_the_edge(1e-15, true).size(), 1U);
}

}  // namespace
}  // namespace weft::collision
