// Compile-only guard: every single-source physics function instantiated for float and double inside
// __global__ kernels. Nothing launches them; the build fails if a header uses anything nvcc cannot
// compile for the device (host-only library calls, exceptions, std::min, non-constexpr globals, …).
#include "weft/physics/aerodynamics.h"
#include "weft/physics/bending.h"
#include "weft/physics/ccd.h"
#include "weft/physics/collider_contact.h"
#include "weft/physics/damping.h"
#include "weft/physics/eigen_sym.h"
#include "weft/physics/hessian.h"
#include "weft/physics/membrane.h"
#include "weft/physics/offset_contact.h"
#include "weft/physics/pair_contact.h"
#include "weft/physics/proximity.h"
#include "weft/physics/midedge_bending.h"
#include "weft/physics/shell_bending.h"
#include "weft/physics/swept_collider.h"

namespace weft::physics {

/// Inputs and outputs in global memory, so the compiler cannot discard any of the calls.
template <typename T>
struct DeviceProbe {
    Vec3<T> x[4];
    Vec3<T> v[4];
    Shape<T> shape;
    T dense[12][12];
    T scalar[8];
    Vec3<T> vec[16];
    Mat3<T> mat[32];
    ContactResult<T> contact[4];
};

template <typename T>
__device__ void exercise(DeviceProbe<T>& p) {
    // membrane
    const MembraneMaterial<T> mm = membrane_material(T(1000), T(0.3));
    T dm_inv[2][2];
    T area;
    membrane_rest(p.x[0], p.x[1], p.x[2], dm_inv, area);
    Vec3<T> g3[3];
    Mat3<T> h3[3][3];
    for (int k = 0; k < 4; ++k)
        p.scalar[0] += membrane_evaluate(dm_inv, area, mm, p.x, g3, h3, static_cast<HessianKind>(k));
    // bending
    const T w = hinge_weight(p.x);
    const T rest = dihedral_angle(p.x);
    Vec3<T> g4[4];
    Mat3<T> h4[4][4];
    for (int k = 0; k < 4; ++k)
        p.scalar[1] += bending_evaluate(T(1e-3), w, rest, p.x, g4, h4, static_cast<HessianKind>(k));
    dihedral_angle_derivatives(p.x, g4, h4);
    // bending from a shape operator per triangle
    ShellBendingRest<T> sr;
    (void)shell_bending_rest(p.x[0], p.x[1], p.x[2], sr);
    const bool present[3] = {true, true, false};
    const Vec3<T> stencil[3][4] = {{p.x[0], p.x[1], p.x[2], p.x[3]}, {p.x[1], p.x[2], p.x[0], p.x[3]},
                                   {p.x[2], p.x[0], p.x[1], p.x[3]}};
    const T shell_rest[3] = {T(0), T(0.1), T(0)};
    const ShellBendingTerms<T> st = shell_bending_evaluate(T(1e-3), sr, present, stencil, shell_rest);
    p.scalar[1] += st.energy + shell_bending_coupling(T(1e-3), sr, 0, 1);
    p.vec[4] = st.dtheta[0][0];
    // with mid-edge normals
    const ShellBendingRest<T> mr = midedge_condensed_rest(sr, present);
    MidEdgeFace<T> mf;
    mf.side[0] = T(midedge_side(0u, 0u));
    const T xi[3] = {T(0.01), T(0), T(0)};
    const ShellReading<T> reading = midedge_reading(mf, xi);
    p.scalar[1] += shell_bending_evaluate(T(1e-3), mr, present, stencil, shell_rest, &reading).energy +
                   midedge_xi_gradient(mf, mr, xi, 0, true);
    // contact
    const ContactParams<T> cp{T(1e4), T(0.01), T(0.3), T(0.01)};
    for (int k = 0; k < 4; ++k) p.contact[k] = collider_contact(p.shape, cp, p.x[0], p.v[0], static_cast<HessianKind>(k));
    p.scalar[2] = shape_distance(p.shape, p.x[1], p.vec[0], &p.mat[0]);
    p.vec[1] = shape_point_velocity(p.shape, p.x[1]);
    // aerodynamics and gusts
    const AeroCoefficients<T> ac{T(1.2), T(1.5), T(0.8)};
    aerodynamic_force(p.x, p.v, p.v[3], ac, p.vec[2], &p.mat[1]);
    p.mat[2] = aerodynamic_force_jacobian(p.x, p.v, p.v[3], ac);
    p.vec[3] = aerodynamic_plate_force(p.v[0], p.x[0], T(1), ac, &p.mat[3]);
    p.vec[4] = wind_gust(p.x[0], p.scalar[3], T(2), T(1), T(3));
    // damping
    p.vec[5] = mass_damping_force(T(0.5), T(2), p.v[0]);
    stiffness_damping_force<3>(T(0.1), h3, p.v, g3);
    p.vec[6] = g3[0];
    p.mat[4] = rayleigh_velocity_jacobian(T(0.5), T(2), true, T(0.1), h3[0][0]);
    // eigen
    T ev[12], vec[12][12];
    p.scalar[4] = T(eigen_sym<12>(p.dense, ev, vec)) + ev[0] + vec[0][0];
    p.scalar[5] = project_psd<12>(p.dense) ? T(1) : T(0);
    T d9[9][9];
    pack_blocks<3>(h3, d9);
    project_psd<9>(d9);
    unpack_blocks<3>(d9, h3);
    project_psd_blocks<4>(h4);
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) p.mat[5 + 3 * a + b] = h3[a][b];
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) p.mat[14 + b] += h4[a][b];
    for (int a = 0; a < 4; ++a) p.vec[7 + a] = g4[a];
    // proximity
    const PointSegmentProximity<T> ps = point_segment_proximity(p.x[0], p.x[1], p.x[2]);
    const PointTriangleProximity<T> pt = point_triangle_proximity(p.x[0], p.x[1], p.x[2], p.x[3]);
    const EdgeEdgeProximity<T> pe = edge_edge_proximity(p.x[0], p.x[1], p.x[2], p.x[3]);
    p.vec[11] = ps.normal + ps.closest;
    p.vec[12] = pt.normal + pt.closest;
    p.vec[13] = pe.normal + pe.closest_e + pe.closest_f;
    p.scalar[6] = ps.distance + ps.s + pt.distance + pt.u + pt.v + pe.distance + pe.u + pe.v;
    // continuous collision detection (start positions in x, end positions in v)
    const CcdResult<T> cv =
        vertex_face_ccd(p.x[0], p.x[1], p.x[2], p.x[3], p.v[0], p.v[1], p.v[2], p.v[3], p.scalar[3]);
    CcdOptions<T> co{};
    co.max_iterations = 256;
    const CcdResult<T> ce =
        edge_edge_ccd<T, 16>(p.x[0], p.x[1], p.x[2], p.x[3], p.v[0], p.v[1], p.v[2], p.v[3], p.scalar[3], co);
    p.scalar[7] = cv.toi + cv.u + cv.diag.distance_bound + ce.toi + ce.v + ce.diag.error_bound +
                  T(cv.diag.iterations + ce.diag.max_queue) + (cv.hit && ce.hit ? T(1) : T(0));
    p.vec[14] = Vec3<T>{T(static_cast<int>(cv.diag.status)), T(static_cast<int>(ce.diag.status)), T(0)};
    // cloth–cloth pair springs and the swept test against fast colliders
    const PairContactForce<T> pc =
        pair_contact(p.vec[0], p.x[2], p.v[2], PairContactParams<T>{T(1e3), T(0.01), T(0.3), T(1e-3)});
    p.mat[30] = pc.dfdx + pc.dfdv;
    p.vec[15] = pc.force;
    // offset geometric contact (§7b)
    const OffsetContactForce<T> oc =
        offset_contact(p.x[2], p.v[2], p.vec[0], OffsetContactParams<T>{T(1e3), T(0.01), T(0.3), T(1e-3)});
    p.mat[30] += oc.dfdx + oc.dfdv;
    p.vec[15] += oc.force;
    const SweptContact<T> sc = swept_shape_contact(p.shape, p.shape, T(0.01), p.x[0], p.v[0], T(0.005), 64);
    p.vec[15] += sc.position;
    p.scalar[7] += sc.tau + T(sc.samples) + (sc.hit ? T(1) : T(0));
}

__global__ void physics_device_compile_float(DeviceProbe<float>* p) { exercise(*p); }
__global__ void physics_device_compile_double(DeviceProbe<double>* p) { exercise(*p); }

}  // namespace weft::physics
