#pragma once
/// @file
/// Limits a scene must keep, stated once and enforced where scenes and meshes are read.

namespace weft {

/// The largest coordinate, m, at which a scene may place cloth, colliders or motions (each
/// component, after a mesh's scale and placement). Float keeps about 8 mm at 1e5 m, already coarse
/// for cloth a few millimetres thick: keep a scene near its origin. Beyond it a scene is refused
/// with the value named rather than simulated into garbage.
inline constexpr double kWorldExtent = 1e5;

}  // namespace weft
