#pragma once
/// @file
/// Exact orientation predicates on double coordinates: `orient2d` and `orient3d` return the sign of
/// a 2×2 / 3×3 determinant exactly, for every finite double input. They are what the exact
/// triangle–triangle test (`weft/physics/triangle_intersection.h`) and the whole-mesh intersection
/// check are built on: a yes/no answer about the final state must not depend on rounding.
///
/// **Host only.** Unlike the rest of `weft/physics/`, nothing here is `WEFT_HD`: the exact stages
/// use `std::fma`, `std::frexp` and stack arrays of a few kilobytes, and the check runs on the CPU.
///
/// How the exact sign is obtained, in three tiers (written from scratch after the ideas of Shewchuk,
/// "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric Predicates", 1997):
///
/// 1. **Filter.** When every coordinate is 0 or has a magnitude in [2^-267, 2^320] (the *window*,
///    which any physical scene in metres is far inside), the determinant is evaluated in plain double
///    arithmetic together with its *permanent* (the same expression over absolute values). A rounding
///    error analysis (below, at the constants) bounds |computed − exact| by c·permanent, so if
///    |computed| exceeds that bound the computed sign is the exact one. A zero permanent means that
///    every term is exactly zero. Almost every call ends here.
/// 2. **Expansions.** Otherwise the determinant is evaluated exactly as a floating-point expansion
///    (a sum of doubles with non-overlapping bits, Shewchuk §2): the coordinate differences are split
///    exactly into (rounded difference, rounding error) by TwoSum, every monomial of the determinant
///    is multiplied out exactly with TwoProduct (`std::fma`), and all pieces are accumulated without
///    error by Grow-Expansion. The sign of a non-overlapping expansion is the sign of its largest
///    component. The window guarantees that no product underflows or overflows, the one thing that
///    would make TwoProduct inexact (see `kWindowLow`).
/// 3. **Big integers.** Outside the window (coordinates beyond 2^320 or closer to zero than 2^-267,
///    e.g. 1e300 next to 1e-300), every input is rescaled to an integer by the same power of two and
///    the determinant is computed with a small fixed-capacity big-integer type. Slow, but only
///    reachable with absurd coordinates; it is what makes the result exact for *all* finite inputs.
///
/// Requirements: IEEE-754 binary64 with round-to-nearest-even and gradual underflow (no flush-to-zero,
/// no `-ffast-math`; checked below where the compiler tells), and no extended-precision evaluation
/// (FLT_EVAL_METHOD == 0). The error bounds do not rely on fused multiply-adds (Weft builds the host
/// with -ffp-contract=off); the only FMAs are the explicit `std::fma` calls of TwoProduct, which are
/// exact whatever the hardware. Inputs must be finite (NaN or infinity give an unspecified sign).

#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <limits>

#include "weft/physics/vec.h"

#if defined(__FAST_MATH__)
#error "weft/physics/predicates.h needs IEEE-754 semantics: do not compile it with -ffast-math"
#endif
static_assert(FLT_EVAL_METHOD == 0, "predicates.h needs doubles evaluated in double precision (no x87)");
static_assert(std::numeric_limits<double>::is_iec559 && std::numeric_limits<double>::digits == 53,
              "predicates.h needs IEEE-754 binary64 doubles");

namespace weft::physics {

namespace predicates_detail {

/// Unit roundoff of double: |fl(x ∘ y) − x ∘ y| ≤ kEps·|x ∘ y| for a result in the normal range.
inline constexpr double kEps = 0x1p-53;

/// The window of coordinates for which tiers 1 and 2 are exact (see the file comment).
///
/// Why these bounds: a nonzero coordinate |x| ≥ 2^-267 is an integer multiple of 2^-319 (its ulp),
/// so every degree-k quantity formed from the coordinates (the differences, products, and the
/// roundings and rounding errors of those) is a multiple of 2^-319k: a nonzero one is at least
/// 2^-957 in magnitude for k ≤ 3. That keeps every result of the filter in the normal range (its
/// error analysis assumes no underflow; the bound itself, ≈2^-50·permanent ≥ 2^-1007, too), and it
/// keeps every TwoProduct error term representable (an error term is a multiple of 2^-957, far
/// above the subnormal quantum 2^-1074, with at most 53 significant bits). With |x| ≤ 2^320,
/// differences are below 2^321, degree-3 products below 2^963 and every sum below 2^971: no
/// overflow.
inline constexpr double kWindowLow = 0x1p-267;
inline constexpr double kWindowHigh = 0x1p+320;

/// Filter constants. Error analysis (standard model fl(x∘y) = (x∘y)(1+δ), |δ| ≤ u = kEps, valid
/// because nothing under- or overflows in the window; γ_n = n·u/(1−n·u)):
///
/// orient3d. Each of the six monomials of the determinant passes through at most 8 roundings: its
/// three coordinate differences (one each), the inner product and the inner subtraction, the outer
/// product, and two of the three outer additions. So det_fl = Σ m_i(1+θ_i) with |θ_i| ≤ γ8 and
/// |det_fl − det| ≤ γ8·P, P = Σ|m_i| the exact permanent. The permanent computed with the same
/// operation tree over |·| satisfies P_fl ≥ (1−γ8)·P, and the bound is itself rounded once
/// (a factor ≥ 1−u). Hence the test |det_fl| > fl(c·P_fl) is safe when
/// c ≥ γ8 / ((1−γ8)(1−u)) = 8u(1 + 17u + O(u²)); c = 8u(1 + 2^-43) is larger, and exact.
///
/// orient2d. Each of the two monomials sees 4 roundings (two differences, a product, the final
/// subtraction), the permanent likewise: c ≥ γ4 / ((1−γ4)(1−u)) = 4u(1 + 9u + O(u²)); 4u(1 + 2^-43).
inline constexpr double kOrient3dBound = 8.0 * kEps * (1.0 + 0x1p-43);
inline constexpr double kOrient2dBound = 4.0 * kEps * (1.0 + 0x1p-43);

inline bool in_window(double x) {
    const double m = std::fabs(x);
    return m == 0.0 || (m >= kWindowLow && m <= kWindowHigh);
}

inline int sign_of(double x) { return (x > 0.0) - (x < 0.0); }

// ---- Error-free transformations ------------------------------------------------------------------

/// s = fl(a + b) and e with s + e == a + b exactly (Knuth's branch-free TwoSum). Exact for all finite
/// a, b whose sum does not overflow, subnormals included: the rounding error of an addition is
/// always a representable double.
inline void two_sum(double a, double b, double& s, double& e) {
    s = a + b;
    const double b_virtual = s - a;
    const double a_virtual = s - b_virtual;
    e = (a - a_virtual) + (b - b_virtual);
}

/// p = fl(a·b) and e with p + e == a·b exactly, provided the error term is representable (no
/// underflow of it; guaranteed in the window, see `kWindowLow`). The explicit fma computes a·b − p
/// with a single rounding, which is exact when a·b − p is representable.
inline void two_product(double a, double b, double& p, double& e) {
    p = a * b;
    e = std::fma(a, b, -p);
}

/// An exact sum of doubles kept as a non-overlapping expansion: components in increasing magnitude,
/// no zeros, each one's lowest set bit above the highest set bit of the one before (Shewchuk §2.3).
/// `N` must exceed the number of `add` calls (each call lengthens it by at most one component).
template <int N>
struct Expansion {
    double c[N];
    int n = 0;

    /// Adds `b` exactly. Grow-Expansion with zero elimination: b is carried up through the
    /// components with TwoSum, each rounding error left behind as a component. By Shewchuk's
    /// Theorem 10 the result is again non-overlapping and increasing, so the invariant holds.
    void add(double b) {
        if (b == 0.0) return;
        double q = b;
        int m = 0;
        for (int i = 0; i < n; ++i) {
            double s = 0.0, e = 0.0;
            two_sum(q, c[i], s, e);
            if (e != 0.0) c[m++] = e;  // m ≤ i: never overwrites a component not yet read
            q = s;
        }
        if (q != 0.0) c[m++] = q;
        n = m;
    }

    /// Sign of the exact sum. The largest component outweighs all the others together (their bits
    /// lie strictly below its lowest set bit), so its sign is the sign of the sum.
    [[nodiscard]] int sign() const { return n == 0 ? 0 : sign_of(c[n - 1]); }
};

/// Adds the exact product x·y·z, negated when `negate`, to `acc`. x·y = p + e exactly; then p·z
/// and e·z are two more exact TwoProducts, four components in all. Only valid in the window.
template <int N>
inline void add_triple_product(Expansion<N>& acc, double x, double y, double z, bool negate) {
    double p = 0.0, e = 0.0, p1 = 0.0, e1 = 0.0, p2 = 0.0, e2 = 0.0;
    two_product(x, y, p, e);
    two_product(p, z, p1, e1);
    two_product(e, z, p2, e2);
    if (negate) {
        p1 = -p1;
        e1 = -e1;
        p2 = -p2;
        e2 = -e2;
    }
    acc.add(e1);
    acc.add(e2);
    acc.add(p2);
    acc.add(p1);
}

/// Tier 2 of orient3d: exact sign of det[u; v; w] where u = b−a, v = c−a, w = d−a, all inputs in the
/// window. Each difference is the exact pair (hi, lo) from TwoSum, so det is a sum of
/// 6 monomials × 2³ combinations of parts; zero parts (the common case: differences of nearby
/// doubles are exact by Sterbenz's lemma) are skipped.
inline int orient3d_expansion(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c,
                              const Vec3<double>& d) {
    double r[3][3][2];  // r[row][axis][hi/lo], rows u, v, w
    const Vec3<double>* pts[3] = {&b, &c, &d};
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) two_sum((*pts[i])[k], -a[k], r[i][k][0], r[i][k][1]);
    // det = Σ over permutations σ of the rows: sgn(σ) · r[σ0].x · r[σ1].y · r[σ2].z
    static constexpr int kPerm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {1, 0, 2}, {2, 1, 0}};
    Expansion<6 * 8 * 4 + 1> acc;
    for (int s = 0; s < 6; ++s) {
        const bool negate = s >= 3;  // the last three permutations are odd
        for (int i = 0; i < 2; ++i) {
            const double x = r[kPerm[s][0]][0][i];
            if (x == 0.0) continue;
            for (int j = 0; j < 2; ++j) {
                const double y = r[kPerm[s][1]][1][j];
                if (y == 0.0) continue;
                for (int k = 0; k < 2; ++k) {
                    const double z = r[kPerm[s][2]][2][k];
                    if (z == 0.0) continue;
                    add_triple_product(acc, x, y, z, negate);
                }
            }
        }
    }
    return acc.sign();
}

/// Tier 2 of orient2d: exact sign of (a−c)×(b−c) with every input in the window.
inline int orient2d_expansion(const Vec2<double>& a, const Vec2<double>& b, const Vec2<double>& c) {
    double ac[2][2], bc[2][2];  // [axis][hi/lo]
    two_sum(a.x, -c.x, ac[0][0], ac[0][1]);
    two_sum(a.y, -c.y, ac[1][0], ac[1][1]);
    two_sum(b.x, -c.x, bc[0][0], bc[0][1]);
    two_sum(b.y, -c.y, bc[1][0], bc[1][1]);
    Expansion<2 * 4 * 2 + 1> acc;
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) {
            double p = 0.0, e = 0.0;
            two_product(ac[0][i], bc[1][j], p, e);  // + acx·bcy
            acc.add(e);
            acc.add(p);
            two_product(ac[1][i], bc[0][j], p, e);  // − acy·bcx
            acc.add(-e);
            acc.add(-p);
        }
    return acc.sign();
}

// ---- Tier 3: big integers ------------------------------------------------------------------------

/// Signed integer of up to 32·kLimbs bits, magnitude in little-endian 32-bit limbs. Just enough
/// arithmetic (add, subtract, multiply) for a 3×3 determinant of doubles scaled to integers:
/// a finite double is m·2^e with an odd 53-bit m and e ≥ −1074, below 2^1024, so after scaling
/// every input by 2^(−e_min) it is an integer below 2^2098; differences stay below 2^2099, degree-3
/// products below 2^6297, and the six-term sum below 2^6300 < 2^(32·197).
struct BigInt {
    static constexpr int kLimbs = 204;
    std::uint32_t limb[kLimbs];
    int n = 0;  ///< limbs in use; limb[n−1] != 0 unless n == 0 (the value zero)
    bool negative = false;

    [[nodiscard]] int sign() const { return n == 0 ? 0 : (negative ? -1 : 1); }
};

/// |a| <=> |b|: −1, 0 or 1.
inline int compare_magnitude(const BigInt& a, const BigInt& b) {
    if (a.n != b.n) return a.n < b.n ? -1 : 1;
    for (int i = a.n - 1; i >= 0; --i)
        if (a.limb[i] != b.limb[i]) return a.limb[i] < b.limb[i] ? -1 : 1;
    return 0;
}

inline void trim(BigInt& r) {
    while (r.n > 0 && r.limb[r.n - 1] == 0) --r.n;
    if (r.n == 0) r.negative = false;
}

/// r = |a| + |b| (r's sign is left to the caller). r may alias neither a nor b.
inline void add_magnitude(const BigInt& a, const BigInt& b, BigInt& r) {
    const int n = std::max(a.n, b.n);
    std::uint64_t carry = 0;
    for (int i = 0; i < n; ++i) {
        const std::uint64_t s = carry + (i < a.n ? a.limb[i] : 0u) + (i < b.n ? b.limb[i] : 0u);
        r.limb[i] = static_cast<std::uint32_t>(s);
        carry = s >> 32;
    }
    r.n = n;
    if (carry != 0) r.limb[r.n++] = static_cast<std::uint32_t>(carry);
}

/// r = |a| − |b| for |a| ≥ |b|.
inline void subtract_magnitude(const BigInt& a, const BigInt& b, BigInt& r) {
    std::int64_t borrow = 0;
    for (int i = 0; i < a.n; ++i) {
        std::int64_t d = std::int64_t{a.limb[i]} - (i < b.n ? std::int64_t{b.limb[i]} : 0) - borrow;
        borrow = d < 0 ? 1 : 0;
        if (d < 0) d += std::int64_t{1} << 32;
        r.limb[i] = static_cast<std::uint32_t>(d);
    }
    r.n = a.n;
}

/// r = a + b (b negated when `subtract`). r may alias neither a nor b.
inline void add(const BigInt& a, const BigInt& b, bool subtract, BigInt& r) {
    const bool b_negative = subtract ? !b.negative : b.negative;
    if (a.negative == b_negative || b.n == 0) {
        add_magnitude(a, b, r);
        r.negative = a.negative;
        if (a.n == 0) r.negative = b_negative;
    } else if (compare_magnitude(a, b) >= 0) {
        subtract_magnitude(a, b, r);
        r.negative = a.negative;
    } else {
        subtract_magnitude(b, a, r);
        r.negative = b_negative;
    }
    trim(r);
}

/// r = a·b (schoolbook; a 32×32-bit product plus two 32-bit carries fits in 64 bits).
inline void multiply(const BigInt& a, const BigInt& b, BigInt& r) {
    if (a.n == 0 || b.n == 0) {
        r.n = 0;
        r.negative = false;
        return;
    }
    r.n = a.n + b.n;
    std::fill(r.limb, r.limb + r.n, 0u);
    for (int i = 0; i < a.n; ++i) {
        std::uint64_t carry = 0;
        for (int j = 0; j < b.n; ++j) {
            const std::uint64_t t = std::uint64_t{a.limb[i]} * b.limb[j] + r.limb[i + j] + carry;
            r.limb[i + j] = static_cast<std::uint32_t>(t);
            carry = t >> 32;
        }
        r.limb[i + b.n] = static_cast<std::uint32_t>(carry);
    }
    r.negative = a.negative != b.negative;
    trim(r);
}

/// Splits a finite nonzero x into x = m·2^e with m an odd integer, |m| < 2^53.
inline void decompose(double x, std::int64_t& m, int& e) {
    int exponent = 0;
    const double fraction = std::frexp(x, &exponent);         // x = fraction·2^exponent, 0.5 ≤ |fraction| < 1
    m = static_cast<std::int64_t>(std::ldexp(fraction, 53));  // exact: fraction has 53 bits
    e = exponent - 53;
    const int zeros = std::countr_zero(static_cast<std::uint64_t>(m < 0 ? -m : m));
    m /= std::int64_t{1} << zeros;  // exact: divides out trailing zero bits
    e += zeros;
}

/// x·2^(−e_min) as a BigInt (an integer, because e_min is at most x's own exponent e).
inline void from_double(double x, int e_min, BigInt& r) {
    r.n = 0;
    r.negative = x < 0.0;
    if (x == 0.0) {
        r.negative = false;
        return;
    }
    std::int64_t m = 0;
    int e = 0;
    decompose(x, m, e);
    const auto mag = static_cast<std::uint64_t>(m < 0 ? -m : m);
    const int shift = e - e_min;
    const int limb_shift = shift / 32, bit_shift = shift % 32;
    std::fill(r.limb, r.limb + limb_shift, 0u);
    // mag < 2^53 shifted by bit_shift < 32 spans at most 85 bits: three limbs.
    const std::uint64_t low = mag << bit_shift;                               // bits 0..63
    const std::uint64_t high = bit_shift == 0 ? 0 : mag >> (64 - bit_shift);  // bits 64..84
    r.limb[limb_shift] = static_cast<std::uint32_t>(low);
    r.limb[limb_shift + 1] = static_cast<std::uint32_t>(low >> 32);
    r.limb[limb_shift + 2] = static_cast<std::uint32_t>(high);
    r.n = limb_shift + 3;
    trim(r);
    r.negative = x < 0.0;
}

/// The smallest exponent e over the nonzero inputs written as m·2^e with m odd; every input is
/// then an integer multiple of 2^e_min.
inline int min_exponent(const double* v, int count) {
    int e_min = 1 << 20;
    for (int i = 0; i < count; ++i) {
        if (v[i] == 0.0) continue;
        std::int64_t m = 0;
        int e = 0;
        decompose(v[i], m, e);
        e_min = std::min(e_min, e);
    }
    return e_min;
}

/// Tier 3 of orient3d: exact for any finite inputs. Same determinant as the other tiers.
inline int orient3d_bigint(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c, const Vec3<double>& d) {
    const double v[12] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z};
    const int e_min = min_exponent(v, 12);
    BigInt r[3][3];  // rows u = b−a, v = c−a, w = d−a
    BigInt p, q;     // scratch
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) {
            from_double(v[3 * (i + 1) + k], e_min, p);
            from_double(v[k], e_min, q);
            add(p, q, true, r[i][k]);
        }
    // det = u.x (v.y w.z − v.z w.y) + v.x (w.y u.z − w.z u.y) + w.x (u.y v.z − u.z v.y)
    BigInt sums[2], minor, term;  // the running sum alternates between sums[0] and sums[1]
    sums[0].n = 0;
    sums[0].negative = false;
    for (int i = 0; i < 3; ++i) {
        const BigInt(&s)[3] = r[(i + 1) % 3];
        const BigInt(&t)[3] = r[(i + 2) % 3];
        multiply(s[1], t[2], p);
        multiply(s[2], t[1], q);
        add(p, q, true, minor);
        multiply(r[i][0], minor, term);
        add(sums[i % 2], term, false, sums[(i + 1) % 2]);
    }
    return sums[1].sign();
}

/// Tier 3 of orient2d: exact for any finite inputs.
inline int orient2d_bigint(const Vec2<double>& a, const Vec2<double>& b, const Vec2<double>& c) {
    const double v[6] = {a.x, a.y, b.x, b.y, c.x, c.y};
    const int e_min = min_exponent(v, 6);
    BigInt d[4], p, q, det;  // d: a.x−c.x, a.y−c.y, b.x−c.x, b.y−c.y
    for (int i = 0; i < 4; ++i) {
        from_double(v[i], e_min, p);
        from_double(v[4 + (i % 2)], e_min, q);
        add(p, q, true, d[i]);
    }
    multiply(d[0], d[3], p);
    multiply(d[1], d[2], q);
    add(p, q, true, det);
    return det.sign();
}

}  // namespace predicates_detail

/// Orientation of d relative to the plane through a, b, c: +1 if d lies on the side that
/// (b−a)×(c−a) points to, −1 on the other side, 0 if the four points are coplanar. Equivalently
/// the sign of det[b−a; c−a; d−a], six times the signed volume of the tetrahedron (a, b, c, d).
/// Example: a, b, c = (0,0,0), (1,0,0), (0,1,0) and d = (0,0,1) give +1. (Shewchuk's orient3d
/// has the opposite sign convention.) Exact for all finite inputs; host only.
inline int orient3d(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c, const Vec3<double>& d) {
    using namespace predicates_detail;
    const bool window = in_window(a.x) && in_window(a.y) && in_window(a.z) && in_window(b.x) && in_window(b.y) &&
                        in_window(b.z) && in_window(c.x) && in_window(c.y) && in_window(c.z) && in_window(d.x) &&
                        in_window(d.y) && in_window(d.z);
    if (!window) return orient3d_bigint(a, b, c, d);
    // Tier 1. Rows u = b−a, v = c−a, w = d−a; det = u.x·(v.y·w.z − v.z·w.y) + v.x·(w.y·u.z − w.z·u.y)
    // + w.x·(u.y·v.z − u.z·v.y). The permanent reuses the rounded products, as the analysis assumes.
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
    const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
    const double wx = d.x - a.x, wy = d.y - a.y, wz = d.z - a.z;
    const double p0 = vy * wz, q0 = vz * wy;
    const double p1 = wy * uz, q1 = wz * uy;
    const double p2 = uy * vz, q2 = uz * vy;
    const double det = ux * (p0 - q0) + vx * (p1 - q1) + wx * (p2 - q2);
    const double permanent = std::fabs(ux) * (std::fabs(p0) + std::fabs(q0)) +
                             std::fabs(vx) * (std::fabs(p1) + std::fabs(q1)) +
                             std::fabs(wx) * (std::fabs(p2) + std::fabs(q2));
    const double bound = kOrient3dBound * permanent;
    if (det > bound || -det > bound) return sign_of(det);
    // Every computed product is zero only if a factor is (no underflow in the window), and a
    // computed difference is zero only if the coordinates are equal: every exact term is zero.
    if (permanent == 0.0) return 0;
    return orient3d_expansion(a, b, c, d);  // tier 2
}

/// Orientation of the triangle (a, b, c) in the plane: +1 if counter-clockwise (c to the left of
/// the directed line a→b), −1 if clockwise, 0 if collinear. The sign of (a−c)×(b−c), which equals
/// that of (b−a)×(c−a). Exact for all finite inputs; host only.
inline int orient2d(const Vec2<double>& a, const Vec2<double>& b, const Vec2<double>& c) {
    using namespace predicates_detail;
    const bool window =
        in_window(a.x) && in_window(a.y) && in_window(b.x) && in_window(b.y) && in_window(c.x) && in_window(c.y);
    if (!window) return orient2d_bigint(a, b, c);
    const double acx = a.x - c.x, acy = a.y - c.y, bcx = b.x - c.x, bcy = b.y - c.y;
    const double left = acx * bcy, right = acy * bcx;
    const double det = left - right;
    const double permanent = std::fabs(left) + std::fabs(right);
    const double bound = kOrient2dBound * permanent;
    if (det > bound || -det > bound) return sign_of(det);
    if (permanent == 0.0) return 0;
    return orient2d_expansion(a, b, c);
}

}  // namespace weft::physics
