#pragma once
// The player's character: where it stands, where it faces, how it moves, and how it tells Weft.
//
// Weft moves kinematic things with a `weft::Motion`: a frame that is a function of the simulated
// time. A game character is not a function of time known in advance, so every frame the runner
// rewrites its motion as the straight piece from where it is now to where it will be at the end of
// the frame: the next step then sees the body's exact pose and velocity at both ends, which is what
// the contacts (and the cloth pinned to the shoulders) need.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "weft/motion.h"

namespace cape_runner {

/// What the player asks for this frame (keyboard, gamepad or a script).
struct Controls {
    double forward = 0.0;  // −1 … 1
    double turn = 0.0;     // −1 (left) … 1 (right)
    bool jump = false;
    bool run = false;
};

class Runner {
public:
    static constexpr double kWalkSpeed = 2.5;   // m/s
    static constexpr double kRunSpeed = 5.0;    // m/s
    static constexpr double kTurnRate = 2.5;    // rad/s
    static constexpr double kJumpSpeed = 4.2;   // m/s upwards at take-off: a jump of about 0.9 m
    static constexpr double kGravity = 9.81;    // m/s²
    static constexpr double kLevelHalfSize = 14.0;  // m: the level's edge, where the runner stops

    explicit Runner(weft::Vec3d start) : position_(start) {}

    /// Where the runner will be `dt` seconds from now, given `controls`.
    void advance(const Controls& c, double dt) {
        previous_position_ = position_;
        previous_heading_ = heading_;
        heading_ -= std::clamp(c.turn, -1.0, 1.0) * kTurnRate * dt;  // right turns clockwise seen from above
        const double speed = std::clamp(c.forward, -1.0, 1.0) * (c.run ? kRunSpeed : kWalkSpeed);
        position_ += speed * dt * facing();
        if (c.jump && on_ground()) vertical_speed_ = kJumpSpeed;
        vertical_speed_ -= kGravity * dt;
        position_.y += vertical_speed_ * dt;
        if (position_.y <= 0.0) {  // landed
            position_.y = 0.0;
            vertical_speed_ = 0.0;
        }
        position_.x = std::clamp(position_.x, -kLevelHalfSize, kLevelHalfSize);
        position_.z = std::clamp(position_.z, -kLevelHalfSize, kLevelHalfSize);
    }

    /// The motion that carries the runner's frame from its last pose, at time `t` (s), to its
    /// current one at `t + dt`: a constant velocity and turn rate over the frame.
    [[nodiscard]] weft::Motion motion(double t, double dt) const {
        weft::Motion m;
        m.linear_velocity = (position_ - previous_position_) / dt;
        m.origin = previous_position_ - t * m.linear_velocity;  // at(t) is the last pose
        const double turn_rate = (heading_ - previous_heading_) / dt;
        m.angular_velocity = {0.0, turn_rate, 0.0};
        m.initial_rotation = yaw(previous_heading_ - turn_rate * t);
        return m;
    }

    /// The runner's frame now: feet at the origin, y up, facing +z.
    [[nodiscard]] weft::Transform frame() const { return {yaw(heading_), position_}; }
    [[nodiscard]] weft::Vec3d position() const { return position_; }
    [[nodiscard]] weft::Vec3d facing() const { return {std::sin(heading_), 0.0, std::cos(heading_)}; }
    [[nodiscard]] bool on_ground() const { return position_.y <= 0.0 && vertical_speed_ <= 0.0; }

private:
    static weft::Mat3d yaw(double angle) { return weft::rotation_from_vector({0.0, angle, 0.0}); }

    weft::Vec3d position_{}, previous_position_{};
    double heading_ = 0.0, previous_heading_ = 0.0;  // rad about +y; 0 faces +z
    double vertical_speed_ = 0.0;                   // m/s
};

}  // namespace cape_runner
