#pragma once
/// @file
/// Small fixed-size vectors and matrices: `Vec3<T>`, `Vec2<T>`, `Mat3<T>` (row-major 3×3),
/// `Mat2<T>`. The game API's `Vec3d` is `Vec3<double>`; the physics kernels use them in float and
/// double. Header-only, host and device, templated on the scalar. Operations are written out by hand so that the CPU and CUDA backends evaluate
/// exactly the same expression tree (with -ffp-contract=off on the host).

#include <cmath>

#include "weft/math/host_device.h"

namespace weft::math {

template <typename T>
struct Vec2 {
    T x{}, y{};
    WEFT_HD constexpr T& operator[](int i) { return i == 0 ? x : y; }
    WEFT_HD constexpr T operator[](int i) const { return i == 0 ? x : y; }
};

template <typename T>
struct Vec3 {
    T x{}, y{}, z{};
    WEFT_HD constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    WEFT_HD constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    template <typename U>
    WEFT_HD constexpr Vec3<U> cast() const {
        return {static_cast<U>(x), static_cast<U>(y), static_cast<U>(z)};
    }
};

// ---- Vec3 arithmetic ---------------------------------------------------------------------------
template <typename T> WEFT_HD constexpr Vec3<T> operator+(Vec3<T> a, Vec3<T> b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <typename T> WEFT_HD constexpr Vec3<T> operator-(Vec3<T> a, Vec3<T> b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <typename T> WEFT_HD constexpr Vec3<T> operator-(Vec3<T> a) { return {-a.x, -a.y, -a.z}; }
template <typename T> WEFT_HD constexpr Vec3<T> operator*(T s, Vec3<T> a) { return {s * a.x, s * a.y, s * a.z}; }
template <typename T> WEFT_HD constexpr Vec3<T> operator*(Vec3<T> a, T s) { return {s * a.x, s * a.y, s * a.z}; }
template <typename T> WEFT_HD constexpr Vec3<T> operator/(Vec3<T> a, T s) { return {a.x / s, a.y / s, a.z / s}; }
template <typename T> WEFT_HD constexpr Vec3<T>& operator+=(Vec3<T>& a, Vec3<T> b) { a.x += b.x; a.y += b.y; a.z += b.z; return a; }
template <typename T> WEFT_HD constexpr Vec3<T>& operator-=(Vec3<T>& a, Vec3<T> b) { a.x -= b.x; a.y -= b.y; a.z -= b.z; return a; }
template <typename T> WEFT_HD constexpr Vec3<T>& operator*=(Vec3<T>& a, T s) { a.x *= s; a.y *= s; a.z *= s; return a; }
template <typename T> WEFT_HD constexpr bool operator==(Vec3<T> a, Vec3<T> b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

template <typename T> WEFT_HD constexpr T dot(Vec3<T> a, Vec3<T> b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <typename T> WEFT_HD constexpr Vec3<T> cross(Vec3<T> a, Vec3<T> b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T> WEFT_HD constexpr T length_squared(Vec3<T> a) { return dot(a, a); }
template <typename T> WEFT_HD inline T length(Vec3<T> a) { using std::sqrt; return sqrt(dot(a, a)); }
/// Unit vector along `a`; returns zero for a zero vector instead of NaN.
template <typename T> WEFT_HD inline Vec3<T> normalized(Vec3<T> a) {
    const T l = length(a);
    return l > T(0) ? a / l : Vec3<T>{};
}
template <typename T> WEFT_HD inline bool is_finite(Vec3<T> a) {
    using std::isfinite;
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}

// ---- Vec2 arithmetic ---------------------------------------------------------------------------
template <typename T> WEFT_HD constexpr Vec2<T> operator+(Vec2<T> a, Vec2<T> b) { return {a.x + b.x, a.y + b.y}; }
template <typename T> WEFT_HD constexpr Vec2<T> operator-(Vec2<T> a, Vec2<T> b) { return {a.x - b.x, a.y - b.y}; }
template <typename T> WEFT_HD constexpr Vec2<T> operator*(T s, Vec2<T> a) { return {s * a.x, s * a.y}; }
template <typename T> WEFT_HD constexpr T dot(Vec2<T> a, Vec2<T> b) { return a.x * b.x + a.y * b.y; }

// ---- Mat3 (row-major) ----------------------------------------------------------------------------
template <typename T>
struct Mat3 {
    T m[3][3]{};  ///< m[row][col]
    WEFT_HD static constexpr Mat3 zero() { return Mat3{}; }
    WEFT_HD static constexpr Mat3 identity() {
        Mat3 r{};
        r.m[0][0] = r.m[1][1] = r.m[2][2] = T(1);
        return r;
    }
    WEFT_HD static constexpr Mat3 diagonal(T d) {
        Mat3 r{};
        r.m[0][0] = r.m[1][1] = r.m[2][2] = d;
        return r;
    }
    /// a bᵀ
    WEFT_HD static constexpr Mat3 outer(Vec3<T> a, Vec3<T> b) {
        Mat3 r{};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r.m[i][j] = a[i] * b[j];
        return r;
    }
    WEFT_HD constexpr T& operator()(int r, int c) { return m[r][c]; }
    WEFT_HD constexpr T operator()(int r, int c) const { return m[r][c]; }
    WEFT_HD constexpr Vec3<T> row(int r) const { return {m[r][0], m[r][1], m[r][2]}; }
    WEFT_HD constexpr Vec3<T> col(int c) const { return {m[0][c], m[1][c], m[2][c]}; }
    template <typename U>
    WEFT_HD constexpr Mat3<U> cast() const {
        Mat3<U> r{};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r.m[i][j] = static_cast<U>(m[i][j]);
        return r;
    }
};

template <typename T> WEFT_HD constexpr Mat3<T> operator+(const Mat3<T>& a, const Mat3<T>& b) {
    Mat3<T> r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][j] + b.m[i][j];
    return r;
}
template <typename T> WEFT_HD constexpr Mat3<T> operator-(const Mat3<T>& a, const Mat3<T>& b) {
    Mat3<T> r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][j] - b.m[i][j];
    return r;
}
template <typename T> WEFT_HD constexpr Mat3<T> operator*(T s, const Mat3<T>& a) {
    Mat3<T> r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = s * a.m[i][j];
    return r;
}
template <typename T> WEFT_HD constexpr Mat3<T>& operator+=(Mat3<T>& a, const Mat3<T>& b) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) a.m[i][j] += b.m[i][j];
    return a;
}
template <typename T> WEFT_HD constexpr Vec3<T> operator*(const Mat3<T>& a, Vec3<T> v) {
    return {a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z,
            a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
            a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z};
}
template <typename T> WEFT_HD constexpr Mat3<T> operator*(const Mat3<T>& a, const Mat3<T>& b) {
    Mat3<T> r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
    return r;
}
template <typename T> WEFT_HD constexpr Mat3<T> transpose(const Mat3<T>& a) {
    Mat3<T> r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[j][i];
    return r;
}
template <typename T> WEFT_HD constexpr T determinant(const Mat3<T>& a) {
    return a.m[0][0] * (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) -
           a.m[0][1] * (a.m[1][0] * a.m[2][2] - a.m[1][2] * a.m[2][0]) +
           a.m[0][2] * (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]);
}
/// Inverse by the adjugate. The caller guarantees |det| is not tiny (block-Jacobi diagonal blocks
/// are SPD by construction: mass plus projected stiffness).
template <typename T> WEFT_HD constexpr Mat3<T> inverse(const Mat3<T>& a) {
    Mat3<T> r{};
    r.m[0][0] = a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1];
    r.m[0][1] = a.m[0][2] * a.m[2][1] - a.m[0][1] * a.m[2][2];
    r.m[0][2] = a.m[0][1] * a.m[1][2] - a.m[0][2] * a.m[1][1];
    r.m[1][0] = a.m[1][2] * a.m[2][0] - a.m[1][0] * a.m[2][2];
    r.m[1][1] = a.m[0][0] * a.m[2][2] - a.m[0][2] * a.m[2][0];
    r.m[1][2] = a.m[0][2] * a.m[1][0] - a.m[0][0] * a.m[1][2];
    r.m[2][0] = a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0];
    r.m[2][1] = a.m[0][1] * a.m[2][0] - a.m[0][0] * a.m[2][1];
    r.m[2][2] = a.m[0][0] * a.m[1][1] - a.m[0][1] * a.m[1][0];
    const T det = a.m[0][0] * r.m[0][0] + a.m[0][1] * r.m[1][0] + a.m[0][2] * r.m[2][0];
    return (T(1) / det) * r;
}

// ---- Mat2 (row-major) ----------------------------------------------------------------------------
template <typename T>
struct Mat2 {
    T m[2][2]{};
    WEFT_HD constexpr T& operator()(int r, int c) { return m[r][c]; }
    WEFT_HD constexpr T operator()(int r, int c) const { return m[r][c]; }
};
template <typename T> WEFT_HD constexpr T determinant(const Mat2<T>& a) { return a.m[0][0] * a.m[1][1] - a.m[0][1] * a.m[1][0]; }
template <typename T> WEFT_HD constexpr Mat2<T> inverse(const Mat2<T>& a) {
    const T inv = T(1) / determinant(a);
    Mat2<T> r{};
    r.m[0][0] = a.m[1][1] * inv;
    r.m[0][1] = -a.m[0][1] * inv;
    r.m[1][0] = -a.m[1][0] * inv;
    r.m[1][1] = a.m[0][0] * inv;
    return r;
}

}  // namespace weft::math
