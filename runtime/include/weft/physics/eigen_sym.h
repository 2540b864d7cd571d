#pragma once
/// @file
/// Symmetric eigendecomposition of small dense matrices (N ≤ 12) by the cyclic Jacobi method, and
/// the projection of an element Hessian onto the positive semi-definite cone.
///
/// Why Jacobi: it needs no workspace beyond the matrix and its eigenvectors, has no data-dependent
/// recursion, is accurate to a few ulps in every eigenvalue (Demmel & Veselić 1992), and runs the
/// same code path on host and device. For the 9×9 membrane and 12×12 hinge Hessians it converges in
/// 5–8 sweeps. Golub & Van Loan, Matrix Computations (4th ed.), §8.5, the cyclic Jacobi algorithm.

#include <cmath>

#include "weft/math/host_device.h"
#include "weft/physics/scalar.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Eigendecomposition A = V·diag(λ)·Vᵀ of a symmetric N×N matrix, N ≤ 12.
/// @param a     the matrix (only its values are read as symmetric); overwritten: on return it is
///              (numerically) diagonal.
/// @param eval  receives the N eigenvalues (unsorted, in the order of the columns of `evec`).
/// @param evec  receives the orthonormal eigenvectors as columns: evec[i][k] is component i of
///              eigenvector k.
/// @return the number of sweeps used (a sweep visits every off-diagonal pair once).
template <int N, typename T>
WEFT_HD inline int eigen_sym(T a[N][N], T eval[N], T evec[N][N], int max_sweeps = 30) {
    using std::fabs;
    using std::sqrt;
    static_assert(N >= 1 && N <= 12, "eigen_sym is meant for small element matrices");
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) evec[i][j] = i == j ? T(1) : T(0);
    // Symmetrise first: callers pass Hessians assembled in floating point that are symmetric only
    // up to rounding; Jacobi assumes exact symmetry.
    T total = T(0);
    for (int i = 0; i < N; ++i)
        for (int j = i + 1; j < N; ++j) {
            const T s = T(0.5) * (a[i][j] + a[j][i]);
            a[i][j] = s;
            a[j][i] = s;
        }
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) total += a[i][j] * a[i][j];
    // Stop when the off-diagonal mass is below (ε·‖A‖_F)²: by Weyl's inequality the diagonal then
    // holds every eigenvalue to within ‖off(A)‖₂ ≤ ‖off(A)‖_F ≤ ε‖A‖_F.
    const T tol = sqr_(ScalarTraits<T>::epsilon) * total;
    int sweep = 0;
    for (; sweep < max_sweeps; ++sweep) {
        T off = T(0);
        for (int i = 0; i < N; ++i)
            for (int j = i + 1; j < N; ++j) off += a[i][j] * a[i][j];
        if (!(off > tol)) break;  // also stops on NaN instead of spinning
        for (int p = 0; p < N - 1; ++p) {
            for (int q = p + 1; q < N; ++q) {
                const T apq = a[p][q];
                if (apq == T(0)) continue;
                // Rotation angle that annihilates a_pq (Golub & Van Loan 4th ed., Alg. 8.5.1):
                // t = tan φ is the smaller root of t² + 2τt − 1 = 0, for stability.
                const T tau = (a[q][q] - a[p][p]) / (T(2) * apq);
                const T t = sign_(tau) / (fabs(tau) + sqrt(T(1) + tau * tau));
                const T c = T(1) / sqrt(T(1) + t * t);
                const T s = t * c;
                for (int k = 0; k < N; ++k) {  // A ← A·J (columns p, q)
                    const T akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < N; ++k) {  // A ← Jᵀ·A (rows p, q)
                    const T apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                a[p][q] = T(0);
                a[q][p] = T(0);
                for (int k = 0; k < N; ++k) {  // V ← V·J
                    const T vkp = evec[k][p], vkq = evec[k][q];
                    evec[k][p] = c * vkp - s * vkq;
                    evec[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    for (int i = 0; i < N; ++i) eval[i] = a[i][i];
    return sweep;
}

/// Projects a symmetric N×N matrix onto the positive semi-definite cone in place: negative
/// eigenvalues are clamped to zero (the nearest PSD matrix in the Frobenius norm; Higham 1988).
/// This is what makes the Newton system SPD so that CG converges (Teran et al. 2005 use the same
/// per-element clamp).
/// @return true if any eigenvalue was clamped (the matrix changed beyond symmetrisation).
template <int N, typename T>
WEFT_HD inline bool project_psd(T a[N][N]) {
    T d[N][N];
    T lambda[N];
    T v[N][N];
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) d[i][j] = a[i][j];
    eigen_sym<N>(d, lambda, v);
    bool clamped = false;
    for (int k = 0; k < N; ++k)
        if (lambda[k] < T(0)) {
            lambda[k] = T(0);
            clamped = true;
        }
    if (!clamped) {  // already PSD: only symmetrise, keep the input bits otherwise
        for (int i = 0; i < N; ++i)
            for (int j = i + 1; j < N; ++j) {
                const T s = T(0.5) * (a[i][j] + a[j][i]);
                a[i][j] = s;
                a[j][i] = s;
            }
        return false;
    }
    for (int i = 0; i < N; ++i)
        for (int j = i; j < N; ++j) {
            T s = T(0);
            for (int k = 0; k < N; ++k) s += v[i][k] * lambda[k] * v[j][k];
            a[i][j] = s;
            a[j][i] = s;
        }
    return true;
}

/// Copies n×n blocks of 3×3 into a dense 3n×3n array: a[3i+r][3j+c] = blocks[i][j].m[r][c].
template <int n, typename T>
WEFT_HD inline void pack_blocks(const Mat3<T> blocks[n][n], T a[3 * n][3 * n]) {
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) a[3 * i + r][3 * j + c] = blocks[i][j].m[r][c];
}

/// Inverse of `pack_blocks`: blocks[i][j].m[r][c] = a[3i+r][3j+c].
template <int n, typename T>
WEFT_HD inline void unpack_blocks(const T a[3 * n][3 * n], Mat3<T> blocks[n][n]) {
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) blocks[i][j].m[r][c] = a[3 * i + r][3 * j + c];
}

/// Projects an element Hessian stored as n×n 3×3 blocks onto the PSD cone (see `project_psd`).
template <int n, typename T>
WEFT_HD inline bool project_psd_blocks(Mat3<T> blocks[n][n]) {
    T a[3 * n][3 * n];
    pack_blocks<n>(blocks, a);
    const bool clamped = project_psd<3 * n>(a);
    unpack_blocks<n>(a, blocks);
    return clamped;
}

}  // namespace weft::physics
