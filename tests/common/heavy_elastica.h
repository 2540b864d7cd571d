#pragma once
// Euler's heavy elastica, solved independently of the simulator: the exact large-deflection sag of an
// inextensible strip clamped horizontally at s = 0 under its own weight. With θ(s) the angle below
// the horizontal, w the weight per length and EI the bending stiffness (a plate's D times the strip's
// width), the moment balance is
//     EI·θ''(s) = −w·(L − s)·cos θ(s),   θ(0) = 0,   θ'(L) = 0,
// and the tip deflection is δ = ∫₀ᴸ sin θ ds. Solved by shooting on θ'(0) with RK4 (the cantilever
// test and the bending convergence benchmark share it).

#include <array>
#include <cmath>
#include <utility>

namespace weft::test {

/// Integrates θ'' = −q (L − s) cos θ from s = 0 with θ(0) = 0, θ'(0) = κ0 (q = w/EI, 1/m³): returns
/// θ'(L) and δ.
inline std::pair<double, double> elastica_shoot(double q, double L, double kappa0, int steps) {
    const double ds = L / steps;
    double s = 0.0, theta = 0.0, kappa = kappa0, y = 0.0;
    auto f = [&](double ss, double th, double k) { return std::array<double, 3>{k, -q * (L - ss) * std::cos(th), std::sin(th)}; };
    for (int i = 0; i < steps; ++i) {
        const auto k1 = f(s, theta, kappa);
        const auto k2 = f(s + ds / 2, theta + ds / 2 * k1[0], kappa + ds / 2 * k1[1]);
        const auto k3 = f(s + ds / 2, theta + ds / 2 * k2[0], kappa + ds / 2 * k2[1]);
        const auto k4 = f(s + ds, theta + ds * k3[0], kappa + ds * k3[1]);
        theta += ds / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]);
        kappa += ds / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]);
        y += ds / 6 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2]);
        s += ds;
    }
    return {kappa, y};
}

/// The tip deflection (m) of a strip of length `L` (m) under the load q = w/EI (1/m³).
inline double heavy_elastica_deflection(double q, double L) {
    // θ'(L) is monotone in κ0 over [0, qL²/2] (the linear-beam root curvature bounds it): bisect.
    double lo = 0.0, hi = q * L * L / 2.0 * 1.0001;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (elastica_shoot(q, L, mid, 4000).first > 0.0 ? hi : lo) = mid;
    }
    return elastica_shoot(q, L, 0.5 * (lo + hi), 4000).second;
}

}  // namespace weft::test
