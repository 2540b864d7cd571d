#pragma once
/// @file
/// The implicit terms: what each vertex, triangle, hinge and contact adds to the right-hand side b
/// and to the 3×3 blocks of A = M − h·∂f/∂v − h²·∂f/∂x in one Newton iterate of the implicit Euler
/// step (docs/architecture.md, "The step in detail", equation (1)), written once for both backends.
/// The CPU solver calls these in double or float; the CUDA kernels call them in float. Each backend
/// only gathers its inputs (positions at the linearisation point, velocities, parameters) from its
/// own layout and scatters the results into its own matrix.
///
/// Notation: h the substep, x0 and v0 the state at its start, v_k the current velocity iterate, w_k
/// the velocity of the linearisation point (x = x0 + h·w_k; w_0 = 0, then w_k = v_k), d = v_k − w_k.
/// A force f(x, v) with K = ∂f/∂x and D = ∂f/∂v, linearised about (x0 + h·w_k, v_k), contributes
///     b += h·f + h²·K·d,        A −= h·D + h²·K                    (Baraff & Witkin 1998, eq. 16–18)
/// and an elastic element with energy E (gradient g, PSD Hessian H) and Rayleigh damping f = −β·H·v
/// contributes b_a += −h·g_a − Σ_b H_ab (h·β·v_b + h²·d_b) and A_ab += (h·β + h²)·H_ab.
///
/// The order of every floating-point operation is part of the contract: the CPU backend is
/// bit-identical across thread counts and releases, and the GPU agrees with it to float rounding.

#include "weft/math/host_device.h"
#include "weft/physics/aerodynamics.h"
#include "weft/physics/bending.h"
#include "weft/physics/collider_contact.h"
#include "weft/physics/hessian.h"
#include "weft/physics/membrane.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// A cloth's material as the implicit terms evaluate it, in scalar T (Lamé parameters for the
/// membrane; the rest as the material states them: N·m, 1/s, s, dimensionless, m).
template <typename T>
struct MaterialCoefficients {
    MembraneMaterial<T> membrane{};
    T bending{}, damping_mass{}, damping_stiffness{};
    T drag{}, lift{}, thickness{}, friction{};
};

/// The substep length h (s) and its square, formed once by the caller (the CUDA backend forms h² in
/// float from the float h, as the CPU float solver does).
template <typename T>
struct ImplicitStep {
    T h{}, h2{};
};

/// The right-hand side share h·f + h²·K·d of a force linearised about the Newton iterate.
template <typename T>
WEFT_HD inline Vec3<T> implicit_force_rhs(const ImplicitStep<T>& s, Vec3<T> force, const Mat3<T>& dfdx, Vec3<T> d) {
    return s.h * force + s.h2 * (dfdx * d);
}

/// The system-matrix share −h·D − h²·K of a force with Jacobians K = ∂f/∂x and D = ∂f/∂v.
template <typename T>
WEFT_HD inline Mat3<T> implicit_force_block(const ImplicitStep<T>& s, const Mat3<T>& dfdx, const Mat3<T>& dfdv) {
    return T(-1) * s.h * dfdv + T(-1) * s.h2 * dfdx;
}

// ---- Per vertex --------------------------------------------------------------------------------

/// Wind and time for the aerodynamic terms of a substep.
template <typename T>
struct WindField {
    bool active = false;     ///< any mean wind or turbulence
    Vec3<T> velocity{};      ///< mean wind, m/s
    T air_density{};         ///< kg/m³
    T turbulence{};          ///< gust amplitude, m/s (0: none)
    T turbulence_frequency{};  ///< Hz
    T turbulence_scale{};    ///< m
    T time{};                ///< s, the gust field's clock
};

/// The spring of a grabbed vertex (weft/grab.h): f = k·(target − x) − c·v.
template <typename T>
struct GrabSpring {
    Vec3<T> target{};  ///< m
    T stiffness{};     ///< N/m
    T damping{};       ///< N·s/m
};

/// One vertex at the Newton iterate: mass (kg), start velocity v0, iterate v_k and linearisation
/// velocity w_k (m/s), start position x0 (m), and whether it is pinned (pins get no contact or grab
/// terms: their velocity is prescribed by the solve's filter).
template <typename T>
struct VertexIterate {
    T mass{};
    Vec3<T> x0{}, v0{}, vk{}, wk{};
    bool fixed = false;
};

/// The analytic colliders of a substep at its end (their pose at t + h), with each one's friction
/// coefficient (negative: use the cloth's), and the scene's penalty stiffness (N/m; 0 picks one).
template <typename T>
struct ColliderSet {
    const Shape<T>* shapes = nullptr;
    const T* friction = nullptr;
    int count = 0;
    T stiffness{};
};

/// Penalty stiffness of a vertex against the analytic colliders: the scene's, or 100·m/h². With the
/// latter a vertex carrying its own weight sinks g·h²/100 into the contact thickness (0.03 mm at
/// 60 Hz), one carrying the tension of a whole draped sheet still well under the thickness, and the
/// diagonal block grows by 100·m, which block-Jacobi absorbs, so CG is not slowed.
template <typename T>
WEFT_HD inline T collider_penalty_stiffness(T scene_stiffness, T mass, T h2) {
    return scene_stiffness > T(0) ? scene_stiffness : T(100) * mass / h2;
}

/// Vertex terms: inertia, gravity and mass-proportional damping,
///     b = M(v0 − v_k) + h·m·g − h·α·m·v_k,   A_ii = m·(1 + h·α)·I,
/// then each analytic collider's penalty contact with smoothed Coulomb friction (a force like any
/// other: its K and D enter as above) and, when `grabbed`, the grab spring, linearised as
/// b += h·f − h²·k·d, A_ii += (h·c + h²·k)·I. Returns the number of active collider contacts.
template <typename T>
WEFT_HD inline int vertex_terms(const ImplicitStep<T>& s, const VertexIterate<T>& v, const MaterialCoefficients<T>& p,
                                Vec3<T> gravity, const ColliderSet<T>& colliders, bool grabbed,
                                const GrabSpring<T>& grab, HessianKind kind, Vec3<T>& rhs, Mat3<T>& block) {
    const T h = s.h, h2 = s.h2, m = v.mass;
    // Summed in locals and stored once: `rhs` and `block` may point into a backend's arrays, which
    // the compiler could not keep in registers across the collider calls.
    Vec3<T> row_rhs = m * (v.v0 - v.vk) + (h * m) * gravity - (h * p.damping_mass * m) * v.vk;
    Mat3<T> diagonal = Mat3<T>::diagonal(m * (T(1) + h * p.damping_mass));
    int active = 0;
    if (colliders.count > 0 && !v.fixed) {
        const Vec3<T> x = v.x0 + h * v.wk;
        const Vec3<T> d = v.vk - v.wk;
        const T k = collider_penalty_stiffness(colliders.stiffness, m, h2);
        for (int c = 0; c < colliders.count; ++c) {
            const T mu = colliders.friction[c] >= T(0) ? colliders.friction[c] : p.friction;
            const ContactParams<T> cp{k, p.thickness, mu, T(1e-3)};
            const ContactResult<T> r = collider_contact(colliders.shapes[c], cp, x, v.vk, kind);
            if (!r.active) continue;
            ++active;
            row_rhs += implicit_force_rhs(s, r.force, r.dfdx, d);
            diagonal += implicit_force_block(s, r.dfdx, r.dfdv);
        }
    }
    if (grabbed && !v.fixed) {
        const Vec3<T> x = v.x0 + h * v.wk;
        const T k = grab.stiffness, c = grab.damping;
        row_rhs += h * (k * (grab.target - x) - c * v.vk) - (h2 * k) * (v.vk - v.wk);
        diagonal += Mat3<T>::diagonal(h * c + h2 * k);
    }
    rhs = row_rhs;
    block = diagonal;
    return active;
}

// ---- Per element -------------------------------------------------------------------------------

/// What an element of N vertices adds: N right-hand-side entries and N×N blocks (row a, column b),
/// held in the element (the CUDA kernels keep them in registers). The element functions below write
/// through `rhs_at` and `block_at`, so a backend with buffers of its own passes an ElementTermsView.
template <typename T, int N>
struct ElementTerms {
    Vec3<T> rhs[N];
    Mat3<T> block[N][N];
    WEFT_HD Vec3<T>& rhs_at(int a) { return rhs[a]; }
    WEFT_HD Mat3<T>& block_at(int a, int b) { return block[a][b]; }
};

/// The same terms written straight into a backend's buffers: N right-hand sides from `rhs`, N×N
/// blocks row-major from `block` (the CPU solver's per-element slots, which it gathers per row).
template <typename T, int N>
struct ElementTermsView {
    Vec3<T>* rhs = nullptr;
    Mat3<T>* block = nullptr;
    WEFT_HD Vec3<T>& rhs_at(int a) const { return rhs[a]; }
    WEFT_HD Mat3<T>& block_at(int a, int b) const { return block[N * a + b]; }
};

/// An element's corners at the Newton iterate are passed as three arrays: positions at the
/// linearisation point x = x0 + h·w_k (m), velocities v_k (m/s) and d = v_k − w_k (m/s). Three
/// arrays rather than one struct: the element math takes the address of x only, so a compiler keeps
/// v_k and d in registers (one struct would count as escaped whole; measured 5% on the CPU).

/// The elastic element's share, from its energy gradient `grad` and PSD Hessian `H` at the
/// linearisation point, with Rayleigh stiffness damping f = −β·H·v (∂f/∂v = −β·H):
///     rhs_a = −h·grad_a − Σ_b H_ab·(h·β·v_b + h²·d_b),   block_ab = (h·β + h²)·H_ab.
template <typename T, int N, typename Out>
WEFT_HD inline void elastic_terms(const ImplicitStep<T>& s, T beta, const Vec3<T> (&grad)[N], const Mat3<T> (&H)[N][N],
                                  const Vec3<T> (&vk)[N], const Vec3<T> (&d)[N], Out& out) {
    const T h = s.h, h2 = s.h2;
    const T coef = h * beta + h2;
    for (int a = 0; a < N; ++a) {
        Vec3<T> acc = T(-1) * h * grad[a];
        for (int b = 0; b < N; ++b) acc -= H[a][b] * (h * beta * vk[b] + h2 * d[b]);
        out.rhs_at(a) = acc;
        for (int b = 0; b < N; ++b) out.block_at(a, b) = coef * H[a][b];
    }
}

/// A triangle: StVK membrane (weft/physics/membrane.h) with stiffness damping, and the wind's drag
/// and lift (weft/physics/aerodynamics.h) against the wind at its centroid. The aerodynamic force
/// acts on the triangle's mean velocity: each corner carries a third of it, h·f per corner as the
/// force is already per corner, and its PSD damping D couples every pair of corners by (h/9)·D.
template <typename T, typename Out>
WEFT_HD inline void triangle_terms(const ImplicitStep<T>& s, const T (&dm_inv)[2][2], T area,
                                   const MaterialCoefficients<T>& p, const WindField<T>& wind,
                                   const Vec3<T> (&x)[3], const Vec3<T> (&vk)[3], const Vec3<T> (&d)[3],
                                   HessianKind kind, Out& out) {
    Vec3<T> grad[3];
    Mat3<T> H[3][3];
    membrane_evaluate(dm_inv, area, p.membrane, x, grad, H, kind);
    elastic_terms<T, 3, Out>(s, p.damping_stiffness, grad, H, vk, d, out);
    if (wind.active && (p.drag > T(0) || p.lift > T(0))) {
        const Vec3<T> centroid = (x[0] + x[1] + x[2]) / T(3);
        Vec3<T> air = wind.velocity;
        if (wind.turbulence > T(0))
            air += wind_gust(centroid, wind.time, wind.turbulence, wind.turbulence_frequency, wind.turbulence_scale);
        Vec3<T> force{};
        Mat3<T> D{};
        aerodynamic_force(x, vk, air, AeroCoefficients<T>{wind.air_density, p.drag, p.lift}, force, &D);
        const T share = s.h / T(9);
        for (int a = 0; a < 3; ++a) {
            out.rhs_at(a) += s.h * force;
            for (int b = 0; b < 3; ++b) out.block_at(a, b) += share * D;
        }
    }
}

/// A triangle's centroid against the analytic colliders (SolverSettings::face_contacts): the vertex
/// contact of collider_contact at x_c = (x_0 + x_1 + x_2)/3, its force a third on each corner and
/// its Jacobians a ninth on each pair of corners (x_c's derivative by each corner is I/3). Why:
/// colliders push vertices only, and a coarse cloth over a curved collider sags between its vertices
/// by about the sagitta d²/8r of a cell of diagonal d over a radius r (9 mm for a 0.19 m cell over a
/// 0.5 m ball, more than the 5 mm contact thickness), so the collider shows through the triangles;
/// a contact at each centroid holds the cloth off it there too. `mass` is the centroid's mass for the
/// penalty stiffness (the corners' mean: the stiffness of the vertex contacts around it). Returns the
/// number of active contacts.
template <typename T, typename Out>
WEFT_HD inline int face_collider_terms(const ImplicitStep<T>& s, const ColliderSet<T>& colliders,
                                       const MaterialCoefficients<T>& p, T mass, const Vec3<T> (&x)[3],
                                       const Vec3<T> (&vk)[3], const Vec3<T> (&d)[3], HessianKind kind, Out& out) {
    const T third = T(1) / T(3);
    const Vec3<T> xc = third * (x[0] + x[1] + x[2]);
    const Vec3<T> vc = third * (vk[0] + vk[1] + vk[2]);
    const Vec3<T> dc = third * (d[0] + d[1] + d[2]);
    const T k = collider_penalty_stiffness(colliders.stiffness, mass, s.h2);
    int active = 0;
    for (int c = 0; c < colliders.count; ++c) {
        const T mu = colliders.friction[c] >= T(0) ? colliders.friction[c] : p.friction;
        const ContactResult<T> r = collider_contact(colliders.shapes[c], ContactParams<T>{k, p.thickness, mu, T(1e-3)},
                                                    xc, vc, kind);
        if (!r.active) continue;
        ++active;
        const Vec3<T> rhs = third * implicit_force_rhs(s, r.force, r.dfdx, dc);
        const Mat3<T> block = (third * third) * implicit_force_block(s, r.dfdx, r.dfdv);
        for (int a = 0; a < 3; ++a) {
            out.rhs_at(a) += rhs;
            for (int b = 0; b < 3; ++b) out.block_at(a, b) += block;
        }
    }
    return active;
}

/// A hinge: discrete bending (weft/physics/bending.h, rest angle and weight from the fabric) with
/// stiffness damping. Returns false, writing nothing, when the cloth has no bending stiffness.
template <typename T, typename Out>
WEFT_HD inline bool hinge_terms(const ImplicitStep<T>& s, T weight, T rest_angle, const MaterialCoefficients<T>& p,
                                const Vec3<T> (&x)[4], const Vec3<T> (&vk)[4], const Vec3<T> (&d)[4], HessianKind kind,
                                Out& out) {
    if (p.bending <= T(0)) return false;
    Vec3<T> grad[4];
    Mat3<T> H[4][4];
    bending_evaluate(p.bending, weight, rest_angle, x, grad, H, kind);
    elastic_terms<T, 4, Out>(s, p.damping_stiffness, grad, H, vk, d, out);
    return true;
}

// ---- Per contact pair --------------------------------------------------------------------------

/// A proximity contact's pair spring (weft/physics/pair_contact.h) in the factored form both solves
/// keep: one right-hand side h·F + h²·K·Σ w_j d_j and one block C = −h·D − h²·K, which the pair's
/// four vertices share with weights w_i·w_j. `force`, `dfdx` and `dfdv` are the spring's at the
/// weighted gap; `d` is Σ_j w_j·d_j over the cloth corners.
template <typename T>
WEFT_HD inline void pair_contact_terms(const ImplicitStep<T>& s, Vec3<T> force, const Mat3<T>& dfdx, const Mat3<T>& dfdv,
                                       Vec3<T> d, Vec3<T>& rhs, Mat3<T>& block) {
    rhs = implicit_force_rhs(s, force, dfdx, d);
    block = implicit_force_block(s, dfdx, dfdv);
}

}  // namespace weft::physics
