#pragma once
/// @file
/// Skinned meshes for animated characters used as colliders (issue 23, item 2): a joint hierarchy,
/// keyframed clips and linear blend skinning, on the host. A skinned mesh's vertex i at time t is
///     x_i(t) = Σ_k w_ik · (G_j(t) · B_j) · X_i,   j = joint_ik,
/// with X_i its bind-pose position, G_j(t) joint j's world transform (its parent's times its own
/// local pose from the clip) and B_j the inverse of its world transform in the bind pose, so that a
/// clip holding the bind pose gives back X_i. File import (glTF 2.0, FBX) is in weft::assets
/// (`import_skinned_mesh`); libweft itself reads no file format here.
///
/// A mesh collider with a skin and a clip (weft/collider.h) is a character: both backends collide
/// cloth with it (the CUDA backend skins it on the device) and pins can follow its skin vertices or
/// its joints (PinDesc::collider_vertex, collider_joint).

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "weft/fabric.h"
#include "weft/types.h"

namespace weft {

/// A rotation as a unit quaternion w + xi + yj + zk.
struct Quatd {
    double w = 1.0, x = 0.0, y = 0.0, z = 0.0;
};

/// The rotation matrix of `q` (normalised first; a zero quaternion gives the identity).
[[nodiscard]] Mat3d rotation_matrix(Quatd q);
/// Spherical interpolation from `a` (s = 0) to `b` (s = 1) along the shorter arc.
[[nodiscard]] Quatd slerp(Quatd a, Quatd b, double s);

/// An affine map p ↦ linear·p + translation (m).
struct Affine {
    Mat3d linear = Mat3d::identity();
    Vec3d translation{};
    [[nodiscard]] Vec3d apply(Vec3d p) const { return linear * p + translation; }
};
[[nodiscard]] Affine operator*(const Affine& a, const Affine& b);
/// The inverse map; throws weft::Error for a singular linear part.
[[nodiscard]] Affine inverse(const Affine& a);

/// A joint's pose relative to its parent (glTF's TRS order: scale, then rotate, then translate).
struct JointPose {
    Vec3d translation{};  ///< m
    Quatd rotation{};
    Vec3d scale{1.0, 1.0, 1.0};
    [[nodiscard]] Affine matrix() const;
};

struct Joint {
    std::string name;
    std::int32_t parent = -1;  ///< index of an earlier joint, -1 for a root
    JointPose rest;            ///< the local pose a clip without a track for it keeps
    Affine inverse_bind;       ///< world → joint space in the bind pose (B_j)
};

/// One joint's keyframes; an empty list leaves that part of the pose at the joint's rest value.
/// Times in s, increasing; between keys translation and scale are linear, rotation spherical.
struct JointTrack {
    std::uint32_t joint = 0;
    std::vector<double> translation_times, rotation_times, scale_times;
    std::vector<Vec3d> translations, scales;
    std::vector<Quatd> rotations;
};

struct AnimationClip {
    std::string name;
    double duration = 0.0;  ///< s: the last key of any track
    std::vector<JointTrack> tracks;
};

/// A mesh bound to a skeleton: up to four joints per vertex, weights summing to 1.
struct SkinnedMesh {
    MeshData mesh;  ///< bind-pose positions (m) and triangles
    std::vector<std::array<std::uint32_t, 4>> vertex_joints;
    std::vector<std::array<double, 4>> vertex_weights;
    std::vector<Joint> joints;  ///< parents before children
    std::vector<AnimationClip> clips;

    /// The clip called `name`; throws weft::Error listing the clips there are.
    [[nodiscard]] const AnimationClip& clip(const std::string& name) const;
};

/// Checks what skinning relies on, naming `mesh.mesh.source` and the first problem: one joint list
/// and one weight list per vertex, joint indices in range, parents before children, finite
/// non-negative weights summing to 1 within 1e-3 (`normalize_weights` fixes sums), tracks naming
/// existing joints with increasing times and as many values as times. Throws weft::Error.
void validate(const SkinnedMesh& mesh);
/// Scales each vertex's weights to sum to 1 (importers often leave small errors); a vertex with no
/// weight at all is an error (it would collapse to the origin).
void normalize_weights(SkinnedMesh& mesh);

/// The local pose of every joint at time `t` (s) of `clip`; `loop` wraps t into [0, duration).
[[nodiscard]] std::vector<JointPose> sample_clip(const SkinnedMesh& mesh, const AnimationClip& clip, double t, bool loop);
/// Joint j's skinning transform G_j·B_j for the local poses `poses` (one per joint).
[[nodiscard]] std::vector<Affine> skinning_transforms(const SkinnedMesh& mesh, std::span<const JointPose> poses);
/// The skinned positions (m) for `transforms` (skinning_transforms): linear blend skinning.
void skin(const SkinnedMesh& mesh, std::span<const Affine> transforms, std::span<Vec3d> positions);
/// Each joint's pose blended from `from` (s = 0) to `to` (s = 1): translations and scales linearly,
/// rotations along the shorter arc. A cross-fade between two clips' poses.
[[nodiscard]] std::vector<JointPose> blend_poses(std::span<const JointPose> from, std::span<const JointPose> to, double s);
/// The bind pose's local poses (every joint at its rest value).
[[nodiscard]] std::vector<JointPose> rest_poses(const SkinnedMesh& mesh);

}  // namespace weft
