// `weft run --cache FILE.glb` (gltf_cache_writer.h).
#include "gltf_cache_writer.h"

#include <algorithm>
#include <cstring>
#include <string>

#include "weft/atomic_file.h"
#include "weft/error.h"
#include "weft/world.h"

#ifdef WEFT_HAVE_GLTF
#include <tiny_gltf.h>
#endif

namespace weft::cli {

bool gltf_caches_available() {
#ifdef WEFT_HAVE_GLTF
    return true;
#else
    return false;
#endif
}

GltfCacheWriter::GltfCacheWriter(std::filesystem::path file, const World& world, double frame_seconds)
    : file_(std::move(file)), frame_seconds_(frame_seconds), frames_(world.cloth_count()) {
    if (!gltf_caches_available())
        throw Error("--cache " + file_.string() + ": glTF caches are not built (configure with TinyGLTF: Debian's "
                                                  "libtinygltf-dev); write FILE.pc2 instead");
    if (!(frame_seconds > 0.0)) throw Error("--cache " + file_.string() + ": frame time " + std::to_string(frame_seconds) + " s");
    if (file_.has_parent_path()) {
        std::error_code ec;
        std::filesystem::create_directories(file_.parent_path(), ec);
        if (ec) throw Error("cannot create the cache's folder '" + file_.parent_path().string() + "': " + ec.message());
    }
}

void GltfCacheWriter::append(const World& world) {
    for (std::size_t c = 0; c < frames_.size(); ++c) {
        const std::vector<Vec3d> x = world.positions(c);
        std::vector<Vec3f> f(x.size());
        for (std::size_t i = 0; i < x.size(); ++i)
            f[i] = Vec3f{static_cast<float>(x[i].x), static_cast<float>(x[i].y), static_cast<float>(x[i].z)};
        frames_[c].push_back(std::move(f));
    }
}

#ifdef WEFT_HAVE_GLTF
namespace {

/// Appends `bytes` to the single buffer as a new view (4-byte aligned) and returns the view's index.
int add_view(tinygltf::Model& m, const void* bytes, std::size_t size, int target) {
    std::vector<unsigned char>& data = m.buffers[0].data;
    while (data.size() % 4 != 0) data.push_back(0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = data.size();
    view.byteLength = size;
    view.target = target;
    const auto* p = static_cast<const unsigned char*>(bytes);
    data.insert(data.end(), p, p + size);
    m.bufferViews.push_back(view);
    return static_cast<int>(m.bufferViews.size()) - 1;
}

/// A float VEC3 accessor over `v` with its bounds (the format requires them for positions).
int add_vec3(tinygltf::Model& m, const std::vector<Vec3f>& v) {
    tinygltf::Accessor a;
    a.bufferView = add_view(m, v.data(), v.size() * sizeof(Vec3f), TINYGLTF_TARGET_ARRAY_BUFFER);
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.type = TINYGLTF_TYPE_VEC3;
    a.count = v.size();
    a.minValues = {1e30, 1e30, 1e30};
    a.maxValues = {-1e30, -1e30, -1e30};
    for (const Vec3f& p : v) {
        const double c[3] = {static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)};
        for (int k = 0; k < 3; ++k) {
            a.minValues[k] = std::min(a.minValues[k], c[k]);
            a.maxValues[k] = std::max(a.maxValues[k], c[k]);
        }
    }
    m.accessors.push_back(a);
    return static_cast<int>(m.accessors.size()) - 1;
}

int add_floats(tinygltf::Model& m, const std::vector<float>& v, bool bounds) {
    tinygltf::Accessor a;
    a.bufferView = add_view(m, v.data(), v.size() * sizeof(float), 0);
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.type = TINYGLTF_TYPE_SCALAR;
    a.count = v.size();
    if (bounds && !v.empty()) {  // an animation's input needs them
        a.minValues = {static_cast<double>(*std::min_element(v.begin(), v.end()))};
        a.maxValues = {static_cast<double>(*std::max_element(v.begin(), v.end()))};
    }
    m.accessors.push_back(a);
    return static_cast<int>(m.accessors.size()) - 1;
}

}  // namespace
#endif

void GltfCacheWriter::finish(const World& world) {
#ifdef WEFT_HAVE_GLTF
    tinygltf::Model m;
    m.asset.version = "2.0";
    m.asset.generator = "weft run --cache";
    m.buffers.resize(1);
    tinygltf::Scene scene;
    tinygltf::Animation animation;
    animation.name = "weft";
    const std::size_t frames = this->frames();
    std::vector<float> times(frames);
    for (std::size_t k = 0; k < frames; ++k) times[k] = static_cast<float>(static_cast<double>(k) * frame_seconds_);
    const int time_accessor = frames > 1 ? add_floats(m, times, true) : -1;
    for (std::size_t c = 0; c < frames_.size(); ++c) {
        const std::vector<std::vector<Vec3f>>& f = frames_[c];
        if (f.empty()) continue;
        tinygltf::Primitive prim;
        prim.mode = TINYGLTF_MODE_TRIANGLES;
        prim.attributes["POSITION"] = add_vec3(m, f.front());
        std::vector<std::uint32_t> indices;
        for (const Triangle& t : world.cloth(c).fabric->triangles()) indices.insert(indices.end(), {t.v[0], t.v[1], t.v[2]});
        tinygltf::Accessor ia;
        ia.bufferView = add_view(m, indices.data(), indices.size() * sizeof(std::uint32_t), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
        ia.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
        ia.type = TINYGLTF_TYPE_SCALAR;
        ia.count = indices.size();
        m.accessors.push_back(ia);
        prim.indices = static_cast<int>(m.accessors.size()) - 1;
        // Frame k > 0 is morph target k − 1: its displacement from the first frame.
        std::vector<Vec3f> d(f.front().size());
        for (std::size_t k = 1; k < frames; ++k) {
            for (std::size_t i = 0; i < d.size(); ++i) d[i] = f[k][i] - f.front()[i];
            prim.targets.push_back({{"POSITION", add_vec3(m, d)}});
        }
        tinygltf::Mesh mesh;
        mesh.name = world.cloth(c).name;
        mesh.primitives.push_back(prim);
        mesh.weights.assign(frames > 0 ? frames - 1 : 0, 0.0);
        m.meshes.push_back(mesh);
        tinygltf::Node node;
        node.name = world.cloth(c).name;
        node.mesh = static_cast<int>(m.meshes.size()) - 1;
        m.nodes.push_back(node);
        scene.nodes.push_back(static_cast<int>(m.nodes.size()) - 1);
        if (frames > 1) {
            // At key k the weights are one-hot at target k − 1 (all zero at key 0): linear
            // interpolation between keys is then the linear interpolation of the positions.
            std::vector<float> weights((frames) * (frames - 1), 0.0F);
            for (std::size_t k = 1; k < frames; ++k) weights[k * (frames - 1) + (k - 1)] = 1.0F;
            tinygltf::AnimationSampler sampler;
            sampler.input = time_accessor;
            sampler.output = add_floats(m, weights, false);
            sampler.interpolation = "LINEAR";
            animation.samplers.push_back(sampler);
            tinygltf::AnimationChannel channel;
            channel.sampler = static_cast<int>(animation.samplers.size()) - 1;
            channel.target_node = node.mesh >= 0 ? static_cast<int>(m.nodes.size()) - 1 : -1;
            channel.target_path = "weights";
            animation.channels.push_back(channel);
        }
    }
    if (!animation.channels.empty()) m.animations.push_back(animation);
    m.scenes.push_back(scene);
    m.defaultScene = 0;
    tinygltf::TinyGLTF gltf;
    AtomicFile out(file_);  // whole or not at all: TinyGLTF writes the temporary file
    out.release_stream();
    if (!gltf.WriteGltfSceneToFile(&m, out.temporary().string(), true, true, false, true))
        throw Error("cannot write the glTF cache " + file_.string());
    out.commit();
#else
    (void)world;
    throw Error("--cache " + file_.string() + ": glTF caches are not built");
#endif
}

}  // namespace weft::cli
