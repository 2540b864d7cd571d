#pragma once
/// @file
/// Continuous collision detection (CCD) of the two cloth primitive pairs over one step, with every
/// vertex moving linearly from its start position (t = 0) to its end position (t = 1):
///   vertex–face  a point p(t) against a triangle (a(t), b(t), c(t));
///   edge–edge    a segment [e0(t), e1(t)] against a segment [f0(t), f1(t)].
/// A contact is any instant at which the primitives come within the minimum separation eta ≥ 0 (m).
///
/// Method: an inclusion-based root finder in the spirit of Wang, Ferguson, Schneider, Jiang, Attene
/// & Panozzo 2021, "A large-scale benchmark and an inclusion-based algorithm for continuous collision
/// detection" (Tight-Inclusion); written from the paper's idea, not its code. The pairs meet when
/// the gap function
///   vertex–face  F(t, u, v) = p(t) − ((1 − u − v)·a(t) + u·b(t) + v·c(t)),  u, v ≥ 0, u + v ≤ 1,
///   edge–edge    F(t, u, v) = e0(t) + u·(e1(t) − e0(t)) − (f0(t) + v·(f1(t) − f0(t))),  u, v ∈ [0, 1],
/// has |F| ≤ eta for some t ∈ [0, 1]. F is multilinear in (t, u, v) (degree ≤ 1 in each), so over an
/// axis-aligned box of parameters it is a convex combination of its 8 corner values, with weights the
/// products of (1 − λ) and λ: the box's image lies in the convex hull of the corners. (A vertex–face
/// box straddling u + v = 1 uses the corners of its part inside the triangle instead; F is affine in
/// (u, v) at fixed t.) A box is excluded when that hull, widened by a rigorous bound δ_i on the
/// rounding of the corner values, provably keeps its distance from 0 above eta: per coordinate
/// (|F| ≤ eta forces |F_i| ≤ eta), in the Euclidean norm of its bounding box (so that eta acts as a
/// ball, not a cube: Tight-Inclusion's per-coordinate test alone reports contacts up to √3·eta away),
/// and along a few separating directions (the box's mean gap, the face normals of the parallelepiped
/// its image nearly is, see `ccd_directions_exclude`, and the gaps between the closest points of the
/// primitives at the box's end times). Boxes not excluded are bisected.
///
/// Search: best-first by the lower time bound t0 of the boxes, in a fixed-capacity array (no heap
/// allocation, no recursion, bounded memory and iterations: device code). The boxes left always
/// cover every contact, so the smallest t0 left is a valid answer at any moment; the search tightens
/// it from below (excluding boxes) and from above: a near contact is *certified* at a time t when the
/// rigorous bound on |F| at the closest points of the primitives at t (proximity.h) is ≤ eta +
/// distance_tolerance + 4δ. Candidate times are the box ends and a Gauss–Newton prediction of the
/// contact time from each box. Once a near contact is certified at t_c, boxes starting after it are
/// dropped, boxes reaching it are bisected in t, and the search ends (status Contact) when the
/// smallest t0 left is within t_tolerance of t_c. A box that reaches the tolerances (t-width
/// ≤ t_tolerance, and bisecting u or v would shrink its hull by less than distance_tolerance) without
/// being excluded also ends the search with status Contact. The parameter bisected is the one whose
/// variation spans most of the hull (t only while wider than t_tolerance), after trying to exclude
/// the earlier half in t. Boxes are dyadic (16 bytes each); the default 128 hold a whole dive to the
/// finest level (≤ 3 × 31 bisections). Should the queue fill anyway, the box with the latest t0 is
/// set aside and its t0 caps any later answer (QueueOverflow), so nothing is ever lost.
///
/// Guarantee (for finite inputs, eta ≥ 0, exact real arithmetic on the given floating-point
/// inputs as the reference):
///   - No false negatives. If there are t* ∈ [0, 1] and (u, v) in the domain with |F(t*, u, v)| ≤ eta,
///     the result has hit = true and toi ≤ t*. This holds for every status, including a run out of
///     iterations or queue space (then hit is reported conservatively at the smallest t0 of the
///     boxes not yet decided).
///   - toi is a lower bound of the first contact time, never later. `diag.distance_bound` is a
///     rigorous upper bound on the distance between the primitives at time `diag.contact_time` (at the
///     returned u, v). With status Contact, contact_time ∈ [toi, toi + t_tolerance] and
///       distance_bound ≤ eta + √3·(2·distance_tolerance + 8·δ + t_tolerance·D)
///     up to rounding, δ = max_i δ_i below and D the largest change of a coordinate of F over the
///     step at fixed (u, v) (≤ 4× the largest vertex displacement). A certified near contact meets
///     eta + distance_tolerance + 4δ; a box that reached the tolerances has a hull reaching within eta
///     of 0, of width ≤ the t-variation (≤ t_tolerance·D + 2δ of rounding) plus the u- and
///     v-variations (≤ distance_tolerance + 2δ each), and its corner is reported, δ more for its
///     rounding. (This needs the u/v width floor t_tolerance/16 not reached, which the automatic
///     distance tolerance guarantees; for eta below √(10⁶·min_normal), where the Euclidean test is
///     skipped, eta counts √3 times.)
///     So false positives (hit = true while the true distance stays above eta) are possible only for
///     near misses within that margin, or with status BudgetExhausted / QueueOverflow / NonFinite.
///     Callers count them; tests/physics/ccd_test.cpp measures their rate.
///
/// Rounding bound (derived in `detail::ccd_error_bound`): every corner value is computed in T from
/// inputs with |coordinate i| ≤ M_i by a fixed sequence of at most 8 dependent operations whose
/// intermediate magnitudes stay ≤ 6·M_i, giving |fl(F_i) − F_i| ≤ 50·ε·M_i (ε = machine epsilon);
/// the tests use δ_i = 64·ε·M_i plus an underflow term.

#include <cmath>

#include "weft/math/host_device.h"
#include "weft/physics/proximity.h"
#include "weft/physics/scalar.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// How a CCD query ended.
enum class CcdStatus : unsigned char {
    Separated,        ///< every box was discarded: no contact in [0, 1] (proven; hit = false)
    Contact,          ///< a near contact resolved to the tolerances (hit = true; see the file comment)
    BudgetExhausted,  ///< `max_iterations` boxes examined first: hit reported conservatively
    QueueOverflow,    ///< a box had to be set aside for lack of queue space and no earlier contact
                      ///< was resolved: hit reported conservatively at that box's t0
    NonFinite,        ///< an input is not finite or too large (|x| > max/64): hit reported at t = 0
};

/// Default tolerances per scalar. The float t tolerance is coarser because float corner values
/// carry ~1e-7·|x| of rounding noise that bisection below it cannot resolve anyway.
template <typename T>
struct CcdDefaults;
template <>
struct CcdDefaults<float> {
    static constexpr float t_tolerance = 1e-4F;
    static constexpr int max_iterations = 4096;
};
template <>
struct CcdDefaults<double> {
    static constexpr double t_tolerance = 1e-6;
    static constexpr int max_iterations = 4096;
};

/// CCD options. The defaults suit cloth in metres.
template <typename T>
struct CcdOptions {
    /// Width in t (fraction of the step, dimensionless) below which a box's time is not refined, and
    /// how far toi may lie below a certified near contact. Not below 2^−24 (float) or 2^−31 (double),
    /// the finest box level.
    T t_tolerance = CcdDefaults<T>::t_tolerance;
    /// Spatial tolerance (m): u and v stop being bisected once that would shrink the corner bounds by
    /// less than this. ≤ 0 selects t_tolerance × (the largest coordinate extent of the 8 positions).
    T distance_tolerance = T(-1);
    /// Most boxes examined before answering conservatively (BudgetExhausted); ≤ 0 answers at once.
    int max_iterations = CcdDefaults<T>::max_iterations;
};

/// Diagnostics of one CCD query.
template <typename T>
struct CcdDiagnostics {
    CcdStatus status;
    int iterations;    ///< boxes examined (popped or looked ahead at)
    int max_queue;     ///< most boxes queued at once
    int dropped;       ///< boxes set aside for lack of queue space
    T error_bound;     ///< largest rounding bound δ_i widening the inclusions (m)
    T contact_time;    ///< time at which distance_bound holds; in [toi, toi + t_tolerance] with status Contact
    T distance_bound;  ///< rigorous upper bound on the distance at (contact_time, u, v) (m); −1 if NonFinite
};

/// Result of one CCD query.
template <typename T>
struct CcdResult {
    bool hit;  ///< contact (or, with status BudgetExhausted/QueueOverflow/NonFinite, possibly one)
    T toi;     ///< conservative time of impact in [0, 1]: no contact before it; 1 when !hit
    T u, v;    ///< parameters (as in F) of the point where diag.distance_bound holds
    CcdDiagnostics<T> diag;
};

namespace detail {

/// Floating-point limits not in `ScalarTraits` (kept here so the header stays self-contained).
template <typename T>
struct CcdLimits;
template <>
struct CcdLimits<float> {
    static constexpr float min_normal = 1.17549435e-38F;  ///< 2⁻¹²⁶
    static constexpr float max_input = 5.3e36F;           ///< ≈ FLT_MAX/64
};
template <>
struct CcdLimits<double> {
    static constexpr double min_normal = 2.2250738585072014e-308;  ///< 2⁻¹⁰²²
    static constexpr double max_input = 2.8e306;                   ///< ≈ DBL_MAX/64
};

/// Rigorous bound δ on |fl(F_i) − F_i| for a corner value computed by `ccd_positions` and
/// `ccd_gap` below, where M bounds |coordinate i| of all 8 input positions.
///
/// Model: each operation returns op(x, y)(1 + θ), |θ| ≤ u = ε/2 (round to nearest), ε the machine
/// epsilon; corner parameters t, u, v ∈ [0, 1] are exact (they are bisection points). We bound with
/// ε instead of u, i.e. twice the rounding, which also absorbs every O(ε²) term below.
///   x(t) = x0 + t·d with d = fl(x1 − x0) computed once:
///     d:      |x1 − x0| ≤ 2M, error ≤ 2Mε;
///     t·d:    inherited ≤ t·2Mε, rounding ≤ 2Mε → ≤ 4Mε;
///     x0+t·d: |x(t)| ≤ M (a convex combination), rounding ≤ Mε → ≤ 5Mε.
///   vertex–face, F = ((p − a) − u·(b − a)) − v·(c − a):
///     b − a, c − a, p − a: magnitude ≤ 2M, error ≤ 5 + 5 + 2 = 12Mε;
///     u·(b − a), v·(c − a): ≤ 12 + 2 = 14Mε;
///     (p − a) − u·(b − a): magnitude ≤ 4M, ≤ 12 + 14 + 4 = 30Mε;
///     … − v·(c − a): magnitude ≤ 6M (u + v ≤ 2 inside a box), ≤ 30 + 14 + 6 = 50Mε.
///   edge–edge, F = (e0 + u·(e1 − e0)) − (f0 + v·(f1 − f0)):
///     e1 − e0: ≤ 12Mε; u·(e1 − e0): ≤ 14Mε; e0 + u·(…): magnitude ≤ M, ≤ 5 + 14 + 1 = 20Mε;
///     likewise for f; the difference: magnitude ≤ 2M, ≤ 20 + 20 + 2 = 42Mε.
/// Hence δ = 64·ε·M (≥ 50·ε·M with the factor-2 margin above). Fused multiply–adds (nvcc contracts
/// x0 + t·d and the u·(…) products by default) round once where two roundings were counted, so the
/// bound holds for them too. Gradual underflow adds an absolute error ≤ half the smallest subnormal
/// per operation and flush-to-zero ≤ the smallest normal: 16·min_normal covers the ≤ 13 operations.
/// The computation of δ itself is exact (64ε is a power of two) up to one rounding of the sum, which
/// the margin covers.
template <typename T>
WEFT_HD constexpr T ccd_error_bound(T M) {
    return T(64) * ScalarTraits<T>::epsilon * M + T(16) * CcdLimits<T>::min_normal;
}

/// One parameter box, stored as dyadic intervals so that it takes 16 bytes whatever T is: along
/// each of t, u, v the interval [i·2^−level, (i + 1)·2^−level]. Levels stop at kMaxLevel (24 for
/// float, 31 for double), where i + 1 ≤ 2^level is still exact in T: endpoints are then exact, so
/// the two halves of a box cover it exactly (no gap between [lo, mid] and [mid, hi]).
struct CcdBox {
    unsigned int t, u, v;           ///< interval indices
    unsigned char tl, ul, vl, pad;  ///< interval levels
};

template <typename T>
struct CcdMaxLevel;
template <>
struct CcdMaxLevel<float> {
    static constexpr int value = 24;
};
template <>
struct CcdMaxLevel<double> {
    static constexpr int value = 31;
};

/// Lower end of a box's t interval as a 31-bit fixed-point number: exact ordering of boxes by t0.
WEFT_HD constexpr unsigned int ccd_t0_key(const CcdBox& b) { return b.t << (31 - b.tl); }
/// Number of bisections that made the box.
WEFT_HD constexpr int ccd_depth(const CcdBox& b) { return int(b.tl) + int(b.ul) + int(b.vl); }
/// i·2^−level in T (exact: i < 2^24 for float, the power of two exact in both).
template <typename T>
WEFT_HD constexpr T ccd_dyadic(unsigned int i, int level) {
    return T(i) / T(1u << level);
}

/// Positions of the 4 moving points at time t: x(t) = x0 + t·d (d = x1 − x0 precomputed). The
/// operation order is the one `ccd_error_bound` analyses; do not reorder.
template <typename T>
WEFT_HD inline void ccd_positions(const Vec3<T> x0[4], const Vec3<T> d[4], T t, Vec3<T> x[4]) {
    for (int k = 0; k < 4; ++k) x[k] = x0[k] + t * d[k];
}

/// The gap F at (u, v) from the positions at one time: vertex–face with x = {p, a, b, c}, edge–edge
/// with x = {e0, e1, f0, f1}. The operation order is the one `ccd_error_bound` analyses.
template <bool kVertexFace, typename T>
WEFT_HD inline Vec3<T> ccd_gap(const Vec3<T> x[4], T u, T v) {
    if constexpr (kVertexFace) {
        return ((x[0] - x[1]) - u * (x[2] - x[1])) - v * (x[3] - x[1]);
    } else {
        return (x[0] + u * (x[1] - x[0])) - (x[2] + v * (x[3] - x[2]));
    }
}

template <typename T>
WEFT_HD constexpr T abs_(T x) {
    return x < T(0) ? -x : x;
}

/// Rigorous upper bound on |F| at a point whose computed gap is `g` (per-coordinate error δ):
/// ‖(|g_i| + δ_i)‖, enlarged by 16ε for the rounding of the norm itself (< 6 roundings of ε/2).
template <typename T>
WEFT_HD inline T ccd_distance_bound(Vec3<T> g, Vec3<T> delta) {
    using std::sqrt;
    const Vec3<T> a{abs_(g.x) + delta.x, abs_(g.y) + delta.y, abs_(g.z) + delta.z};
    return sqrt(dot(a, a)) * (T(1) + T(16) * ScalarTraits<T>::epsilon);
}

/// Separating-plane test of a box's corner hull against the eta-ball along the direction m (any
/// direction is sound; the caller picks a few good ones). m is scaled to a largest component of 1.
/// Rounding: with F̂ the computed corners, |m·F̂ − fl(m·F̂)| ≤ γ₃·Σ|m_i||F̂_i| ≤ 2ε·S and
/// |m·(F̂ − F)| ≤ Σ|m_i|δ_i = D, so min_k ±fl(m·F̂_k) > (eta·N + 2ε·S + D)(1 + 16ε), N ≥ |m|, proves
/// ±m·F > eta·|m| on the whole hull, hence |F| > eta (the factor 1 + 16ε covers the roundings of
/// the threshold; δ's absolute underflow term covers underflow in the dot products since |m_i| ≤ 1).
template <typename T>
WEFT_HD inline bool ccd_direction_excludes(Vec3<T> m, const Vec3<T>* P, int np, const T fmin[3], const T fmax[3],
                                           Vec3<T> delta, T eta) {
    using std::sqrt;
    constexpr T eps = ScalarTraits<T>::epsilon;
    const T mmax = max_(abs_(m.x), max_(abs_(m.y), abs_(m.z)));
    if (!(mmax > T(0)) || !(mmax < CcdLimits<T>::max_input)) return false;
    m = m / mmax;
    const T N = sqrt(dot(m, m)) * (T(1) + T(4) * eps);
    T S = T(0), D = T(0);
    for (int i = 0; i < 3; ++i) {
        S += abs_(m[i]) * max_(abs_(fmin[i]), abs_(fmax[i]));
        D += abs_(m[i]) * delta[i];
    }
    const T threshold = (eta * N + T(2) * eps * S + D) * (T(1) + T(16) * eps);
    bool above = true, below = true;
    for (int k = 0; k < np; ++k) {
        const T q = dot(m, P[k]);
        above = above && q > threshold;
        below = below && q < -threshold;
    }
    return above || below;
}

/// Candidate separating directions for a box. For a small box F is nearly affine and its image
/// nearly the parallelepiped spanned by the mean edge vectors e_t, e_u, e_v of the 8 corners F; a
/// point outside a parallelepiped is separated from it along one of its face normals e_i × e_j (e.g.
/// e_u × e_v is the triangle's normal). When the parallelepiped is flat — e_u ∥ e_v for edges that
/// are parallel, or a triangle collapsing to a segment, at the contact instant — those normals
/// vanish or all lie along the flat direction; the separating axes of the flat shape are then the
/// in-plane normals n × e_i (n the best-defined face normal), which also separate the boxes lying
/// before the contact instant along the whole line of contacts. Last, the mean of the points: the
/// gap direction at the box centre, which separates boxes along a near miss (e.g. a vertex sliding
/// over a face at a small gap) that the axis-aligned bounds only separate once they are tiny.
/// The points P (np of them; see the caller) are what is tested; the directions are only heuristics.
template <typename T>
WEFT_HD inline bool ccd_directions_exclude(const Vec3<T> F[8], const Vec3<T>* P, int np, const T fmin[3],
                                           const T fmax[3], Vec3<T> delta, T eta) {
    Vec3<T> m{}, e[3]{};
    for (int k = 0; k < np; ++k) m += P[k];
    for (int k = 0; k < 8; ++k)
        for (int dim = 0; dim < 3; ++dim)
            if ((k & (1 << dim)) == 0) e[dim] += F[k | (1 << dim)] - F[k];
    if (ccd_direction_excludes(m, P, np, fmin, fmax, delta, eta)) return true;
    const Vec3<T> normals[3] = {cross(e[1], e[2]), cross(e[0], e[1]), cross(e[0], e[2])};
    int best = 0;
    for (int j = 0; j < 3; ++j) {
        if (ccd_direction_excludes(normals[j], P, np, fmin, fmax, delta, eta)) return true;
        if (length_squared(normals[j]) > length_squared(normals[best])) best = j;
    }
    for (int dim = 0; dim < 3; ++dim)
        if (ccd_direction_excludes(cross(normals[best], e[dim]), P, np, fmin, fmax, delta, eta)) return true;
    return false;
}

/// The shared search. x0, x1: the 4 points at t = 0 and t = 1 in `ccd_gap` order.
template <bool kVertexFace, int Capacity, typename T>
WEFT_HD inline CcdResult<T> ccd_search(const Vec3<T> x0[4], const Vec3<T> x1[4], T eta, const CcdOptions<T>& opt) {
    static_assert(Capacity >= 4, "the CCD queue needs room for a few boxes");
    constexpr T eps = ScalarTraits<T>::epsilon;
    constexpr int kMaxLevel = CcdMaxLevel<T>::value;
    CcdResult<T> res{};
    res.toi = T(1);
    res.diag.status = CcdStatus::Separated;

    // Magnitudes, extent and finiteness of the inputs.
    Vec3<T> M{}, lo = x0[0], hi = x0[0];
    bool finite = true;
    for (int k = 0; k < 8; ++k) {
        const Vec3<T> x = k < 4 ? x0[k] : x1[k - 4];
        finite = finite && is_finite(x);
        for (int i = 0; i < 3; ++i) {
            M[i] = max_(M[i], abs_(x[i]));
            lo[i] = min_(lo[i], x[i]);
            hi[i] = max_(hi[i], x[i]);
        }
    }
    const T big = CcdLimits<T>::max_input;
    if (!finite || !(M.x <= big && M.y <= big && M.z <= big)) {
        res.hit = true;
        res.toi = T(0);
        res.diag.status = CcdStatus::NonFinite;
        res.diag.distance_bound = T(-1);  // no bound
        return res;
    }
    const T eta_ = eta > T(0) ? eta : T(0);  // negative or NaN → 0
    const T t_tol = opt.t_tolerance > T(0) ? min_(opt.t_tolerance, T(1)) : CcdDefaults<T>::t_tolerance;
    const T extent = max_(hi.x - lo.x, max_(hi.y - lo.y, hi.z - lo.z));
    // δ_i and the per-coordinate thresholds W_i = (eta + δ_i)(1 + 4ε): fl(fl(eta + δ)·(1 + 4ε)) ≥
    // (eta + δ)(1 − ε/2)²(1 + 4ε) > eta + δ, so the rounding of W itself cannot make a discard unsound.
    Vec3<T> delta{}, W{}, delta_w{};
    T delta_max = T(0);
    for (int i = 0; i < 3; ++i) {
        delta[i] = ccd_error_bound(M[i]);
        W[i] = (eta_ + delta[i]) * (T(1) + T(4) * eps);
        delta_w[i] = delta[i] * (T(1) + T(4) * eps);
        delta_max = max_(delta_max, delta[i]);
    }
    res.diag.error_bound = delta_max;
    // The Euclidean bounds test needs eta² well above the underflow range, where rounding is
    // relative; below it (eta ≤ 1e-16 in float) the per-coordinate test decides alone.
    const T eta_sq_w = eta_ * eta_ * (T(1) + T(32) * eps);
    const bool euclidean = eta_ * eta_ >= T(1e6) * CcdLimits<T>::min_normal;
    const T user_tol = opt.distance_tolerance > T(0) ? opt.distance_tolerance : t_tol * extent;
    // u/v refinement stops once a bisection would gain less than the spatial tolerance; the corner
    // noise (≤ 2δ per difference) is added so that boxes of width ~t_tolerance always meet it.
    const T dist_tol = user_tol + T(2) * delta_max;
    // A near contact is certified when the rigorous distance bound at a point is within this of eta;
    // 4δ leaves room for the δ in the bound itself (√3·δ at an exact contact) and for rounding.
    const T certify_tol = user_tol + T(4) * delta_max;
    // u and v are never bisected below this width (nor below 2^−kMaxLevel).
    const T uv_min = t_tol * T(0.0625);
    // Times as 31-bit fixed point (exact for the dyadic box ends).
    const auto tol_key = static_cast<unsigned int>(t_tol * T(2147483648.0));

    Vec3<T> d[4];
    for (int k = 0; k < 4; ++k) d[k] = x1[k] - x0[k];

    // Certified near contact: the earliest time t_hit (a box end) found so far at which the rigorous
    // bound on the distance is ≤ eta + certify_tol, with its parameters. Boxes starting at or after
    // t_hit cannot hold the first contact, or else it is later than a time we report anyway.
    bool have_hit = false;
    unsigned int hit_key = 0u;
    T hit_u = T(0), hit_v = T(0), hit_bound = T(0);
    // Distance bound at time t = key·2^−31 from the closest points of the primitives at t (proximity.h
    // picks the parameters, returned in u, v; the bound is rigorous whatever parameters it picks).
    auto certify = [&](unsigned int key, T& u, T& v, Vec3<T>& gap) {
        const T t = ccd_dyadic<T>(key, 31);
        Vec3<T> x[4];
        ccd_positions(x0, d, t, x);
        if constexpr (kVertexFace) {
            const PointTriangleProximity<T> q = point_triangle_proximity(x[0], x[1], x[2], x[3]);
            // Shrink by 1 − 2ε so that u + v ≤ 1 holds exactly, not only after rounding.
            u = q.u * (T(1) - T(2) * eps);
            v = q.v * (T(1) - T(2) * eps);
        } else {
            const EdgeEdgeProximity<T> q = edge_edge_proximity(x[0], x[1], x[2], x[3]);
            u = q.u;
            v = q.v;
        }
        gap = ccd_gap<kVertexFace>(x, u, v);
        const T bound = ccd_distance_bound(gap, delta);
        if (!(bound <= eta_ + certify_tol)) return false;
        if (!have_hit || key < hit_key) {
            have_hit = true;
            hit_key = key;
            hit_u = u;
            hit_v = v;
            hit_bound = bound;
        }
        return true;
    };
    // A time as a key, rounded down to the finest box level (exact in T).
    auto quantize = [&](T t) { return static_cast<unsigned int>(t * T(1u << kMaxLevel)) << (31 - kMaxLevel); };
    // Gauss–Newton predictor of a contact time in [t_lo, t_hi], started from the parameters (u, v):
    // F(t, u, v) ≈ F + F_t·Δt + F_u·Δu + F_v·Δv. Eliminating Δu, Δv (projecting with P onto the
    // complement of span(F_u, F_v)) leaves the gap r(Δt) = PF + Δt·PF_t, and the step is the earlier
    // root of |r| = eta (or, without one, the closest approach −(PF·PF_t)/|PF_t|²). For a vertex and
    // a non-degenerate triangle that is the time the vertex comes within eta of the triangle's plane;
    // it stays defined for parallel edges or a collapsed triangle (F_u ∥ F_v), where P removes one
    // direction only. Each predicted time is certified at once, and the closest parameters there start
    // the next step. A heuristic: it only decides where to look, `certify` makes any finding rigorous.
    // It finds contacts that box ends miss, e.g. the instant parallel edges touch along a segment.
    auto predict = [&](T t_lo, T t_hi, T u, T v) {
        using std::sqrt;
        T t = (t_lo + t_hi) * T(0.5);
        for (int step = 0; step < 3; ++step) {
            Vec3<T> x[4];
            ccd_positions(x0, d, t, x);
            Vec3<T> g = ccd_gap<kVertexFace>(x, u, v);
            Vec3<T> gt = ccd_gap<kVertexFace>(d, u, v);
            Vec3<T> gu, gv;
            if constexpr (kVertexFace) {
                gu = x[1] - x[2];
                gv = x[1] - x[3];
            } else {
                gu = x[1] - x[0];
                gv = x[2] - x[3];
            }
            const Vec3<T> n = cross(gu, gv);
            const T nn = length_squared(n);
            if (nn > T(1e-6) * length_squared(gu) * length_squared(gv)) {
                g = (dot(n, g) / nn) * n;
                gt = (dot(n, gt) / nn) * n;
            } else {
                const Vec3<T> w = length_squared(gu) >= length_squared(gv) ? gu : gv;
                const T ww = length_squared(w);
                if (ww > T(0)) {
                    g = g - (dot(g, w) / ww) * w;
                    gt = gt - (dot(gt, w) / ww) * w;
                }
            }
            const T qa = length_squared(gt), qb = dot(g, gt), qc = length_squared(g) - eta_ * eta_;
            if (!(qa > T(0))) return false;
            const T disc = qb * qb - qa * qc;
            const T next = t + (disc > T(0) ? (-qb - sqrt(disc)) / qa : -qb / qa);
            t = next > t_lo ? (next < t_hi ? next : t_hi) : t_lo;  // NaN → t_lo
            Vec3<T> gap;
            if (certify(quantize(t), u, v, gap)) return true;
        }
        return false;
    };
    // Answers. `report` for a box that stands for the answer: its t0 is the smallest left; the point
    // where distance_bound holds is its corner (t0, u0, v0), or for the conservative answers the
    // certified near contact if one was found. `report_certified`: toi = the smallest t0 left, within
    // t_tolerance of the certified near contact.
    auto report = [&](const CcdBox& b, CcdStatus status) {
        const T t0 = ccd_dyadic<T>(b.t, b.tl);
        Vec3<T> x[4];
        ccd_positions(x0, d, t0, x);
        res.hit = true;
        res.toi = t0;
        res.diag.status = status;
        if (have_hit && status != CcdStatus::Contact) {
            res.u = hit_u;
            res.v = hit_v;
            res.diag.contact_time = ccd_dyadic<T>(hit_key, 31);
            res.diag.distance_bound = hit_bound;
        } else {
            res.u = ccd_dyadic<T>(b.u, b.ul);
            res.v = ccd_dyadic<T>(b.v, b.vl);
            res.diag.contact_time = t0;
            res.diag.distance_bound = ccd_distance_bound(ccd_gap<kVertexFace>(x, res.u, res.v), delta);
        }
        return res;
    };
    auto report_certified = [&](unsigned int toi_key) {
        res.hit = true;
        res.toi = ccd_dyadic<T>(toi_key < hit_key ? toi_key : hit_key, 31);
        res.u = hit_u;
        res.v = hit_v;
        res.diag.status = CcdStatus::Contact;
        res.diag.contact_time = ccd_dyadic<T>(hit_key, 31);
        res.diag.distance_bound = hit_bound;
        return res;
    };

    CcdBox queue[Capacity];
    int n = 0;
    queue[n++] = CcdBox{0u, 0u, 0u, 0, 0, 0, 0};
    res.diag.max_queue = 1;
    // The box set aside with the smallest t0 (boxes are set aside when the queue is full): a contact
    // may hide in it, so no time at or after its t0 can be reported as "first", and it becomes the
    // conservative answer if the search gets there.
    bool have_dropped = false;
    CcdBox dropped{};
    auto push = [&](const CcdBox& b) {
        // A box entirely beyond the hypotenuse u + v = 1 holds no vertex–face contact (exact integer
        // test of u0 + v0 > 1 in units of 2^−31).
        if (kVertexFace && (static_cast<unsigned long long>(b.u) << (31 - b.ul)) +
                                   (static_cast<unsigned long long>(b.v) << (31 - b.vl)) >
                               (1ull << 31))
            return;
        if (have_hit && ccd_t0_key(b) >= hit_key) return;  // starts after a certified near contact
        CcdBox keep = b;
        if (n < Capacity) {
            queue[n++] = keep;
        } else {  // full: set aside the latest box (largest t0) of the queue and the new one
            int worst = -1;
            unsigned int worst_t = ccd_t0_key(keep);
            for (int i = 0; i < n; ++i)
                if (ccd_t0_key(queue[i]) > worst_t) {
                    worst_t = ccd_t0_key(queue[i]);
                    worst = i;
                }
            if (worst >= 0) {
                const CcdBox tmp = queue[worst];
                queue[worst] = keep;
                keep = tmp;
            }
            ++res.diag.dropped;
            if (!have_dropped || ccd_t0_key(keep) < ccd_t0_key(dropped)) dropped = keep;
            have_dropped = true;
        }
        res.diag.max_queue = n > res.diag.max_queue ? n : res.diag.max_queue;
    };

    // Corner values F of a box (corner k: t = bit 0, u = bit 1, v = bit 2 of k) and whether the box
    // is excluded: provably holds no point with |F| ≤ eta.
    struct Hull {
        Vec3<T> F[8];  // corner values; corner k has t = bit 0, u = bit 1, v = bit 2 of k
        Vec3<T> P[10];
        int np;
        T fmin[3], fmax[3];
    };
    auto evaluate = [&](const CcdBox& b, Hull& h) {
        Vec3<T>* F = h.F;
        Vec3<T>* P = h.P;
        T* fmin = h.fmin;
        T* fmax = h.fmax;
        const T t0 = ccd_dyadic<T>(b.t, b.tl), t1 = ccd_dyadic<T>(b.t + 1u, b.tl);
        const T u0 = ccd_dyadic<T>(b.u, b.ul), u1 = ccd_dyadic<T>(b.u + 1u, b.ul);
        const T v0 = ccd_dyadic<T>(b.v, b.vl), v1 = ccd_dyadic<T>(b.v + 1u, b.vl);
        // Points whose convex hull holds the image of the box ∩ domain: the 8 corners, except for a
        // vertex–face box straddling the hypotenuse u + v = 1, where the corners beyond it are
        // replaced by the crossings of the box's edges with it. (Keeping them would let the values
        // outside the triangle, beyond a vertex or an edge, block the exclusion of every box along
        // the hypotenuse.) At fixed t, F is affine in (u, v), so the image of the clipped square is
        // the hull of its ≤ 5 vertices; between t0 and t1 it interpolates linearly. The crossings
        // 1 − u1, 1 − v0, … are exact (dyadic with ≤ kMaxLevel bits).
        int& np = h.np;
        np = 0;
        {
            Vec3<T> xa[4], xb[4];
            ccd_positions(x0, d, t0, xa);
            ccd_positions(x0, d, t1, xb);
            for (int k = 0; k < 8; ++k)
                F[k] = ccd_gap<kVertexFace>((k & 1) != 0 ? xb : xa, (k & 2) != 0 ? u1 : u0, (k & 4) != 0 ? v1 : v0);
            // Exact test of u + v ≤ 1 for dyadic u = iu·2^−lu, v = iv·2^−lv, in units of 2^−31.
            auto inside = [](unsigned long long iu, int lu, unsigned long long iv, int lv) {
                return (iu << (31 - lu)) + (iv << (31 - lv)) <= (1ull << 31);
            };
            if (!kVertexFace || inside(b.u + 1ull, b.ul, b.v + 1ull, b.vl)) {
                for (int k = 0; k < 8; ++k) P[np++] = F[k];
            } else {
                const bool in_u1v0 = inside(b.u + 1ull, b.ul, b.v, b.vl);
                const bool in_u0v1 = inside(b.u, b.ul, b.v + 1ull, b.vl);
                T pu[5], pv[5];
                int nq = 0;
                auto add = [&](T u, T v) {
                    pu[nq] = u;
                    pv[nq] = v;
                    ++nq;
                };
                add(u0, v0);  // in the domain, or the box would not have been queued
                if (in_u1v0) {
                    add(u1, v0);
                    add(u1, T(1) - u1);
                } else {
                    add(T(1) - v0, v0);
                }
                if (in_u0v1) {
                    add(T(1) - v1, v1);
                    add(u0, v1);
                } else {
                    add(u0, T(1) - u0);
                }
                for (int q = 0; q < nq; ++q) {
                    P[np++] = ccd_gap<kVertexFace>(xa, pu[q], pv[q]);
                    P[np++] = ccd_gap<kVertexFace>(xb, pu[q], pv[q]);
                }
            }
        }
        // Discard tests. Per coordinate: the bounds of the points widened by W exclude 0.
        bool excluded = false;
        for (int i = 0; i < 3; ++i) {
            fmin[i] = fmax[i] = P[0][i];
            for (int k = 1; k < np; ++k) {
                fmin[i] = min_(fmin[i], P[k][i]);
                fmax[i] = max_(fmax[i], P[k][i]);
            }
            excluded = excluded || fmin[i] > W[i] || fmax[i] < -W[i];
        }
        // Euclidean: the distance from 0 to the box [fmin − δ, fmax + δ] exceeds eta. The gaps are
        // computed with δ' = δ(1 + 4ε) ≥ δ, so a positive computed gap g' satisfies g' ≤ (1 + u)·g
        // (u = ε/2) for the exact gap g; the sum of squares adds ≤ 3 roundings and eta² one, and the
        // factor (1 + 32ε) on eta² absorbs all of them: a discard here implies Σ g² > eta² exactly.
        if (!excluded && euclidean) {
            T sum = T(0);
            for (int i = 0; i < 3; ++i) {
                const T g = max_(T(0), max_(fmin[i] - delta_w[i], -fmax[i] - delta_w[i]));
                sum += g * g;
            }
            excluded = sum > eta_sq_w;
        }
        // A separating plane between the hull of the points and the eta-ball.
        if (!excluded) excluded = ccd_directions_exclude(F, P, np, fmin, fmax, delta, eta_);
        return excluded;
    };

    while (n > 0) {
        // Pop the box with the smallest t0; among equal t0 the deepest (a depth-first dive).
        int best = 0;
        unsigned int best_key = ccd_t0_key(queue[0]);
        for (int i = 1; i < n; ++i) {
            const unsigned int key = ccd_t0_key(queue[i]);
            if (key < best_key || (key == best_key && ccd_depth(queue[i]) > ccd_depth(queue[best]))) {
                best = i;
                best_key = key;
            }
        }
        // Every contact left is at t ≥ lb, the smallest t0 of the boxes queued or set aside: within
        // t_tolerance of a certified near contact, done.
        const bool lb_dropped = have_dropped && ccd_t0_key(dropped) <= best_key;
        const unsigned int lb = lb_dropped ? ccd_t0_key(dropped) : best_key;
        if (have_hit && lb + tol_key >= hit_key) return report_certified(lb);
        if (lb_dropped) return report(dropped, CcdStatus::QueueOverflow);
        if (res.diag.iterations >= opt.max_iterations) return report(queue[best], CcdStatus::BudgetExhausted);
        const CcdBox b = queue[best];
        queue[best] = queue[--n];
        ++res.diag.iterations;

        const T t0 = ccd_dyadic<T>(b.t, b.tl), t1 = ccd_dyadic<T>(b.t + 1u, b.tl);
        const T u0 = ccd_dyadic<T>(b.u, b.ul), u1 = ccd_dyadic<T>(b.u + 1u, b.ul);
        const T v0 = ccd_dyadic<T>(b.v, b.vl), v1 = ccd_dyadic<T>(b.v + 1u, b.vl);
        Hull h;
        if (evaluate(b, h)) continue;
        const Vec3<T>* F = h.F;

        // Not excluded: look for a certified near contact at the box's ends. At t0 it ends the search
        // (t0 is the smallest time left); at t1 it bounds the search from above. The gaps between
        // the closest points at t0 and t1 are two more candidate separating directions: the best
        // ones when the primitives pass each other without turning (then one plane separates them
        // throughout the step, e.g. parallel edges sliding past each other at a small gap).
        const unsigned int key0 = ccd_t0_key(b), key1 = key0 + (1u << (31 - b.tl));
        {
            T u = T(0), v = T(0);
            Vec3<T> gap;
            if (certify(key0, u, v, gap)) return report_certified(key0);
            if (ccd_direction_excludes(gap, h.P, h.np, h.fmin, h.fmax, delta, eta_)) continue;
            if (!certify(key1, u, v, gap) && ccd_direction_excludes(gap, h.P, h.np, h.fmin, h.fmax, delta, eta_))
                continue;
            if (!have_hit || key0 + tol_key < hit_key) predict(t0, t1, (u0 + u1) * T(0.5), (v0 + v1) * T(0.5));
        }

        // How much of the corner bounds each parameter's variation accounts for: the largest change
        // of a coordinate along the 4 box edges in that direction.
        T c[3] = {T(0), T(0), T(0)};
        for (int k = 0; k < 8; ++k)
            for (int dim = 0; dim < 3; ++dim) {
                const int bit = 1 << dim;
                if ((k & bit) != 0) continue;
                const Vec3<T> g = F[k | bit] - F[k];
                c[dim] = max_(c[dim], max_(abs_(g.x), max_(abs_(g.y), abs_(g.z))));
            }
        const bool split_t = t1 - t0 > t_tol && b.tl < kMaxLevel;
        const bool split_u = c[1] > dist_tol && u1 - u0 > uv_min && b.ul < kMaxLevel;
        const bool split_v = c[2] > dist_tol && v1 - v0 > uv_min && b.vl < kMaxLevel;
        // Resolved to the tolerances and still not excluded: report it (a near contact within the
        // bound of the file comment, though none was certified at its ends).
        if (!split_t && !split_u && !split_v) return report(b, CcdStatus::Contact);

        // Which parameter to bisect: t for a box reaching a certified near contact (bisecting u or v
        // cannot exclude the part holding it; bisecting t can exclude the part before it); otherwise
        // the one whose variation spans the most of the corner bounds, t only while wider than
        // t_tolerance.
        int dim = 0;
        const bool straddles = have_hit && key1 >= hit_key;
        if (!split_t ||
            (!straddles && (split_u || split_v) && c[0] < max_(split_u ? c[1] : T(0), split_v ? c[2] : T(0))))
            dim = split_u && (!split_v || c[1] >= c[2]) ? 1 : 2;
        auto half = [&](int along, unsigned int side) {
            CcdBox child = b;
            if (along == 0) {
                child.t = 2u * b.t + side;
                child.tl = static_cast<unsigned char>(b.tl + 1);
            } else if (along == 1) {
                child.u = 2u * b.u + side;
                child.ul = static_cast<unsigned char>(b.ul + 1);
            } else {
                child.v = 2u * b.v + side;
                child.vl = static_cast<unsigned char>(b.vl + 1);
            }
            return child;
        };
        // Look-ahead: when u or v was picked but t could be bisected too, try excluding the earlier
        // half in t first. Excluding it is direct progress (the search advances in t), and where the
        // box straddles a contact manifold (parallel edges, a collapsing triangle: contacts along a
        // whole line of (u, v) at one instant) bisecting u or v would only multiply the boxes.
        if (dim != 0 && split_t) {
            const CcdBox early = half(0, 0u);
            ++res.diag.iterations;
            Hull g;
            if (evaluate(early, g)) {
                push(half(0, 1u));
                continue;
            }
        }
        push(half(dim, 1u));
        push(half(dim, 0u));
    }
    // Queue empty: what is left is the set-aside boxes and the certified near contact.
    if (have_dropped && (!have_hit || ccd_t0_key(dropped) + tol_key < hit_key))
        return report(dropped, CcdStatus::QueueOverflow);
    if (have_hit)
        return report_certified(have_dropped && ccd_t0_key(dropped) < hit_key ? ccd_t0_key(dropped) : hit_key);
    return res;  // Separated: every box discarded
}

}  // namespace detail

/// Vertex–face CCD: point p against triangle (a, b, c), each vertex moving linearly from its `_0`
/// position (t = 0) to its `_1` position (t = 1), positions in m; contact when the distance is
/// ≤ eta (m, ≥ 0; negative is read as 0). Guarantees and tolerances in the file comment.
/// `Capacity` is the number of boxes the fixed queue holds (16 bytes each: 2 KiB by default).
template <typename T, int Capacity = 128>
WEFT_HD inline CcdResult<T> vertex_face_ccd(Vec3<T> p_0, Vec3<T> a_0, Vec3<T> b_0, Vec3<T> c_0, Vec3<T> p_1,
                                            Vec3<T> a_1, Vec3<T> b_1, Vec3<T> c_1, T eta,
                                            const CcdOptions<T>& options = CcdOptions<T>{}) {
    const Vec3<T> x0[4] = {p_0, a_0, b_0, c_0};
    const Vec3<T> x1[4] = {p_1, a_1, b_1, c_1};
    return detail::ccd_search<true, Capacity>(x0, x1, eta, options);
}

/// Edge–edge CCD: segment [e0, e1] against segment [f0, f1], each endpoint moving linearly from its
/// `_0` position (t = 0) to its `_1` position (t = 1), positions in m; contact when the distance is
/// ≤ eta (m, ≥ 0). u (on e) and v (on f) in the result follow F. Guarantees in the file comment.
template <typename T, int Capacity = 128>
WEFT_HD inline CcdResult<T> edge_edge_ccd(Vec3<T> e0_0, Vec3<T> e1_0, Vec3<T> f0_0, Vec3<T> f1_0, Vec3<T> e0_1,
                                          Vec3<T> e1_1, Vec3<T> f0_1, Vec3<T> f1_1, T eta,
                                          const CcdOptions<T>& options = CcdOptions<T>{}) {
    const Vec3<T> x0[4] = {e0_0, e1_0, f0_0, f1_0};
    const Vec3<T> x1[4] = {e0_1, e1_1, f0_1, f1_1};
    return detail::ccd_search<false, Capacity>(x0, x1, eta, options);
}

}  // namespace weft::physics
