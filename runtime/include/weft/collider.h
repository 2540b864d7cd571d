#pragma once
/// @file
/// Analytic colliders: plane, sphere, capsule and box, static or following a `Motion`.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "weft/fabric.h"
#include "weft/motion.h"
#include "weft/skinning.h"

namespace weft {

/// Plane, sphere, capsule and box are analytic (penalty contacts in the solve); a mesh collider is a
/// triangle mesh (a body, a chair) that goes through the cloth collision pipeline (proximity
/// contacts, CCD and impact zones) as kinematic geometry.
enum class ColliderShape : std::uint8_t { Plane, Sphere, Capsule, Box, Mesh };

/// An analytic collider. Its local frame follows `motion` (origin, rotation, animation).
/// Plane: passes through the frame origin with normal = local +Y.
/// Sphere: radius about the origin. Capsule: segment from −half_height to +half_height along local Y,
/// swept by radius. Box: half_extents along local X, Y, Z.
struct ColliderDesc {
    std::string name;
    ColliderShape shape = ColliderShape::Plane;
    Motion motion{};
    double radius = 0.5;        ///< m (sphere, capsule)
    double half_height = 0.5;   ///< m (capsule)
    Vec3d half_extents{0.5, 0.5, 0.5};  ///< m (box)
    double friction = -1.0;     ///< Coulomb coefficient; negative: use the cloth material's
    /// Mesh colliders only: the triangles in the collider's local frame (m), placed at time t by
    /// `motion.at(t)`. Closed or open; the cloth keeps its contact thickness from either side.
    std::shared_ptr<const MeshData> mesh;
    /// Mesh colliders only: an animated character (weft/skinning.h). Its clip `clip` bends the mesh
    /// (the skin's bind-pose mesh, which `mesh` then is) in the collider's local frame, which
    /// `motion` places in the world as for a rigid mesh (the character's root motion).
    std::shared_ptr<const SkinnedMesh> skin;
    std::string clip;          ///< the skin's clip to play; empty: the bind pose
    double clip_speed = 1.0;   ///< clip seconds per simulated second (≥ 0)
    bool clip_loop = true;     ///< wrap the clip; otherwise hold its last key
    /// Simulated time (s) at which the clip's time 0 falls: the clip's time at t is
    /// clip_speed·max(0, t − clip_start). A game sets it when it switches clips (a jump starts now).
    double clip_start = 0.0;
    /// A cross-fade from the clip that played before (a game switching clips mid-motion): over
    /// `clip_fade` seconds from `fade_start` (simulated time, s) the pose blends from
    /// `fade_from_clip` (played on with its own speed, start and loop; empty: the bind pose) to
    /// `clip`'s. 0: no fade, the switch is a cut, and a cut moves the body as far in one step as the
    /// two poses differ: cloth pinned to it or held against it cannot follow (switch_clip sets these).
    double clip_fade = 0.0;
    double fade_start = 0.0;
    std::string fade_from_clip;
    double fade_from_speed = 1.0;
    bool fade_from_loop = true;
    double fade_from_start = 0.0;
    /// When not empty (one local pose a joint of the skin), the fade starts from this pose, held
    /// still, instead of `fade_from_clip`: switch_clip sets it when it interrupts a fade, since
    /// what showed then was a blend of two clips, and fading from either alone would jump the body.
    std::vector<JointPose> fade_from_pose;
    [[nodiscard]] bool is_analytic() const { return shape != ColliderShape::Mesh; }
    /// Whether the collider fades out of something other than the bind pose.
    [[nodiscard]] bool fades_from_motion() const { return clip_fade > 0.0 && (!fade_from_clip.empty() || !fade_from_pose.empty()); }
    /// Whether the collider can move: its motion is not static, or its skin plays a clip.
    [[nodiscard]] bool moves() const { return !motion.is_static() || (skin != nullptr && (!clip.empty() || fades_from_motion())); }
};

/// Switches `collider`'s clip at simulated time `t` (s) to `clip` (empty: the bind pose), whose
/// time at t is `clip_time_now` (s; 0 plays it from its start), cross-fading from what played until
/// now over `fade` seconds (0: a cut). What played before keeps playing under the fade; a switch
/// during a fade fades from the blend shown at t, held still (`fade_from_pose`). Throws
/// weft::Error for an unknown clip, a negative fade or speed, or a time into the clip at speed 0.
void switch_clip(ColliderDesc& collider, const std::string& clip, double t, double fade, bool loop = true,
                 double speed = 1.0, double clip_time_now = 0.0);
/// Changes the clip's speed at simulated time `t` (s) without a jump in its time: `clip_start` moves
/// so that the clip is where it was at t. Setting `clip_speed` alone rescales all the time played
/// since `clip_start`, which jumps the pose by as much as the speed changed times that time.
/// `speed` > 0 (at 0 the clip's time is 0 whatever the start: its first pose, not a pause).
void set_clip_speed(ColliderDesc& collider, double t, double speed);

/// A mesh collider's vertices in the world at time `t` (s): skinned by its clip where it has a skin,
/// then placed by its motion. `out` holds one position a mesh vertex (m).
void collider_mesh_positions(const ColliderDesc& collider, double t, std::span<Vec3d> out);

/// Whether a mesh collider is bent by a clip (it has a skin and plays a clip, or fades out of one);
/// otherwise its mesh moves rigidly with its motion.
[[nodiscard]] inline bool plays_clip(const ColliderDesc& c) {
    return c.skin != nullptr && (!c.clip.empty() || c.fades_from_motion());
}

/// The clip time of `collider` at simulated time `t` (s): clip_speed·max(0, t − clip_start).
[[nodiscard]] inline double clip_time(const ColliderDesc& c, double t) {
    return c.clip_speed * (t > c.clip_start ? t - c.clip_start : 0.0);
}

/// The maps that place a mesh collider's vertices in the world at time `t` (s), for backends that
/// skin on their own: one a joint, A_j = F(t)·G_j(t)·B_j (F the motion's frame), for a collider with
/// a skin (its clip's pose, or the bind pose while it plays none, so that a game may switch clips
/// between steps), vertex i then being Σ_k w_ik·A_{j_ik}·X_i (X_i its bind-pose position); for a
/// rigid mesh the one map F(t), applied to every vertex. `out` is resized.
void collider_mesh_transforms(const ColliderDesc& collider, double t, std::vector<Affine>& out);

}  // namespace weft
