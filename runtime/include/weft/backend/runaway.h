#pragma once
// The speed that tells a runaway solve from motion, shared by the backends.

namespace weft {

/// A free cloth vertex faster than this after a solve (m/s) means the solve ran away: the backends
/// drop it and the free vertices keep their start velocity through the substep (the collision
/// stages still sweep that motion), counted in StepStats::runaway_solves. Ten kilometres a second:
/// above the speed of sound in steel, so no cloth a game or a tool moves, struck or not, comes near
/// it, and a solve of a system singular in the backend's precision (a very light vertex under stiff
/// springs in float: |Δv| 1.3·10¹⁵ m/s in the cape_runner's frame 390, docs/results.md) lands far
/// above it.
inline constexpr double kRunawaySpeed = 1e4;

}  // namespace weft
