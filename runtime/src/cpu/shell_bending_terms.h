#pragma once
// The bending models per triangle (SolverSettings::bending = Shell, MidEdge) in the CPU solver's element slots:
// the two passes of weft/physics/shell_bending_slots.h (shared with the CUDA backend), fed from the
// solver's arrays (the file comment there says what each pass computes and why the matrix is H').

#include <cstdint>

#include "weft/fabric.h"
#include "weft/physics/shell_bending_slots.h"
#include "weft/physics/vec.h"

namespace weft::cpu {

template <typename T>
using ShellFaceTerms = physics::ShellFaceTerms<T>;

/// Pass 1 for one triangle. `x`, `vk`, `d`: the solver's arrays (linearisation point, iterate,
/// v_k − w_k) indexed by global vertex; `hinge_at` the flat model's hinges; `stiffness` D, `beta` the
/// stiffness damping; `rest_angle_at` per hinge.
/// `reading`: the mid-edge model's (weft/physics/midedge_bending.h); null for the shell model.
template <typename T, typename HingeAt, typename RestAngleAt>
ShellFaceTerms<T> shell_face_terms(T h, T stiffness, T beta, const physics::ShellBendingRest<T>& rest, const TriangleHinges& th,
                                   HingeAt&& hinge_at, RestAngleAt&& rest_angle_at, const physics::Vec3<T>* x,
                                   const physics::Vec3<T>* vk, const physics::Vec3<T>* d,
                                   const physics::ShellReading<T>* reading = nullptr) {
    physics::Vec3<T> p[3][4], v[3][4], dv[3][4];
    T rest_angle[3];
    for (int k = 0; k < 3; ++k) {
        const bool present = th.edge[k] >= 0;
        rest_angle[k] = present ? rest_angle_at(th.edge[k]) : T(0);
        for (int a = 0; a < 4; ++a) {
            const std::uint32_t vertex = present ? hinge_at(th.edge[k]).v[a] : 0;
            p[k][a] = present ? x[vertex] : physics::Vec3<T>{};
            v[k][a] = present ? vk[vertex] : physics::Vec3<T>{};
            dv[k][a] = present ? d[vertex] : physics::Vec3<T>{};
        }
    }
    return physics::shell_face_terms(h, stiffness, beta, rest, th.edge, p, v, dv, rest_angle, reading);
}

/// Pass 2 for hinge `self`: adds into rhs[4] and block[16] (row-major, the hinge's vertex order)
/// the terms of triangle `face` (pass 1's output) that fall to it.
template <typename T, typename HingeAt>
void shell_hinge_slots(std::int32_t self, const ShellFaceTerms<T>& face, HingeAt&& hinge_at, physics::Vec3<T> rhs[4],
                       physics::Mat3<T> block[16]) {
    std::uint32_t face_vertices[3][4]{};
    for (int k = 0; k < 3; ++k)
        if (face.hinge[k] >= 0)
            for (int a = 0; a < 4; ++a) face_vertices[k][a] = hinge_at(face.hinge[k]).v[a];
    physics::shell_hinge_slots(self, hinge_at(self).v, face, face_vertices, rhs, block);
}

}  // namespace weft::cpu
