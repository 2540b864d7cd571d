// A mesh collider's vertices at a time: its skin's clip, then its rigid motion (weft/collider.h).
#include <string>
#include <vector>

#include "weft/collider.h"
#include "weft/error.h"

namespace weft {

void collider_mesh_positions(const ColliderDesc& c, double t, std::span<Vec3d> out) {
    if (!c.mesh || out.size() != c.mesh->positions.size())
        throw Error("collider '" + c.name + "': " + std::to_string(out.size()) + " positions asked of a mesh of " +
                    std::to_string(c.mesh ? c.mesh->positions.size() : 0));
    const Transform frame = c.motion.at(t);
    if (!plays_clip(c)) {
        for (std::size_t i = 0; i < out.size(); ++i) out[i] = frame.apply(c.mesh->positions[i]);
        return;
    }
    const std::vector<JointPose> poses = sample_clip(*c.skin, c.skin->clip(c.clip), clip_time(c, t), c.clip_loop);
    skin(*c.skin, skinning_transforms(*c.skin, poses), out);
    for (Vec3d& p : out) p = frame.apply(p);
}

void collider_mesh_transforms(const ColliderDesc& c, double t, std::vector<Affine>& out) {
    const Transform frame = c.motion.at(t);
    const Affine placed{frame.rotation, frame.translation};
    if (c.skin == nullptr) {
        out.assign(1, placed);
        return;
    }
    const std::vector<JointPose> poses =
        plays_clip(c) ? sample_clip(*c.skin, c.skin->clip(c.clip), clip_time(c, t), c.clip_loop) : rest_poses(*c.skin);
    out = skinning_transforms(*c.skin, poses);
    for (Affine& a : out) a = placed * a;
}

}  // namespace weft
