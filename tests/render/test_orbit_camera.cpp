// The viewer's camera moves (render/src/window/orbit_camera.h), without a window.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/glm.hpp>

#include "window/orbit_camera.h"

namespace weft::render::detail {
namespace {

Camera start() {
    Camera c;
    c.position = {0.0F, 1.0F, 4.0F};
    c.target = {0.0F, 1.0F, 0.0F};
    return c;
}

TEST(OrbitCamera, OrbitKeepsDistanceAndTarget) {
    OrbitCamera cam(start());
    cam.orbit(200.0, -120.0);
    EXPECT_NEAR(glm::length(cam.camera().position - cam.camera().target), 4.0F, 1e-4F);
    EXPECT_EQ(cam.camera().target, start().target);
    // Dragging right turns the eye to the left of where it looked from (−x seen from +z).
    EXPECT_LT(cam.camera().position.x, 0.0F);
    // Dragging up (dy < 0) lowers the eye.
    EXPECT_LT(cam.camera().position.y, 1.0F);
}

TEST(OrbitCamera, ElevationStaysBelowThePole) {
    OrbitCamera cam(start());
    cam.orbit(0.0, 10000.0);
    const glm::vec3 d = glm::normalize(cam.camera().position - cam.camera().target);
    EXPECT_LT(d.y, std::sin(glm::radians(85.1F)));
    EXPECT_GT(d.y, std::sin(glm::radians(84.9F)));
}

TEST(OrbitCamera, PanMovesEyeAndTargetTogether) {
    OrbitCamera cam(start());
    cam.pan(100.0, 0.0, 480);
    const Camera& c = cam.camera();
    EXPECT_EQ(c.position - c.target, start().position - start().target);
    // Dragging right moves the scene right: the camera goes left (−x), by the width of 100 pixels at
    // the target's depth.
    const float metres = 100.0F * 2.0F * 4.0F * std::tan(glm::radians(45.0F) / 2.0F) / 480.0F;
    EXPECT_NEAR(c.target.x, -metres, 1e-5F);
    EXPECT_NEAR(c.target.y, 1.0F, 1e-6F);
}

TEST(OrbitCamera, ZoomIsClampedAndResetReturnsHome) {
    OrbitCamera cam(start());
    cam.zoom(1.0);
    EXPECT_NEAR(glm::length(cam.camera().position - cam.camera().target), 3.6F, 1e-4F);
    cam.zoom(1000.0);
    EXPECT_NEAR(glm::length(cam.camera().position - cam.camera().target), 2.0F * start().near_plane, 1e-5F);
    cam.zoom(-10000.0);
    EXPECT_NEAR(glm::length(cam.camera().position - cam.camera().target), 0.5F * start().far_plane, 1e-2F);
    cam.reset();
    EXPECT_EQ(cam.camera().position, start().position);
    EXPECT_EQ(cam.camera().target, start().target);
}

}  // namespace
}  // namespace weft::render::detail
