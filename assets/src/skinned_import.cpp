// Skinned meshes through assimp (weft/assets/skinned_import.h).
#include "weft/assets/skinned_import.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>
#include <exception>
#include <map>
#include <string>
#include <vector>

#include "file_signature.h"
#include "weft/error.h"
#include "weft/world_limits.h"

namespace weft::assets {
namespace {

Affine affine_of(const aiMatrix4x4& m) {
    Affine a;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) a.linear.m[r][c] = static_cast<double>(m[static_cast<unsigned>(r)][static_cast<unsigned>(c)]);
        a.translation[r] = static_cast<double>(m[static_cast<unsigned>(r)][3]);
    }
    return a;
}

JointPose pose_of(const aiMatrix4x4& m) {
    aiVector3D scale, position;
    aiQuaternion rotation;
    m.Decompose(scale, rotation, position);
    JointPose p;
    p.translation = {position.x, position.y, position.z};
    p.rotation = {rotation.w, rotation.x, rotation.y, rotation.z};
    p.scale = {scale.x, scale.y, scale.z};
    return p;
}

/// Every node on the way from the root to a bone, parents first (depth-first order).
void collect_joints(const aiNode* node, std::int32_t parent, const std::map<std::string, bool>& needed, SkinnedMesh& out,
                    std::map<std::string, std::uint32_t>& index) {
    std::int32_t self = parent;
    if (needed.count(node->mName.C_Str()) != 0U) {
        Joint j;
        j.name = node->mName.C_Str();
        j.parent = parent;
        j.rest = pose_of(node->mTransformation);
        self = static_cast<std::int32_t>(out.joints.size());
        index[j.name] = static_cast<std::uint32_t>(self);
        out.joints.push_back(std::move(j));
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) collect_joints(node->mChildren[c], self, needed, out, index);
}

/// Marks `node` and its ancestors as needed when it is named in `bones`; returns whether it was.
bool mark_needed(const aiNode* node, const std::map<std::string, aiMatrix4x4>& bones, std::map<std::string, bool>& needed) {
    bool any = bones.count(node->mName.C_Str()) != 0U;
    for (unsigned c = 0; c < node->mNumChildren; ++c) any = mark_needed(node->mChildren[c], bones, needed) || any;
    if (any) needed[node->mName.C_Str()] = true;
    return any;
}

}  // namespace

SkinnedMesh import_skinned_mesh(const std::filesystem::path& path) {
    const std::string file = path.string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(file + ": character file not found");
    check_file_size(path, kMaxMeshFileBytes, "character file");
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext != ".gltf" && ext != ".glb" && ext != ".fbx")
        throw Error(file + ": a skinned character is read from glTF 2.0 (.gltf, .glb) or FBX, not '" + ext + "'");
    (void)check_signature(path, ext);

    Assimp::Importer importer;
    // No PreTransformVertices (it would bake the bind pose and drop the bones); LimitBoneWeights
    // keeps the four largest weights of a vertex.
    const unsigned flags = aiProcess_ValidateDataStructure | aiProcess_Triangulate | aiProcess_LimitBoneWeights;
    const aiScene* scene = nullptr;
    try {
        scene = importer.ReadFile(file, flags);
    } catch (const std::exception& e) {
        throw Error(file + ": cannot import character: " + e.what());
    }
    if (scene == nullptr) throw Error(file + ": cannot import character: " + importer.GetErrorString());
    if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0U || scene->mRootNode == nullptr)
        throw Error(file + ": cannot import character: the file holds no scene");

    // The bones of every skinned triangle mesh: name → offset (inverse bind) matrix.
    std::map<std::string, aiMatrix4x4> bones;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const aiMesh& in = *scene->mMeshes[m];
        if (in.mNumBones == 0 || (in.mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0U) continue;
        for (unsigned b = 0; b < in.mNumBones; ++b) bones[in.mBones[b]->mName.C_Str()] = in.mBones[b]->mOffsetMatrix;
    }
    if (bones.empty()) throw Error(file + ": no skinned triangle mesh (no mesh with bones)");

    SkinnedMesh out;
    out.mesh.source = file;
    std::map<std::string, bool> needed;
    (void)mark_needed(scene->mRootNode, bones, needed);
    std::map<std::string, std::uint32_t> index;
    collect_joints(scene->mRootNode, -1, needed, out, index);
    for (Joint& j : out.joints) {
        const auto bone = bones.find(j.name);
        if (bone != bones.end()) j.inverse_bind = affine_of(bone->second);
    }

    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const aiMesh& in = *scene->mMeshes[m];
        if (in.mNumBones == 0 || (in.mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0U) continue;
        const auto base = static_cast<std::uint32_t>(out.mesh.positions.size());
        for (unsigned v = 0; v < in.mNumVertices; ++v) {
            const aiVector3D& p = in.mVertices[v];
            out.mesh.positions.push_back({p.x, p.y, p.z});
            out.vertex_joints.push_back({0, 0, 0, 0});
            out.vertex_weights.push_back({0.0, 0.0, 0.0, 0.0});
        }
        for (unsigned b = 0; b < in.mNumBones; ++b) {
            const aiBone& bone = *in.mBones[b];
            const std::uint32_t joint = index.at(bone.mName.C_Str());
            for (unsigned w = 0; w < bone.mNumWeights; ++w) {
                const aiVertexWeight& vw = bone.mWeights[w];
                if (vw.mVertexId >= in.mNumVertices)
                    throw Error(file + ": bone '" + std::string(bone.mName.C_Str()) + "' weighs vertex " +
                                std::to_string(vw.mVertexId) + " of " + std::to_string(in.mNumVertices));
                auto& joints = out.vertex_joints[base + vw.mVertexId];
                auto& weights = out.vertex_weights[base + vw.mVertexId];
                // The smallest slot gives way (LimitBoneWeights has left at most four anyway).
                const auto slot = static_cast<std::size_t>(std::min_element(weights.begin(), weights.end()) - weights.begin());
                if (static_cast<double>(vw.mWeight) > weights[slot]) {
                    weights[slot] = vw.mWeight;
                    joints[slot] = joint;
                }
            }
        }
        for (unsigned f = 0; f < in.mNumFaces; ++f) {
            const aiFace& face = in.mFaces[f];
            if (face.mNumIndices != 3) continue;
            out.mesh.triangles.push_back({{base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]}});
        }
    }
    if (out.mesh.triangles.empty()) throw Error(file + ": the skinned meshes hold no triangles");

    for (unsigned a = 0; a < scene->mNumAnimations; ++a) {
        const aiAnimation& anim = *scene->mAnimations[a];
        // Key times are in ticks; a file that gives no rate is taken at assimp's default of 25 a second.
        const double ticks = anim.mTicksPerSecond > 0.0 ? anim.mTicksPerSecond : 25.0;
        AnimationClip clip;
        clip.name = anim.mName.length > 0 ? anim.mName.C_Str() : "clip " + std::to_string(a);
        for (unsigned c = 0; c < anim.mNumChannels; ++c) {
            const aiNodeAnim& ch = *anim.mChannels[c];
            const auto joint = index.find(ch.mNodeName.C_Str());
            if (joint == index.end()) continue;  // a node that moves no bone
            JointTrack t;
            t.joint = joint->second;
            for (unsigned k = 0; k < ch.mNumPositionKeys; ++k) {
                t.translation_times.push_back(ch.mPositionKeys[k].mTime / ticks);
                const aiVector3D& v = ch.mPositionKeys[k].mValue;
                t.translations.push_back({v.x, v.y, v.z});
            }
            for (unsigned k = 0; k < ch.mNumRotationKeys; ++k) {
                t.rotation_times.push_back(ch.mRotationKeys[k].mTime / ticks);
                const aiQuaternion& q = ch.mRotationKeys[k].mValue;
                t.rotations.push_back({q.w, q.x, q.y, q.z});
            }
            for (unsigned k = 0; k < ch.mNumScalingKeys; ++k) {
                t.scale_times.push_back(ch.mScalingKeys[k].mTime / ticks);
                const aiVector3D& v = ch.mScalingKeys[k].mValue;
                t.scales.push_back({v.x, v.y, v.z});
            }
            for (const auto* times : {&t.translation_times, &t.rotation_times, &t.scale_times})
                if (!times->empty()) clip.duration = std::max(clip.duration, times->back());
            clip.tracks.push_back(std::move(t));
        }
        out.clips.push_back(std::move(clip));
    }
    normalize_weights(out);
    validate(out);
    return out;
}

}  // namespace weft::assets
