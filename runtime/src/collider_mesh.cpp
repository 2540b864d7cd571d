// A mesh collider's vertices at a time: its skin's clip, then its rigid motion (weft/collider.h).
#include <cmath>
#include <string>
#include <vector>

#include "weft/collider.h"
#include "weft/error.h"

namespace weft {
namespace {

/// The local joint poses of a skinned collider at time t: its clip (or the bind pose), blended from
/// the clip it fades out of while the fade lasts.
std::vector<JointPose> collider_poses(const ColliderDesc& c, double t) {
    const SkinnedMesh& m = *c.skin;
    const auto play = [&](const std::string& clip, double speed, double start, bool loop) {
        if (clip.empty()) return rest_poses(m);
        return sample_clip(m, m.clip(clip), speed * (t > start ? t - start : 0.0), loop);
    };
    std::vector<JointPose> poses = play(c.clip, c.clip_speed, c.clip_start, c.clip_loop);
    if (c.clip_fade > 0.0 && t < c.fade_start + c.clip_fade) {
        const double s = t > c.fade_start ? (t - c.fade_start) / c.clip_fade : 0.0;
        poses = c.fade_from_pose.empty()
                    ? blend_poses(play(c.fade_from_clip, c.fade_from_speed, c.fade_from_start, c.fade_from_loop), poses, s)
                    : blend_poses(c.fade_from_pose, poses, s);
    }
    return poses;
}

}  // namespace

void switch_clip(ColliderDesc& c, const std::string& clip, double t, double fade, bool loop, double speed,
                 double clip_time_now) {
    if (!(fade >= 0.0) || !std::isfinite(fade) || !(speed >= 0.0) || !std::isfinite(speed) || !std::isfinite(clip_time_now))
        throw Error("collider '" + c.name + "': switch_clip needs a finite fade ≥ 0 s and speed ≥ 0 (got fade " +
                    std::to_string(fade) + ", speed " + std::to_string(speed) + ")");
    // At speed 0 the clip's time is 0 whatever clip_start says: no later time can be asked for.
    if (speed == 0.0 && clip_time_now != 0.0)
        throw Error("collider '" + c.name + "': switch_clip at speed 0 plays the clip's first pose, not " +
                    std::to_string(clip_time_now) + " s into it");
    if (c.skin != nullptr && !clip.empty()) (void)c.skin->clip(clip);  // names the clips there are
    // Interrupting a fade: what shows at t is a blend of two clips, which neither clip alone carries
    // on from (the rigged runner's legs jumped 0.27 m when it stopped during the fade from its jump
    // into the run). The new fade starts from that blend, held still.
    if (c.skin != nullptr && c.clip_fade > 0.0 && t < c.fade_start + c.clip_fade)
        c.fade_from_pose = collider_poses(c, t);
    else
        c.fade_from_pose.clear();
    c.fade_from_clip = c.clip;
    c.fade_from_speed = c.clip_speed;
    c.fade_from_loop = c.clip_loop;
    c.fade_from_start = c.clip_start;
    c.fade_start = t;
    c.clip_fade = fade;
    c.clip = clip;
    c.clip_loop = loop;
    c.clip_speed = speed;
    c.clip_start = speed > 0.0 ? t - clip_time_now / speed : t;
}

void set_clip_speed(ColliderDesc& c, double t, double speed) {
    // Speed 0 would show the clip's first pose, not hold the current one (the clip's time is
    // speed·(t − clip_start)): refused rather than jump.
    if (!(speed > 0.0) || !std::isfinite(speed))
        throw Error("collider '" + c.name + "': clip speed " + std::to_string(speed) + " (expected a finite speed > 0)");
    if (speed == c.clip_speed) return;
    const double now = clip_time(c, t);
    c.clip_speed = speed;
    c.clip_start = t - now / speed;
}


void collider_mesh_positions(const ColliderDesc& c, double t, std::span<Vec3d> out) {
    if (!c.mesh || out.size() != c.mesh->positions.size())
        throw Error("collider '" + c.name + "': " + std::to_string(out.size()) + " positions asked of a mesh of " +
                    std::to_string(c.mesh ? c.mesh->positions.size() : 0));
    const Transform frame = c.motion.at(t);
    if (!plays_clip(c)) {
        for (std::size_t i = 0; i < out.size(); ++i) out[i] = frame.apply(c.mesh->positions[i]);
        return;
    }
    skin(*c.skin, skinning_transforms(*c.skin, collider_poses(c, t)), out);
    for (Vec3d& p : out) p = frame.apply(p);
}

void collider_mesh_transforms(const ColliderDesc& c, double t, std::vector<Affine>& out) {
    const Transform frame = c.motion.at(t);
    const Affine placed{frame.rotation, frame.translation};
    if (c.skin == nullptr) {
        out.assign(1, placed);
        return;
    }
    out = skinning_transforms(*c.skin, collider_poses(c, t));
    for (Affine& a : out) a = placed * a;
}

}  // namespace weft
