#pragma once
// The viewer's camera moves (window.h): orbit round the target, pan the target and the eye together,
// zoom towards the target. Pure math on render::Camera, so it is tested without a display.
#include "weft/render/render_scene.h"

namespace weft::render::detail {

class OrbitCamera {
public:
    OrbitCamera() = default;
    /// Starts at `home`, which reset() returns to.
    explicit OrbitCamera(const Camera& home) : home_(home), camera_(home) {}

    [[nodiscard]] const Camera& camera() const { return camera_; }
    void reset() { camera_ = home_; }

    /// Turns the eye round the target by a drag of (dx, dy) pixels: right turns the scene to the
    /// right (the eye goes left), down tilts the eye up. Elevation stays within ±85°.
    void orbit(double dx, double dy);
    /// Moves the target and the eye together so that the point at the target's depth follows a drag
    /// of (dx, dy) pixels in a viewport `viewport_height` pixels high.
    void pan(double dx, double dy, int viewport_height);
    /// Moves the eye towards the target (steps > 0, one scroll notch = 10 %) or away; the distance
    /// stays within [near plane × 2, far plane / 2].
    void zoom(double steps);

private:
    Camera home_{};
    Camera camera_{};
};

}  // namespace weft::render::detail
