// Orbit, pan and zoom of the viewer's camera (see orbit_camera.h).
#include "window/orbit_camera.h"

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>

namespace weft::render::detail {
namespace {

constexpr double kRadiansPerPixel = 0.005;  // a 628-pixel drag turns the eye half way round
constexpr double kMaxElevation = 85.0 * 3.14159265358979323846 / 180.0;
constexpr double kZoomPerStep = 0.9;

}  // namespace

void OrbitCamera::orbit(double dx, double dy) {
    const glm::dvec3 target(camera_.target);
    const glm::dvec3 offset = glm::dvec3(camera_.position) - target;
    const double distance = glm::length(offset);
    if (distance <= 0.0) return;
    double azimuth = std::atan2(offset.x, offset.z);
    double elevation = std::asin(std::clamp(offset.y / distance, -1.0, 1.0));
    azimuth -= dx * kRadiansPerPixel;
    elevation = std::clamp(elevation + dy * kRadiansPerPixel, -kMaxElevation, kMaxElevation);
    const glm::dvec3 moved(std::cos(elevation) * std::sin(azimuth), std::sin(elevation),
                           std::cos(elevation) * std::cos(azimuth));
    camera_.position = glm::vec3(target + distance * moved);
}

void OrbitCamera::pan(double dx, double dy, int viewport_height) {
    const glm::dvec3 position(camera_.position);
    const glm::dvec3 target(camera_.target);
    const glm::dvec3 forward = target - position;
    const double distance = glm::length(forward);
    if (distance <= 0.0 || viewport_height < 1) return;
    const glm::dvec3 f = forward / distance;
    // The same up rule as the view matrix (frame_uniforms.cpp).
    const glm::dvec3 world_up = std::abs(f.y) > 0.999 ? glm::dvec3(0.0, 0.0, -1.0) : glm::dvec3(0.0, 1.0, 0.0);
    const glm::dvec3 right = glm::normalize(glm::cross(f, world_up));
    const glm::dvec3 up = glm::cross(right, f);
    // Metres per pixel at the target's depth.
    const double scale = 2.0 * distance * std::tan(glm::radians(static_cast<double>(camera_.fov_degrees)) / 2.0) /
                         static_cast<double>(viewport_height);
    const glm::dvec3 shift = (-dx * right + dy * up) * scale;
    camera_.position = glm::vec3(position + shift);
    camera_.target = glm::vec3(target + shift);
}

void OrbitCamera::zoom(double steps) {
    const glm::dvec3 target(camera_.target);
    const glm::dvec3 offset = glm::dvec3(camera_.position) - target;
    const double distance = glm::length(offset);
    if (distance <= 0.0) return;
    const double lo = 2.0 * static_cast<double>(camera_.near_plane);
    const double hi = std::max(lo, 0.5 * static_cast<double>(camera_.far_plane));
    const double wanted = std::clamp(distance * std::pow(kZoomPerStep, steps), lo, hi);
    camera_.position = glm::vec3(target + offset * (wanted / distance));
}

}  // namespace weft::render::detail
