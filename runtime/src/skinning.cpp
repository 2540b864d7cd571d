// Linear blend skinning on the host (weft/skinning.h).
#include "weft/skinning.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "weft/error.h"

namespace weft {
namespace {

[[noreturn]] void fail(const SkinnedMesh& m, const std::string& what) {
    throw Error((m.mesh.source.empty() ? std::string("skinned mesh") : m.mesh.source) + ": " + what);
}

/// The key interval of `t` in `times` (increasing, non-empty): indices a ≤ b and the fraction in it.
struct Interval {
    std::size_t a = 0, b = 0;
    double s = 0.0;
};
Interval locate(const std::vector<double>& times, double t) {
    if (t <= times.front()) return {0, 0, 0.0};
    if (t >= times.back()) return {times.size() - 1, times.size() - 1, 0.0};
    const auto upper = std::upper_bound(times.begin(), times.end(), t);
    const std::size_t b = static_cast<std::size_t>(upper - times.begin()), a = b - 1;
    const double span = times[b] - times[a];
    return {a, b, span > 0.0 ? (t - times[a]) / span : 0.0};
}

Vec3d lerp(Vec3d a, Vec3d b, double s) { return a + s * (b - a); }

bool increasing(const std::vector<double>& times) {
    for (std::size_t k = 0; k < times.size(); ++k) {
        if (!std::isfinite(times[k])) return false;
        if (k > 0 && !(times[k] > times[k - 1])) return false;
    }
    return true;
}

}  // namespace

Mat3d rotation_matrix(Quatd q) {
    const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    if (!(n > 0.0)) return Mat3d::identity();
    const double w = q.w / n, x = q.x / n, y = q.y / n, z = q.z / n;
    Mat3d r;
    r.m[0][0] = 1 - 2 * (y * y + z * z);
    r.m[0][1] = 2 * (x * y - w * z);
    r.m[0][2] = 2 * (x * z + w * y);
    r.m[1][0] = 2 * (x * y + w * z);
    r.m[1][1] = 1 - 2 * (x * x + z * z);
    r.m[1][2] = 2 * (y * z - w * x);
    r.m[2][0] = 2 * (x * z - w * y);
    r.m[2][1] = 2 * (y * z + w * x);
    r.m[2][2] = 1 - 2 * (x * x + y * y);
    return r;
}

Quatd slerp(Quatd a, Quatd b, double s) {
    double d = a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z;
    if (d < 0.0) {  // the shorter arc: q and −q are the same rotation
        b = {-b.w, -b.x, -b.y, -b.z};
        d = -d;
    }
    double wa = 1.0 - s, wb = s;
    if (d < 0.9995) {  // otherwise nearly parallel: linear, then normalised
        const double angle = std::acos(std::min(1.0, d)), sine = std::sin(angle);
        wa = std::sin((1.0 - s) * angle) / sine;
        wb = std::sin(s * angle) / sine;
    }
    Quatd r{wa * a.w + wb * b.w, wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z};
    const double n = std::sqrt(r.w * r.w + r.x * r.x + r.y * r.y + r.z * r.z);
    return n > 0.0 ? Quatd{r.w / n, r.x / n, r.y / n, r.z / n} : Quatd{};
}

Affine operator*(const Affine& a, const Affine& b) { return {a.linear * b.linear, a.linear * b.translation + a.translation}; }

Affine inverse(const Affine& a) {
    const Mat3d& m = a.linear;
    const double det = m.m[0][0] * (m.m[1][1] * m.m[2][2] - m.m[1][2] * m.m[2][1]) -
                       m.m[0][1] * (m.m[1][0] * m.m[2][2] - m.m[1][2] * m.m[2][0]) +
                       m.m[0][2] * (m.m[1][0] * m.m[2][1] - m.m[1][1] * m.m[2][0]);
    if (!(std::abs(det) > 1e-300) || !std::isfinite(det)) throw Error("skinning: a joint transform is singular");
    const Mat3d inv = math::inverse(m);
    return {inv, -(inv * a.translation)};
}

Affine JointPose::matrix() const {
    Mat3d linear = rotation_matrix(rotation);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) linear.m[r][c] *= scale[c];  // R·S: scale first
    return {linear, translation};
}

const AnimationClip& SkinnedMesh::clip(const std::string& name) const {
    for (const AnimationClip& c : clips)
        if (c.name == name) return c;
    std::string known;
    for (const AnimationClip& c : clips) known += (known.empty() ? "" : ", ") + ("'" + c.name + "'");
    fail(*this, "no animation clip '" + name + "' (the file has " + (known.empty() ? std::string("none") : known) + ")");
}

void normalize_weights(SkinnedMesh& m) {
    for (std::size_t i = 0; i < m.vertex_weights.size(); ++i) {
        double sum = 0.0;
        for (const double w : m.vertex_weights[i]) sum += w;
        if (!(sum > 0.0) || !std::isfinite(sum))
            fail(m, "vertex " + std::to_string(i) + " has no skin weight (it would collapse to the origin)");
        for (double& w : m.vertex_weights[i]) w /= sum;
    }
}

void validate(const SkinnedMesh& m) {
    const std::size_t n = m.mesh.positions.size(), joints = m.joints.size();
    if (joints == 0) fail(m, "no joints");
    if (m.vertex_joints.size() != n || m.vertex_weights.size() != n)
        fail(m, std::to_string(n) + " vertices but " + std::to_string(m.vertex_joints.size()) + " joint lists and " +
                    std::to_string(m.vertex_weights.size()) + " weight lists");
    for (std::size_t j = 0; j < joints; ++j) {
        const std::int32_t p = m.joints[j].parent;
        if (p >= static_cast<std::int32_t>(j) || p < -1)
            fail(m, "joint " + std::to_string(j) + " ('" + m.joints[j].name + "') has parent " + std::to_string(p) +
                        ": parents must come before their children");
    }
    for (std::size_t i = 0; i < n; ++i) {
        double sum = 0.0;
        for (int k = 0; k < 4; ++k) {
            const double w = m.vertex_weights[i][static_cast<std::size_t>(k)];
            if (!std::isfinite(w) || w < 0.0) fail(m, "vertex " + std::to_string(i) + " has skin weight " + std::to_string(w));
            if (w > 0.0 && m.vertex_joints[i][static_cast<std::size_t>(k)] >= joints)
                fail(m, "vertex " + std::to_string(i) + " is bound to joint " +
                            std::to_string(m.vertex_joints[i][static_cast<std::size_t>(k)]) + " of " + std::to_string(joints));
            sum += w;
        }
        if (std::abs(sum - 1.0) > 1e-3)
            fail(m, "vertex " + std::to_string(i) + "'s skin weights sum to " + std::to_string(sum) + ", not 1");
    }
    for (const AnimationClip& c : m.clips)
        for (const JointTrack& t : c.tracks) {
            const std::string where = "clip '" + c.name + "', track of joint " + std::to_string(t.joint);
            if (t.joint >= joints) fail(m, where + ": no such joint (" + std::to_string(joints) + " joints)");
            if (t.translation_times.size() != t.translations.size() || t.rotation_times.size() != t.rotations.size() ||
                t.scale_times.size() != t.scales.size())
                fail(m, where + ": key times and values differ in number");
            if (!increasing(t.translation_times) || !increasing(t.rotation_times) || !increasing(t.scale_times))
                fail(m, where + ": key times are not increasing");
        }
}

std::vector<JointPose> rest_poses(const SkinnedMesh& m) {
    std::vector<JointPose> poses;
    poses.reserve(m.joints.size());
    for (const Joint& j : m.joints) poses.push_back(j.rest);
    return poses;
}

std::vector<JointPose> sample_clip(const SkinnedMesh& m, const AnimationClip& clip, double t, bool loop) {
    std::vector<JointPose> poses = rest_poses(m);
    if (loop && clip.duration > 0.0) {
        t = std::fmod(t, clip.duration);
        if (t < 0.0) t += clip.duration;
    }
    for (const JointTrack& track : clip.tracks) {
        JointPose& p = poses.at(track.joint);
        if (!track.translations.empty()) {
            const Interval k = locate(track.translation_times, t);
            p.translation = lerp(track.translations[k.a], track.translations[k.b], k.s);
        }
        if (!track.rotations.empty()) {
            const Interval k = locate(track.rotation_times, t);
            p.rotation = slerp(track.rotations[k.a], track.rotations[k.b], k.s);
        }
        if (!track.scales.empty()) {
            const Interval k = locate(track.scale_times, t);
            p.scale = lerp(track.scales[k.a], track.scales[k.b], k.s);
        }
    }
    return poses;
}

std::vector<JointPose> blend_poses(std::span<const JointPose> from, std::span<const JointPose> to, double s) {
    if (from.size() != to.size())
        throw Error("blend_poses: " + std::to_string(from.size()) + " and " + std::to_string(to.size()) + " joint poses");
    std::vector<JointPose> out(to.begin(), to.end());
    for (std::size_t j = 0; j < out.size(); ++j) {
        out[j].translation = lerp(from[j].translation, to[j].translation, s);
        out[j].rotation = slerp(from[j].rotation, to[j].rotation, s);
        out[j].scale = lerp(from[j].scale, to[j].scale, s);
    }
    return out;
}

std::vector<Affine> skinning_transforms(const SkinnedMesh& m, std::span<const JointPose> poses) {
    if (poses.size() != m.joints.size())
        fail(m, std::to_string(poses.size()) + " joint poses for " + std::to_string(m.joints.size()) + " joints");
    std::vector<Affine> world(m.joints.size()), out(m.joints.size());
    for (std::size_t j = 0; j < m.joints.size(); ++j) {
        const Affine local = poses[j].matrix();
        const std::int32_t p = m.joints[j].parent;
        world[j] = p < 0 ? local : world[static_cast<std::size_t>(p)] * local;  // parents come first
        out[j] = world[j] * m.joints[j].inverse_bind;
    }
    return out;
}

void skin(const SkinnedMesh& m, std::span<const Affine> transforms, std::span<Vec3d> positions) {
    const std::size_t n = m.mesh.positions.size();
    if (positions.size() != n || transforms.size() != m.joints.size())
        fail(m, "skin: " + std::to_string(positions.size()) + " outputs and " + std::to_string(transforms.size()) +
                    " transforms for " + std::to_string(n) + " vertices and " + std::to_string(m.joints.size()) + " joints");
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3d x = m.mesh.positions[i];
        Vec3d sum{};
        for (std::size_t k = 0; k < 4; ++k) {
            const double w = m.vertex_weights[i][k];
            if (w > 0.0) sum += w * transforms[m.vertex_joints[i][k]].apply(x);
        }
        positions[i] = sum;
    }
}

}  // namespace weft
