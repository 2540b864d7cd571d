#pragma once
// Device helpers shared by the narrow-phase kernels (proximity_gpu.cu, ccd_gpu.cu): the four vertices
// of a candidate pair from its key, positions from the backend's structure-of-arrays layout, and the
// pair's weights and normal from its closest points. The rules are those of the CPU reference
// (runtime/src/collision/proximity_contacts.cpp, impact_zones.cpp), evaluated in float.

#include <cstdint>

#include "collision/pair_keys.h"
#include "weft/physics/proximity.h"
#include "weft/physics/vec.h"

namespace weft::cuda::collision {

using V3f = physics::Vec3<float>;

/// The four vertices of a pair in the order of the gap function: vertex–face (p, a, b, c), edge–edge
/// (e0, e1, f0, f1). `first_side` of them belong to the first primitive.
struct PairVertices {
    std::uint32_t id[4];
    int first_side;
    bool vf;
};

__device__ inline PairVertices pair_vertices(const PairEncoding& enc, unsigned long long key,
                                             const std::uint32_t* triangles, const std::uint32_t* edges) {
    PairVertices pv{};
    const std::uint32_t a = enc.first(key), b = enc.second(key);
    pv.vf = !enc.is_ee(key);
    if (pv.vf) {
        const std::uint32_t* t = triangles + 3 * static_cast<std::size_t>(b);
        pv.id[0] = a;
        pv.id[1] = t[0];
        pv.id[2] = t[1];
        pv.id[3] = t[2];
        pv.first_side = 1;
    } else {
        const std::uint32_t* e = edges + 2 * static_cast<std::size_t>(a);
        const std::uint32_t* f = edges + 2 * static_cast<std::size_t>(b);
        pv.id[0] = e[0];
        pv.id[1] = e[1];
        pv.id[2] = f[0];
        pv.id[3] = f[1];
        pv.first_side = 2;
    }
    return pv;
}

/// Position of vertex v in a structure-of-arrays buffer with component stride `stride`.
__device__ inline V3f load_position(const float* x, std::uint32_t v, std::uint32_t stride) {
    return {x[v], x[v + static_cast<std::size_t>(stride)], x[v + 2 * static_cast<std::size_t>(stride)]};
}

/// Closest points of the pair's primitives at positions x: weights w (Σ w_i x_i is the gap vector,
/// as in ProximityContact), the unit normal from the second primitive towards the first, the distance.
__device__ inline void pair_closest(bool vf, const V3f (&x)[4], float (&w)[4], V3f& normal, float& distance) {
    if (vf) {
        const auto q = physics::point_triangle_proximity(x[0], x[1], x[2], x[3]);
        w[0] = 1.0F;
        w[1] = -(1.0F - q.u - q.v);
        w[2] = -q.u;
        w[3] = -q.v;
        normal = q.normal;
        distance = q.distance;
    } else {
        const auto q = physics::edge_edge_proximity(x[0], x[1], x[2], x[3]);
        w[0] = 1.0F - q.u;
        w[1] = q.u;
        w[2] = -(1.0F - q.v);
        w[3] = -q.v;
        normal = q.normal;
        distance = q.distance;
    }
}

/// Candidates in use of a pair list (the device count, clamped to the buffer after an overflow).
__device__ inline std::uint32_t candidates_in_use(const GpuPairList& pairs) {
    const std::uint32_t count = pairs.count[0];
    return count < pairs.capacity ? count : pairs.capacity;
}

}  // namespace weft::cuda::collision
