#pragma once
/// @file
/// Which second derivative an element evaluation computes. Every element (membrane, bending,
/// contact) takes a `HessianKind` so that the solver chooses the speed/accuracy trade-off per scene.

namespace weft::physics {

/// Which Hessian an element evaluation returns along with its energy and gradient.
enum class HessianKind : unsigned char {
    None,       ///< energy and gradient only; Hessian outputs are left untouched
    Exact,      ///< the true Hessian ∂²E/∂x² (may be indefinite: for tests and Newton with line search)
    Fast,       ///< a cheap positive semi-definite approximation, documented per element
    Projected,  ///< the exact Hessian with its negative eigenvalues clamped to zero (PSD, slowest)
};

}  // namespace weft::physics
